// CTS `build`, fast_build cases: structures built with VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR use
// the Morton-code builder (src/engine/morton_builder.cpp). Every structure is checked against the brute-force oracle
// and walked byte by byte for the invariants docs/FORMAT.md promises: every node reached once, 8 children or only
// leaf children, no more nodes than the size query reserves, depth at most 64, leaves of 1 to 4 records (1
// instance) that tile the record array, and child boxes that hold what lies below them.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "meshes.hpp"

using namespace vt;

namespace {

constexpr VkBuildAccelerationStructureFlagsKHR kFastBuild = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;

template <class T>
T load(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

struct Box {
    float lo[3], hi[3];
};

// Walks the tree of a built structure; fails the test on any broken invariant. Returns the depth (internal levels).
class TreeCheck {
public:
    TreeCheck(const AccelStruct* as, uint32_t maxLeaf) : b_(as->data()), maxLeaf_(maxLeaf) {
        primitives_ = load<uint32_t>(b_ + 60);
        records_ = load<uint32_t>(b_ + 64);
        nodes_ = load<uint32_t>(b_ + 68);
        nodeOffset_ = load<uint64_t>(b_ + 80);
        recordOffset_ = load<uint64_t>(b_ + 88);
        topLevel_ = load<uint32_t>(b_ + 8) == 0;
        if (!topLevel_) records48_ = vt::triangleRecordsOf(b_);
    }

    void run() {
        // nodes(N) of docs/FORMAT.md, for the N primitives given to the build.
        const uint64_t n = primitives_;
        const uint64_t bound = n <= maxLeaf_ ? 0 : n / (maxLeaf_ + 1) + (n - 1) / 7 + 1;
        EXPECT_LE(nodes_, bound) << "more nodes than the size query reserves";
        const uint64_t root = load<uint64_t>(b_ + 24);
        if (records_ == 0) {
            EXPECT_EQ(root, 0u);
            return;
        }
        visited_.assign(nodes_, 0);
        covered_.assign(records_, 0);
        Box rootBox;
        for (int a = 0; a < 3; ++a) rootBox.lo[a] = load<float>(b_ + 32 + 4 * a), rootBox.hi[a] = load<float>(b_ + 44 + 4 * a);
        visit(root, rootBox, 0);
        for (uint32_t i = 0; i < nodes_; ++i) EXPECT_EQ(visited_[i], 1) << "node " << i << " not reached exactly once";
        for (uint32_t i = 0; i < records_; ++i) EXPECT_EQ(covered_[i], 1) << "record " << i << " not in exactly one leaf";
        EXPECT_LE(maxDepth_, 64u);
    }
    uint32_t depth() const { return maxDepth_; }
    uint32_t nodeCount() const { return nodes_; }

private:
    static bool inside(const Box& inner, const Box& outer) {
        for (int a = 0; a < 3; ++a)
            if (!(inner.lo[a] >= outer.lo[a] && inner.hi[a] <= outer.hi[a])) return false;
        return true;
    }
    // The box of a record: triangle vertices; top level: none checked here (instance boxes are not stored).
    bool recordBox(uint64_t r, Box& box) const {
        if (topLevel_) return false;
        const uint8_t* rec = records48_.data() + r * 48;
        for (int a = 0; a < 3; ++a) box.lo[a] = INFINITY, box.hi[a] = -INFINITY;
        for (int v = 0; v < 3; ++v)
            for (int a = 0; a < 3; ++a) {
                const float x = load<float>(rec + 12 * v + 4 * a);
                box.lo[a] = std::min(box.lo[a], x), box.hi[a] = std::max(box.hi[a], x);
            }
        return true;
    }
    void visit(uint64_t ref, const Box& box, uint32_t depth) {
        const uint64_t kind = ref >> 62;
        if (kind == 2) {
            const uint64_t first = ref & 0xFF'FFFF'FFFFull;
            const uint32_t count = uint32_t(ref >> 40) & 0xFF;
            ASSERT_GE(count, 1u);
            ASSERT_LE(count, maxLeaf_) << "leaf too large";
            ASSERT_LE(first + count, records_);
            for (uint64_t r = first; r < first + count; ++r) {
                covered_[r]++;
                Box rb;
                // A finite triangle lies in its leaf's box (non-finite coordinates make no promise).
                if (recordBox(r, rb) && std::isfinite(rb.lo[0] + rb.lo[1] + rb.lo[2] + rb.hi[0] + rb.hi[1] + rb.hi[2])) {
                    EXPECT_TRUE(inside(rb, box)) << "record " << r << " outside its leaf box";
                }
            }
            return;
        }
        ASSERT_EQ(kind, 1u) << "bad child reference";
        const uint32_t index = uint32_t(ref);
        ASSERT_LT(index, nodes_);
        ASSERT_EQ(visited_[index]++, 0) << "node " << index << " reached twice";
        maxDepth_ = std::max(maxDepth_, depth + 1);
        ASSERT_LE(depth + 1, 64u) << "tree deeper than the ray query stack";
        const uint8_t* node = b_ + nodeOffset_ + uint64_t(index) * 256;
        uint32_t children = 0, leaves = 0;
        for (uint32_t i = 0; i < 8; ++i) {
            const uint64_t child = load<uint64_t>(node + 192 + 8 * i);
            if (child == 0) continue;
            ++children;
            leaves += (child >> 62) == 2;
            Box cb;
            for (int a = 0; a < 3; ++a) {
                cb.lo[a] = load<float>(node + 64 * a + 4 * i);
                cb.hi[a] = load<float>(node + 64 * a + 32 + 4 * i);
            }
            const bool finite = std::isfinite(cb.lo[0] + cb.lo[1] + cb.lo[2] + cb.hi[0] + cb.hi[1] + cb.hi[2]);
            if (finite && std::isfinite(box.lo[0] + box.lo[1] + box.lo[2] + box.hi[0] + box.hi[1] + box.hi[2])) {
                EXPECT_TRUE(inside(cb, box)) << "child box outside its parent's slot box";
            }
            visit(child, cb, depth + 1);
            if (::testing::Test::HasFatalFailure()) return;
        }
        EXPECT_TRUE(children == 8 || leaves == children)
            << "node " << index << " has " << children << " children, " << leaves << " of them leaves";
    }

    const uint8_t* b_;
    uint32_t maxLeaf_;
    uint32_t primitives_ = 0, records_ = 0, nodes_ = 0;
    uint64_t nodeOffset_ = 0, recordOffset_ = 0;
    bool topLevel_ = false;
    std::vector<uint8_t> records48_;  // the triangles as 48-byte records (vt::triangleRecordsOf)
    std::vector<uint8_t> visited_;
    std::vector<uint8_t> covered_;
    uint32_t maxDepth_ = 0;
};

uint32_t checkTree(const AccelStruct* as, uint32_t maxLeaf) {
    TreeCheck check(as, maxLeaf);
    check.run();
    return check.depth();
}

std::vector<uint8_t> usedBytes(const AccelStruct* as) {
    const uint64_t used = load<uint64_t>(as->data() + 16);
    return std::vector<uint8_t>(as->data(), as->data() + used);
}

}  // namespace

class build_fast_build : public VkasTest {
protected:
    // Builds the mesh with PREFER_FAST_BUILD, checks the tree and traces random and targeted rays against the oracle.
    const AccelStruct* buildAndCheck(const Mesh& mesh, size_t rays = 200) {
        auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
        BuildOptions opt;
        opt.flags = kFastBuild;
        AccelStruct* blas = buildBlas(*geometry, opt);  // checks the canary after the structure
        checkTree(blas, 4);
        const AccelStruct* tlas = buildSingleInstanceTlas(blas);
        if (mesh.triangleCount() != 0) {
            checkRays(tlas, randomRays(*tlas->scene, rays));
            checkRays(tlas, targetedRays(*tlas->scene, rays));
        }
        return blas;
    }
};

// Random triangle soups of random sizes: every ray as the oracle says.
TEST_F(build_fast_build, random_soups) {
    for (int k = 0; k < 6 && !HasFailure(); ++k) {
        const int count = int(rng.below(20000)) + 1;
        SCOPED_TRACE(testing::Message() << count << " triangles");
        buildAndCheck(triangleSoup(count, rng, rng.uniformf(0.01f, 0.5f)));
    }
}

// Meshes with structure: a sphere, a knot, a terrain (flat: most Morton bits on two axes).
TEST_F(build_fast_build, meshes) {
    buildAndCheck(icosphere(5));
    buildAndCheck(torusKnot(300, 24));
    buildAndCheck(terrain(120, rng));
}

// Every count from 1 to 80 and around the leaf and node boundaries above: leaves of at most 4, nodes of 8 or only
// leaf children, no more nodes than the size query allows.
TEST_F(build_fast_build, primitive_counts) {
    std::vector<int> counts;
    for (int n = 1; n <= 80; ++n) counts.push_back(n);
    for (int n : {127, 128, 129, 159, 160, 161, 255, 256, 257, 1023, 1024, 1025, 4095, 4096, 4097})
        counts.push_back(n);
    for (int n : counts) {
        SCOPED_TRACE(testing::Message() << n << " triangles");
        buildAndCheck(triangleSoup(n, rng, 0.3f), 40);
        if (HasFailure()) return;
    }
}

// All triangles identical (every Morton code equal): the builder halves, the depth stays bounded, the node count
// within the size query's reserve, and a ray through the triangle hits one of them.
TEST_F(build_fast_build, duplicated_centroids) {
    for (int n : {5, 33, 1000, 70000}) {
        SCOPED_TRACE(testing::Message() << n << " identical triangles");
        Mesh mesh;
        mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        for (int i = 0; i < n; ++i) mesh.indices.insert(mesh.indices.end(), {0, 1, 2});
        const AccelStruct* blas = buildAndCheck(mesh, 50);
        EXPECT_LE(checkTree(blas, 4), 64u);
    }
    // Many triangles in few distinct places: long runs of equal codes between different ones.
    Mesh mesh;
    for (int i = 0; i < 20000; ++i) {
        const float x = float(i % 7), y = float((i / 7) % 3);
        const uint32_t base = uint32_t(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), {{x, y, 0}, {x + 0.5f, y, 0}, {x, y + 0.5f, 0.25f}});
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
    }
    buildAndCheck(mesh, 100);
}

