// PREFER_FAST_TRACE's spatial splits through the API: a bottom level whose triangles were cut into fragments
// (docs/FORMAT.md, "Fragments") shows a ray every triangle it meets exactly once, as the brute-force oracle lists
// them: every candidate of a query that confirms none (non-opaque geometry, and opaque geometry under the NoOpaque
// ray flag), with and without NO_DUPLICATE_ANY_HIT_INVOCATION; closest and any hits of queries and vkasTraceRays
// match the oracle as for any other build; a serialized structure with fragments loads and traces the same, and so
// does the committed blob tests/data/serialized_fragments_blas.bin (written by DISABLED_generate_golden_blob), which
// every later vkas must keep loading.
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <tuple>

#include "meshes.hpp"
#include "vkas_test.hpp"

namespace vt {
namespace {

constexpr uint32_t kRayNoOpaque = 0x2;  // SPIR-V RayFlagsNoOpaqueKHR

class spatial_splits : public VkasTest {
protected:
    // Header fields at their documented offsets (docs/FORMAT.md, "Header"): the records stored and the fragments.
    static uint32_t header32(const AccelStruct* as, size_t offset) { return as->header32(offset); }
    static uint32_t primitiveCount(const AccelStruct* as) { return header32(as, 60); }
    static uint32_t recordCount(const AccelStruct* as) { return header32(as, 64); }
    static uint32_t fragmentCount(const AccelStruct* as) { return header32(as, 128); }

    // Large, overlapping triangles (which spatial splits cut) and a closed surface of shared edges (where a cut
    // fragment borders a neighbour's).
    std::vector<std::unique_ptr<GeometryData>> geometries(VkGeometryFlagsKHR flags) {
        std::vector<std::unique_ptr<GeometryData>> g;
        g.push_back(makeGeometry(triangleSoup(700, rng, 0.9f), VK_INDEX_TYPE_NONE_KHR, flags));
        g.push_back(makeGeometry(torusKnot(96, 12), VK_INDEX_TYPE_UINT32, flags));
        return g;
    }

    AccelStruct* splitScene(const std::vector<std::unique_ptr<GeometryData>>& g, AccelStruct** blasOut = nullptr) {
        BuildOptions opt;
        opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
        AccelStruct* blas = buildBlas(std::vector<const GeometryData*>{g[0].get(), g[1].get()}, opt);
        EXPECT_GT(fragmentCount(blas), 0u) << "no triangle was cut: the test would prove nothing";
        EXPECT_GT(recordCount(blas), primitiveCount(blas));
        std::cout << recordCount(blas) << " records for " << primitiveCount(blas) << " triangles, "
                  << fragmentCount(blas) << " fragments" << std::endl;
        if (blasOut) *blasOut = blas;
        return buildSingleInstanceTlas(blas);
    }