// Infinite, NaN (outside X: such triangles stay active) and huge finite coordinates next to a valid grid: the build
// ends, fits the size query, and the grid's triangles are still hit.
TEST_F(build_fast_build, nonfinite_and_extreme_coordinates) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    constexpr float kMax = std::numeric_limits<float>::max();
    const Float3 odd[] = {{1, kInf, 1}, {-kInf, 2, 1}, {3, 2, -kInf}, {1, kNaN, 2}, {2, 1, kNaN},
                          {kMax, 1, 1}, {-kMax, 1, 1}, {1, kMax, -kMax}};
    for (int extra : {1, 6, 50, 3000}) {
        SCOPED_TRACE(testing::Message() << extra << " extreme triangles");
        Mesh mesh = grid(16, 16);
        const size_t gridTriangles = mesh.triangleCount();
        for (int i = 0; i < extra; ++i) {
            const uint32_t base = uint32_t(mesh.positions.size());
            const Float3 p = odd[rng.below(std::size(odd))];
            mesh.positions.insert(mesh.positions.end(), {p, {p[0] + 1, p[1], p[2]}, {p[0], p[1] + 1, p[2] + 1}});
            mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
        }
        auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        BuildOptions opt;
        opt.flags = kFastBuild;
        AccelStruct* blas = buildBlas(*geometry, opt);
        checkTree(blas, 4);
        const AccelStruct* tlas = buildSingleInstanceTlas(blas);
        for (int k = 0; k < 100; ++k) {
            // A vertical ray into a random grid quad, well inside one of its two triangles.
            const int i = int(rng.below(16)), j = int(rng.below(16));
            oracle::Ray ray;
            ray.origin = {float(i) + 0.7f, float(j) + 0.2f, 1.0f};
            ray.direction = {0, 0, -1};
            ray.tMin = 0;
            ray.tMax = 10;
            const Hit hit = traceClosest(tlas, ray);
            ASSERT_EQ(hit.type, uint32_t(VKAS_COMMITTED_INTERSECTION_TRIANGLE)) << describe(ray);
            EXPECT_LT(uint32_t(hit.primitiveIndex), gridTriangles) << describe(ray);
        }
    }
}