    // A blob of vkCopyAccelerationStructureToMemoryKHR, and the structure vkCopyMemoryToAccelerationStructureKHR
    // makes of it (seen by the oracle as `like`'s geometry).
    std::vector<uint8_t> serialize(const AccelStruct* src) {
        uint64_t n = 0;
        VkAccelerationStructureKHR h = src->handle;
        EXPECT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(
                      device, 1, &h, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR, sizeof n, &n, sizeof n),
                  VK_SUCCESS);
        std::vector<uint8_t> blob(n);
        VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
        info.src = src->handle;
        info.dst.hostAddress = blob.data();
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        EXPECT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &info), VK_SUCCESS);
        return blob;
    }
    AccelStruct* deserialize(const std::vector<uint8_t>& blob, const AccelStruct* like) {
        uint64_t deserializedSize;
        std::memcpy(&deserializedSize, blob.data() + 40, 8);
        AccelStruct* dst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, deserializedSize, {});
        VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src.hostAddress = blob.data();
        info.dst = dst->handle;
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
        EXPECT_EQ(vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &info), VK_SUCCESS);
        dst->blas = like->blas;
        blasRegistry[dst->reference()] = dst->blas;
        return dst;
    }

    // The golden blob's geometry: 300 large overlapping triangles from a fixed LCG and exact float arithmetic, so
    // that every build of the test makes the same vertices.
    static Mesh goldenMesh() {
        Mesh m;
        uint64_t state = 0x5eed'f4a9'7e11'0001ull;
        auto next = [&] {  // a multiple of 1/256 in [-1, 1)
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return float(int32_t(state >> 55) - 256) / 256.0f;
        };
        for (int i = 0; i < 300; ++i) {
            const float c[3] = {4 * next(), 4 * next(), 4 * next()};
            for (int k = 0; k < 3; ++k) {
                m.positions.push_back({c[0] + 2 * next(), c[1] + 2 * next(), c[2] + 2 * next()});
                m.indices.push_back(uint32_t(m.positions.size() - 1));
            }
        }
        return m;
    }

    std::vector<oracle::Ray> rays(const AccelStruct* tlas, size_t n) {
        auto r = randomRays(*tlas->scene, n);
        const auto t = targetedRays(*tlas->scene, n);
        r.insert(r.end(), t.begin(), t.end());
        return r;
    }

    // Every candidate of a query that confirms none against the oracle's list: each at most once, each listed, each
    // required one present. Returns the candidates seen.
    size_t checkCandidateSets(const AccelStruct* tlas, const std::vector<oracle::Ray>& rs, uint32_t rayFlags) {
        size_t seen = 0;
        for (size_t i = 0; i < rs.size(); ++i) {
            const oracle::Ray& ray = rs[i];
            const oracle::Result expected = oracle::trace(*tlas->scene, ray, rayFlags, 0xFF);
            const QueryTrace q = query(tlas->handle, ray, rayFlags, 0xFF, Confirm::None);
            EXPECT_TRUE(q.problems.empty()) << "ray " << i << ": " << q.problems;
            std::set<std::tuple<int32_t, int32_t, int32_t>> shown;
            for (const Hit& h : q.candidates) {
                EXPECT_TRUE(shown.insert({h.instanceId, h.geometryIndex, h.primitiveIndex}).second)
                    << "ray " << i << " was shown primitive " << h.primitiveIndex << " of geometry " << h.geometryIndex
                    << " twice";
                const oracle::Candidate* c = expected.find(h.instanceId, h.geometryIndex, h.primitiveIndex);
                EXPECT_NE(c, nullptr) << "ray " << i << ": " << h.str() << " is no candidate";
                if (c) {
                    EXPECT_NEAR(h.t, c->t, c->tTolerance) << "ray " << i << ": " << h.str();
                }
            }
            for (const oracle::Candidate& c : expected.candidates) {
                if (c.optional) continue;
                EXPECT_TRUE(shown.count({c.instanceId, c.geometryIndex, c.primitiveIndex}))
                    << "ray " << i << " missed primitive " << c.primitiveIndex << " of geometry " << c.geometryIndex;
            }
            seen += q.candidates.size();
        }
        return seen;
    }
};

TEST_F(spatial_splits, non_opaque_triangles_are_each_shown_once) {
    const auto g = geometries(0);
    AccelStruct* tlas = splitScene(g);
    const auto rs = rays(tlas, 400);
    EXPECT_GT(checkCandidateSets(tlas, rs, 0), rs.size());
}

TEST_F(spatial_splits, no_duplicate_any_hit_geometry_is_shown_once) {
    const auto g = geometries(VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR);
    AccelStruct* tlas = splitScene(g);
    const auto rs = rays(tlas, 300);
    EXPECT_GT(checkCandidateSets(tlas, rs, 0), rs.size());
}