// The same input gives the same bytes, build after build (no dependence on addresses or leftover memory).
TEST_F(build_fast_build, same_input_same_bytes) {
    const Mesh mesh = triangleSoup(30000, rng, 0.1f);
    auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32);
    BuildOptions a, b;
    a.flags = b.flags = kFastBuild;
    b.memoryPoison = 0x55;
    b.scratchPoison = 0x00;
    const std::vector<uint8_t> first = usedBytes(buildBlas(*geometry, a));
    EXPECT_TRUE(first == usedBytes(buildBlas(*geometry, b)));
}

// Top level: instances of a few bottom levels, built with PREFER_FAST_BUILD (leaves of one instance).
TEST_F(build_fast_build, instances) {
    std::vector<const AccelStruct*> blases;
    std::vector<std::unique_ptr<GeometryData>> geometries;
    for (int k = 0; k < 3; ++k) {
        geometries.push_back(makeGeometry(k == 0 ? icosphere(2) : triangleSoup(300, rng, 0.3f), VK_INDEX_TYPE_UINT32,
                                          VK_GEOMETRY_OPAQUE_BIT_KHR));
        BuildOptions opt;
        opt.flags = k == 1 ? kFastBuild : 0;
        blases.push_back(buildBlas(*geometries.back(), opt));
    }
    for (int count : {1, 2, 9, 100, 3000}) {
        SCOPED_TRACE(testing::Message() << count << " instances");
        std::vector<Instance> instances(count);
        for (auto& inst : instances) {
            inst.transform = randomTransform(rng, 0.05f, 0.5f, rng.coin(0.2), 20.0f);
            inst.customIndex = rng.u32() & 0xFFFFFF;
            inst.blas = rng.coin(0.05) ? nullptr : blases[rng.below(3)];  // some inactive
        }
        BuildOptions opt;
        opt.flags = kFastBuild;
        AccelStruct* tlas = buildTlas(instances, opt);
        checkTree(tlas, 1);
        checkRays(tlas, randomRays(*tlas->scene, 300));
        checkRays(tlas, targetedRays(*tlas->scene, 300));
        if (HasFailure()) return;
    }
}