TEST_F(spatial_splits, opaque_triangles_under_no_opaque_rays_are_each_shown_once) {
    const auto g = geometries(VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* tlas = splitScene(g);
    const auto rs = rays(tlas, 300);
    EXPECT_GT(checkCandidateSets(tlas, rs, kRayNoOpaque), rs.size());
}

TEST_F(spatial_splits, closest_and_any_hits_match_the_oracle) {
    for (const VkGeometryFlagsKHR flags : {VkGeometryFlagsKHR(VK_GEOMETRY_OPAQUE_BIT_KHR), VkGeometryFlagsKHR(0)}) {
        const auto g = geometries(flags);
        AccelStruct* tlas = splitScene(g);
        const auto rs = rays(tlas, 400);
        EXPECT_GT(checkRays(tlas, rs), rs.size() / 4);
    }
}

TEST_F(spatial_splits, the_same_inputs_build_the_same_bytes_within_the_size_query) {
    const auto g = geometries(VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = nullptr;
    AccelStruct* tlas = splitScene(g, &blas);
    AccelStruct* twin = nullptr;
    splitScene(g, &twin);
    uint64_t used;
    std::memcpy(&used, blas->data() + 16, 8);
    EXPECT_LE(used, blas->sizes.accelerationStructureSize);
    EXPECT_EQ(std::memcmp(blas->data(), twin->data(), size_t(used)), 0);
    (void)tlas;
}

TEST_F(spatial_splits, a_serialized_structure_keeps_its_fragments_and_candidates) {
    const auto g = geometries(0);
    AccelStruct* blas = nullptr;
    splitScene(g, &blas);
    AccelStruct* copy = deserialize(serialize(blas), blas);
    uint64_t used;
    std::memcpy(&used, blas->data() + 16, 8);
    EXPECT_EQ(std::memcmp(blas->data(), copy->data(), size_t(used)), 0);
    AccelStruct* tlas = buildSingleInstanceTlas(copy);
    const auto rs = rays(tlas, 200);
    EXPECT_GT(checkCandidateSets(tlas, rs, 0), rs.size());
}

#ifdef VKAS_TEST_DATA_DIR
// Run with --gtest_also_run_disabled_tests and VKAS_WRITE_TEST_DATA=<dir> to write the golden blob.
TEST_F(spatial_splits, DISABLED_generate_golden_blob) {
    const char* dir = std::getenv("VKAS_WRITE_TEST_DATA");
    ASSERT_NE(dir, nullptr) << "set VKAS_WRITE_TEST_DATA to the output directory";
    auto g = makeGeometry(goldenMesh(), VK_INDEX_TYPE_NONE_KHR, 0);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
    AccelStruct* blas = buildBlas(*g, opt);
    ASSERT_GT(fragmentCount(blas), 0u);
    const std::vector<uint8_t> blob = serialize(blas);
    std::ofstream(std::string(dir) + "/serialized_fragments_blas.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(blob.data()), std::streamsize(blob.size()));
}

// The blob vkas wrote when fragments were introduced (f99d842) loads, keeps its fragments, and shows every ray each
// triangle it meets once, as the oracle over the same (regenerated) geometry says.
TEST_F(spatial_splits, the_golden_blob_with_fragments_loads_and_traces) {
    std::ifstream f(std::string(VKAS_TEST_DATA_DIR) + "/serialized_fragments_blas.bin", std::ios::binary);
    ASSERT_TRUE(f.good());
    const std::vector<uint8_t> blob((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    VkAccelerationStructureVersionInfoKHR vi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
    vi.pVersionData = blob.data();
    VkAccelerationStructureCompatibilityKHR c;
    vk.vkGetDeviceAccelerationStructureCompatibilityKHR(device, &vi, &c);
    ASSERT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR);
    auto g = makeGeometry(goldenMesh(), VK_INDEX_TYPE_NONE_KHR, 0);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
    AccelStruct* fresh = buildBlas(*g, opt);  // for the oracle's view of the geometry
    AccelStruct* loaded = deserialize(blob, fresh);
    EXPECT_GT(fragmentCount(loaded), 0u);
    EXPECT_EQ(primitiveCount(loaded), 300u);
    AccelStruct* tlas = buildSingleInstanceTlas(loaded);
    const auto rs = rays(tlas, 300);
    EXPECT_GT(checkCandidateSets(tlas, rs, 0), rs.size());
}
#endif

}  // namespace
}  // namespace vt
