// The lavapipe side alone, against hand-computed expectations: if these fail, the referee of the differential tests
// (or the way this side drives it) is wrong, and no comparison with vkas means anything.
#include <gtest/gtest.h>
#include <vkas/vkas_compat.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <tuple>

#include "lavapipe_side.hpp"

namespace {

using diff::Geometry;
using diff::Instance;
using diff::LavapipeSide;
using diff::Ray;
using diff::Result;
using diff::Scene;

// SPIR-V RayFlags and Vulkan flags used below.
constexpr uint32_t kRayOpaque = 0x1, kRayNoOpaque = 0x2, kRayCullBack = 0x10, kRayCullFront = 0x20;
constexpr uint32_t kCommittedNone = 0, kCommittedTriangle = 1, kCommittedGenerated = 2;
constexpr uint32_t kCandidateTriangle = 0, kCandidateAabb = 1;
constexpr float kTol = 1e-6f;  // for t and barycentrics of triangle hits, which the driver computes its own way

// Appends bytes to the scene's blob at an offset aligned to `alignment`; returns the offset.
uint64_t append(Scene& scene, const void* data, size_t size, size_t alignment = 16) {
    const size_t offset = (scene.blob.size() + alignment - 1) / alignment * alignment;
    scene.blob.resize(offset + size);
    std::memcpy(scene.blob.data() + offset, data, size);
    return offset;
}

template <typename T>
uint64_t append(Scene& scene, const std::vector<T>& values, size_t alignment = 16) {
    return append(scene, values.data(), values.size() * sizeof(T), alignment);
}

VkTransformMatrixKHR matrix(float m00, float m01, float m02, float m03, float m10, float m11, float m12, float m13,
                            float m20, float m21, float m22, float m23) {
    return {{{m00, m01, m02, m03}, {m10, m11, m12, m13}, {m20, m21, m22, m23}}};
}

VkTransformMatrixKHR translation(float x, float y, float z) { return matrix(1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z); }

// A non-indexed R32G32B32_SFLOAT geometry: 9 floats per triangle.
Geometry triangles(Scene& scene, const std::vector<float>& xyz, VkGeometryFlagsKHR flags = VK_GEOMETRY_OPAQUE_BIT_KHR) {
    Geometry g;
    g.type = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g.flags = flags;
    g.triangles.vertexOffset = append(scene, xyz);
    g.triangles.maxVertex = uint32_t(xyz.size() / 3 - 1);
    g.range.primitiveCount = uint32_t(xyz.size() / 9);
    return g;
}

Geometry aabbs(Scene& scene, const std::vector<VkAabbPositionsKHR>& boxes, VkGeometryFlagsKHR flags) {
    Geometry g;
    g.type = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.flags = flags;
    g.aabbs.dataOffset = append(scene, boxes, 8);
    g.range.primitiveCount = uint32_t(boxes.size());
    return g;
}

int addBlas(Scene& scene, std::vector<Geometry> geometries, VkBuildAccelerationStructureFlagsKHR flags = 0) {
    scene.blases.push_back({std::move(geometries), flags});
    return int(scene.blases.size() - 1);
}

Instance instance(int blas, const VkTransformMatrixKHR& transform = translation(0, 0, 0)) {
    Instance in;
    in.blas = blas;
    in.transform = transform;
    return in;
}

Ray ray(float ox, float oy, float oz, float dx, float dy, float dz, float tMin = 0.0f, float tMax = 1000.0f,
        uint32_t flags = 0, uint32_t cullMask = 0xFF, uint32_t mode = diff::kModeClosest) {
    return {{ox, oy, oz}, tMin, {dx, dy, dz}, tMax, flags, cullMask, mode, 0};
}

// A miss: committed type none, and every field the program does not define is 0.
void expectMiss(const Result& r, uint32_t candidateCount = 0) {
    EXPECT_EQ(r.committedType, kCommittedNone);
    EXPECT_EQ(r.candidateCount, candidateCount);
    Result zero;
    std::memset(&zero, 0, sizeof zero);
    zero.candidateCount = r.candidateCount;
    std::memcpy(zero.candidates, r.candidates, sizeof zero.candidates);
    EXPECT_EQ(std::memcmp(&r, &zero, sizeof r), 0) << "a field of a miss is not 0";
}

void expectTriangle(const Result& r, uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex, float t,
                    float u, float v, bool front) {
    EXPECT_EQ(r.committedType, kCommittedTriangle);
    EXPECT_EQ(r.instanceId, instanceId);
    EXPECT_EQ(r.geometryIndex, geometryIndex);
    EXPECT_EQ(r.primitiveIndex, primitiveIndex);
    EXPECT_NEAR(r.t, t, kTol);
    EXPECT_NEAR(r.barycentrics[0], u, kTol);
    EXPECT_NEAR(r.barycentrics[1], v, kTol);
    EXPECT_EQ(r.frontFace, front ? 1u : 0u);
}

void expectPositions(const Result& r, const std::vector<std::array<float, 3>>& expected) {
    ASSERT_EQ(r.positionsValid, 1u);
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.positions[i][c], expected[size_t(i)][size_t(c)], kTol) << i << c;
        EXPECT_EQ(r.positions[i][3], 0.0f);
    }
}

class LavapipeSideTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        side_ = LavapipeSide::create(&why_);
        if (side_)
            std::cout << "[ LAVAPIPE ] " << side_->deviceDescription()
                      << (side_->hasPositionFetch() ? ", position fetch" : ", no position fetch")
                      << (side_->hasOpacityMicromap() ? ", opacity micromaps" : ", no opacity micromaps") << std::endl;
    }
    static void TearDownTestSuite() { side_.reset(); }

    void SetUp() override {
        if (side_) return;
        const char* require = std::getenv("VKAS_REQUIRE_LAVAPIPE");
        if (require && std::string(require) == "1") FAIL() << "lavapipe is required but unavailable: " << why_;
        GTEST_SKIP() << "lavapipe unavailable (set VKAS_REQUIRE_LAVAPIPE=1 to make this a failure): " << why_;
    }

    static std::vector<Result> run(const Scene& scene, const std::vector<Ray>& rays) {
        std::vector<Result> results = side_->run(scene, rays);
        EXPECT_EQ(results.size(), rays.size());
        return results;
    }

    static inline std::unique_ptr<LavapipeSide> side_;
    static inline std::string why_;
};

TEST_F(LavapipeSideTest, SingleTriangleIdsFacingAndMask) {
    Scene scene;
    // Geometry 0 and primitive 0 of geometry 1 lie away from the rays; primitive 1 of geometry 1 is hit at z = 2.
    const int blas = addBlas(scene, {triangles(scene, {100, 0, 2, 101, 0, 2, 100, 1, 2}),
                                     triangles(scene, {0, 100, 2, 1, 100, 2, 0, 101, 2,  //
                                                       0, 0, 2, 0, 4, 2, 4, 0, 2})});
    scene.instances.push_back(instance(blas, translation(10, 0, 0)));  // instance 0 is not on the rays
    Instance hit = instance(blas);
    hit.customIndex = 0xABCDEF;
    hit.sbtOffset = 0x123456;
    hit.mask = 0x0F;
    scene.instances.push_back(hit);

    const std::vector<Ray> rays = {
        ray(1, 0.5f, 0, 0, 0, 1),                          // 0: front face: cross(v1 - v0, v2 - v0) faces it
        ray(1, 0.5f, 4, 0, 0, -1),                         // 1: back face
        ray(1, 0.5f, 0, 0, 0, 1, 0, 1000, 0, 0xF0),        // 2: cull mask disjoint from the instance mask
        ray(1, 0.5f, 0, 0, 0, 1, 0, 1000, 0, 0x01),        // 3: cull mask sharing one bit
        ray(1, 0.5f, 0, 0, 0, 1, 0, 1000, kRayCullFront),  // 4: front face culled
        ray(1, 0.5f, 4, 0, 0, -1, 0, 1000, kRayCullBack),  // 5: back face culled
        ray(1, 0.5f, 0, 0, 0, 1, 0, 1.5f),                 // 6: tMax before the triangle
        ray(1, 0.5f, 0, 0, 0, 1, 2.5f, 1000),              // 7: tMin after the triangle
    };
    const std::vector<Result> r = run(scene, rays);
    // P = v0 + u (v1 - v0) + v (v2 - v0): (1, 0.5) = (4 v, 4 u).
    expectTriangle(r[0], 1, 1, 1, 2.0f, 0.125f, 0.25f, true);
    EXPECT_EQ(r[0].customIndex, 0xABCDEFu);
    EXPECT_EQ(r[0].sbtOffset, 0x123456u);
    EXPECT_EQ(r[0].candidateCount, 0u) << "opaque triangles are committed without a candidate";
    EXPECT_EQ(r[0].positionsValid, 0u) << "the BLAS does not allow data access";
    expectTriangle(r[1], 1, 1, 1, 2.0f, 0.125f, 0.25f, false);
    expectMiss(r[2]);
    expectTriangle(r[3], 1, 1, 1, 2.0f, 0.125f, 0.25f, true);
    expectMiss(r[4]);
    expectMiss(r[5]);
    expectMiss(r[6]);
    expectMiss(r[7]);
}

TEST_F(LavapipeSideTest, TransformedInstance) {
    Scene scene;
    const int blas = addBlas(scene, {triangles(scene, {0, 0, 0, 1, 0, 0, 0, 1, 0})});
    // A rotation by 90 degrees about z, a scale by 2 in x and y and a translation: object (x, y, z) is world
    // (3 - 2y, 2x - 1, z + 5). The facing is decided in object space: the instance transform does not change it.
    scene.instances.push_back(instance(blas, matrix(0, -2, 0, 3, 2, 0, 0, -1, 0, 0, 1, 5)));
    Instance flipped = instance(blas, matrix(0, -2, 0, 23, 2, 0, 0, -1, 0, 0, 1, 5));
    flipped.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR;
    scene.instances.push_back(flipped);

    // Object point (0.25, 0.25, 0) is world (2.5, -0.5, 5); the direction's length 2 halves t.
    const std::vector<Result> r =
        run(scene, {ray(2.5f, -0.5f, 9, 0, 0, -2), ray(22.5f, -0.5f, 9, 0, 0, -2), ray(2.5f, -0.5f, 1, 0, 0, 4)});
    expectTriangle(r[0], 0, 0, 0, 2.0f, 0.25f, 0.25f, true);
    expectTriangle(r[1], 1, 0, 0, 2.0f, 0.25f, 0.25f, false);
    expectTriangle(r[2], 0, 0, 0, 1.0f, 0.25f, 0.25f, false);
}

TEST_F(LavapipeSideTest, AabbProceduralStepGeneratesAtBoxEntry) {
    Scene scene;
    // Object-space boxes along +x; instance 1 moves them by +10 (instance 0 is a null reference).
    // generateRule(instance 1, geometry 0, p) is false for p = 1 only: the nearest box is never generated.
    const int blas =
        addBlas(scene, {aabbs(scene,
                              {{2, -1, -1, 2.5f, 1, 1},  // p0: world x 12 .. 12.5
                               {1, -1, -1, 1.5f, 1, 1},  // p1: world x 11 .. 11.5, not generated
                               {4, -1, -1, 5, 1, 1}},    // p2: world x 14 .. 15
                              // Opaque AABBs are candidates all the same.
                              VK_GEOMETRY_OPAQUE_BIT_KHR | VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR)});
    scene.instances.push_back(instance(-1));
    Instance boxes = instance(blas, translation(10, 0, 0));
    boxes.customIndex = 77;
    boxes.sbtOffset = 5;
    scene.instances.push_back(boxes);

    const std::vector<Ray> rays = {
        ray(0, 0, 0, 1, 0, 0),                                      // 0: p0 entered at t = 12
        ray(0, 0, 0, 2, 0, 0),                                      // 1: same, t = 6 along a longer direction
        ray(0, 0, 0, 1, 0, 0, 12.25f, 1000),                        // 2: tMin inside p0: tHit = tMin
        ray(0, 0, 0, 1, 0, 0, 12.75f, 1000),                        // 3: tMin past p0: p2 at 14
        ray(0, 0, 0, 1, 0, 0, 0, 11.75f),                           // 4: only p1 in range, never generated
        ray(0, 0, 0, 1, 0, 0, 0, 1000, 0, 0xFF, diff::kModeCount),  // 5: every box is a candidate
    };
    const std::vector<Result> r = run(scene, rays);
    const float expectedT[4] = {12.0f, 6.0f, 12.25f, 14.0f};
    const uint32_t expectedPrimitive[4] = {0, 0, 0, 2};
    for (int i = 0; i < 4; ++i) {
        SCOPED_TRACE(i);
        EXPECT_EQ(r[size_t(i)].committedType, kCommittedGenerated);
        EXPECT_EQ(r[size_t(i)].instanceId, 1u);
        EXPECT_EQ(r[size_t(i)].customIndex, 77u);
        EXPECT_EQ(r[size_t(i)].sbtOffset, 5u);
        EXPECT_EQ(r[size_t(i)].geometryIndex, 0u);
        EXPECT_EQ(r[size_t(i)].primitiveIndex, expectedPrimitive[i]);
        EXPECT_EQ(r[size_t(i)].t, expectedT[i]) << "the generated t is the program's own float result";
        EXPECT_EQ(r[size_t(i)].frontFace, 0u);
        EXPECT_EQ(r[size_t(i)].barycentrics[0], 0.0f);
        EXPECT_EQ(r[size_t(i)].barycentrics[1], 0.0f);
        EXPECT_GE(r[size_t(i)].candidateCount, 1u);
        EXPECT_EQ(r[size_t(i)].candidates[0].type, kCandidateAabb);
    }
    EXPECT_EQ(r[4].committedType, kCommittedNone);
    EXPECT_GE(r[4].candidateCount, 1u);
    EXPECT_EQ(r[4].t, 0.0f);
    expectMiss(r[5], 3);
    std::vector<uint32_t> primitives;
    for (uint32_t i = 0; i < std::min(r[5].candidateCount, 3u); ++i) {
        EXPECT_EQ(r[5].candidates[i].type, kCandidateAabb);
        EXPECT_EQ(r[5].candidates[i].instanceId, 1u);
        EXPECT_EQ(r[5].candidates[i].geometryIndex, 0u);
        primitives.push_back(r[5].candidates[i].primitiveIndex);
    }
    std::sort(primitives.begin(), primitives.end());
    EXPECT_EQ(primitives, (std::vector<uint32_t>{0, 1, 2}));
}

// The AABB step is float arithmetic without contraction, the same on both sides: the generated t must be the value
// C++ computes, bit for bit (an identity instance keeps the object-space ray exact).
TEST_F(LavapipeSideTest, AabbStepIsExactFloatArithmetic) {
    Scene scene;
    const VkAabbPositionsKHR box{0.3f, 0.1f, 0.2f, 0.7f, 0.9f, 0.8f};
    const int blas = addBlas(scene, {aabbs(scene, {box}, 0)});
    scene.instances.push_back(instance(blas));

    std::vector<Ray> rays;
    std::vector<float> expected;
    uint32_t state = 12345;
    auto next = [&] {  // a fixed LCG: the same rays on every run
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    while (rays.size() < 256) {
        const float o[3] = {-1.0f - next(), -0.5f - next(), -0.7f - next()};
        const float target[3] = {0.35f + 0.3f * next(), 0.15f + 0.7f * next(), 0.25f + 0.5f * next()};
        const float d[3] = {(target[0] - o[0]) * 0.37f, (target[1] - o[1]) * 0.37f, (target[2] - o[2]) * 0.37f};
        const float tMin = next() < 0.25f ? 3.0f * next() : 0.0f;
        float t0[3], t1[3];
        const float lo[3] = {box.minX, box.minY, box.minZ}, hi[3] = {box.maxX, box.maxY, box.maxZ};
        for (int c = 0; c < 3; ++c) {
            t0[c] = (lo[c] - o[c]) / d[c];
            t1[c] = (hi[c] - o[c]) / d[c];
        }
        const float tNear = std::max(std::max(std::min(t0[0], t1[0]), std::min(t0[1], t1[1])), std::min(t0[2], t1[2]));
        const float tFar = std::min(std::min(std::max(t0[0], t1[0]), std::max(t0[1], t1[1])), std::max(t0[2], t1[2]));
        const float tHit = std::max(tNear, tMin);
        if (!(tHit <= tFar)) continue;
        rays.push_back(ray(o[0], o[1], o[2], d[0], d[1], d[2], tMin, 1000));
        expected.push_back(tHit);
    }
    const std::vector<Result> r = run(scene, rays);
    int mismatches = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(r[i].committedType, kCommittedGenerated) << "ray " << i;
        if (r[i].t != expected[i] && ++mismatches <= 5)
            ADD_FAILURE() << "ray " << i << ": t " << r[i].t << " != " << expected[i] << " (" << std::hexfloat << r[i].t
                          << " vs " << expected[i] << std::defaultfloat << ")";
    }
    EXPECT_EQ(mismatches, 0);
}

TEST_F(LavapipeSideTest, CountModeCountsNonOpaqueCandidates) {
    Scene scene;
    // Geometry 0: three non-opaque triangles at z = 1, 2, 3 (no duplicate any-hit: each is a candidate once);
    // geometry 1: an opaque triangle at z = 5.
    std::vector<float> stack;
    for (float z : {1.0f, 2.0f, 3.0f}) stack.insert(stack.end(), {-1, -1, z, 3, -1, z, -1, 3, z});
    const int blas = addBlas(scene, {triangles(scene, stack, VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR),
                                     triangles(scene, {-1, -1, 5, 3, -1, 5, -1, 3, 5})});
    scene.instances.push_back(instance(blas));

    const std::vector<Ray> rays = {
        ray(0, 0, 0, 0, 0, 1, 0, 100, 0, 0xFF, diff::kModeCount),             // 0
        ray(0, 0, 0, 0, 0, 1, 0, 100, kRayOpaque, 0xFF, diff::kModeCount),    // 1: everything opaque
        ray(0, 0, 0, 0, 0, 1, 0, 100, kRayNoOpaque, 0xFF, diff::kModeCount),  // 2: nothing opaque
        ray(0, 0, 0, 0, 0, 1),                                                // 3: closest mode
    };
    const std::vector<Result> r = run(scene, rays);
    // (0, 0) on each triangle: v0 + 0.25 (v1 - v0) + 0.25 (v2 - v0); seen from below (v0, v1, v2) is counterclockwise.
    expectTriangle(r[0], 0, 1, 0, 5.0f, 0.25f, 0.25f, false);
    EXPECT_EQ(r[0].candidateCount, 3u);
    std::vector<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>> candidates;
    for (uint32_t i = 0; i < std::min(r[0].candidateCount, 3u); ++i) {
        const auto& c = r[0].candidates[i];
        candidates.emplace_back(c.type, c.instanceId, c.geometryIndex, c.primitiveIndex);
    }
    std::sort(candidates.begin(), candidates.end());
    EXPECT_EQ(candidates,
              (decltype(candidates){
                  {kCandidateTriangle, 0, 0, 0}, {kCandidateTriangle, 0, 0, 1}, {kCandidateTriangle, 0, 0, 2}}));
    for (uint32_t i = 3; i < diff::kMaxRecordedCandidates; ++i) {
        const auto& c = r[0].candidates[i];
        EXPECT_EQ(c.type | c.instanceId | c.geometryIndex | c.primitiveIndex, 0u) << "unrecorded slot " << i;
    }

    expectTriangle(r[1], 0, 0, 0, 1.0f, 0.25f, 0.25f, false);
    EXPECT_EQ(r[1].candidateCount, 0u);
    expectMiss(r[2], 4);
    // confirmRule(0, 0, p) = 3p % 4 != 0: the triangle at z = 1 (p = 0) is not confirmed, the one at z = 2 is.
    expectTriangle(r[3], 0, 0, 1, 2.0f, 0.25f, 0.25f, false);
}

TEST_F(LavapipeSideTest, NullReferenceAndEmptyTlasMiss) {
    Scene scene;
    const int blas = addBlas(scene, {triangles(scene, {-1, -1, 1, 3, -1, 1, -1, 3, 1})});
    scene.instances.push_back(instance(-1));
    const Ray down = ray(0, 0, 0, 0, 0, 1);
    expectMiss(run(scene, {down})[0]);

    scene.instances.push_back(instance(blas));  // instance ids count null references
    expectTriangle(run(scene, {down})[0], 1, 0, 0, 1.0f, 0.25f, 0.25f, false);

    scene.instances.clear();
    expectMiss(run(scene, {down})[0]);

    Scene empty;  // no BLAS, no instance, no data
    expectMiss(run(empty, {down, ray(0, 0, 0, 1, 0, 0, 0, 1000, 0, 0xFF, diff::kModeCount)})[1]);
    EXPECT_TRUE(run(empty, {}).empty());
}

TEST_F(LavapipeSideTest, PositionFetchReturnsTransformedVertices) {
    if (!side_->hasPositionFetch()) GTEST_SKIP() << "lavapipe without rayTracingPositionFetch";
    Scene scene;
    // Two geometry transforms; the range's transformOffset selects the second: x' = 2x + 1, z' = z + 3.
    const std::vector<VkTransformMatrixKHR> transforms = {matrix(9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9),
                                                          matrix(2, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 3)};
    auto geometry = [&] {
        Geometry g = triangles(scene, {0, 0, 0, 0, 1, 0, 1, 0, 0});
        g.triangles.hasTransform = true;
        g.triangles.transformOffset = append(scene, transforms);
        g.range.transformOffset = sizeof(VkTransformMatrixKHR);
        return g;
    };
    const int withAccess = addBlas(scene, {geometry()}, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR);
    const int without = addBlas(scene, {geometry()});
    scene.instances.push_back(instance(withAccess, translation(0, 0, 10)));  // positions stay in object space
    scene.instances.push_back(instance(without, translation(10, 0, 10)));

    // The transformed triangle (1,0,3) (1,1,3) (3,0,3) is at world z = 13.
    const std::vector<Result> r = run(scene, {ray(1.5f, 0.25f, 20, 0, 0, -1), ray(11.5f, 0.25f, 20, 0, 0, -1)});
    expectTriangle(r[0], 0, 0, 0, 7.0f, 0.25f, 0.25f, false);
    expectPositions(r[0], {{1, 0, 3}, {1, 1, 3}, {3, 0, 3}});
    expectTriangle(r[1], 1, 0, 0, 7.0f, 0.25f, 0.25f, false);
    EXPECT_EQ(r[1].positionsValid, 0u);
    for (const auto& p : r[1].positions)
        for (float c : p) EXPECT_EQ(c, 0.0f);
}

// Position fetch in a BLAS of two geometries. Mesa 25.0.7's lavapipe takes the primitive index as an index over the
// whole BLAS (geometry 0's triangles first), so a hit on geometry 1 primitive 0 returns geometry 0 primitive 0's
// vertices. The test accepts exactly that wrong answer, naming the defect (the differential test recognises it as
// lavapipe-fetch-blas-index), or the spec's answer; anything else fails.
TEST_F(LavapipeSideTest, PositionFetchSecondGeometry) {
    if (!side_->hasPositionFetch()) GTEST_SKIP() << "lavapipe without rayTracingPositionFetch";
    Scene scene;
    // Geometry 0: one triangle at z = 0; geometry 1: two triangles at z = 5, the second one the hit below.
    const Geometry first = triangles(scene, {0, 0, 0, 0, 1, 0, 1, 0, 0});
    const Geometry second = triangles(scene, {20, 0, 5, 20, 1, 5, 21, 0, 5, 10, 0, 5, 10, 1, 5, 11, 0, 5});
    scene.instances.push_back(
        instance(addBlas(scene, {first, second}, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR)));
    const std::vector<Result> r = run(scene, {ray(10.25f, 0.25f, 10, 0, 0, -1), ray(20.25f, 0.25f, 10, 0, 0, -1)});
    expectTriangle(r[0], 0, 1, 1, 5.0f, 0.25f, 0.25f, false);
    expectTriangle(r[1], 0, 1, 0, 5.0f, 0.25f, 0.25f, false);
    ASSERT_EQ(r[0].positionsValid, 1u);
    ASSERT_EQ(r[1].positionsValid, 1u);
    // BLAS-wide triangle 1 is geometry 1 primitive 0; BLAS-wide triangle 0 is geometry 0 primitive 0.
    if (r[0].positions[0][0] == 20.0f && r[1].positions[0][0] == 0.0f) {
        std::cout << "[ DEFECT   ] " << side_->deviceDescription()
                  << " fetches the vertices of the BLAS-wide triangle numbered by the primitive index, ignoring the "
                     "geometry index (docs/CONFORMANCE.md)"
                  << std::endl;
        return;
    }
    expectPositions(r[0], {{10, 0, 5}, {10, 1, 5}, {11, 0, 5}});
    expectPositions(r[1], {{20, 0, 5}, {20, 1, 5}, {21, 0, 5}});
}

TEST_F(LavapipeSideTest, Snorm16AndHalfFloatVertexFormats) {
    Scene scene;
    // R16G16B16A16_SNORM: -32768 clamps to -1, 32767 is 1; w is ignored.
    const std::vector<int16_t> snorm = {-32768, -32767, 32767, 12345,  //
                                        32767,  -32767, 32767, -5,     //
                                        -32767, 32767,  32767, 0};
    Geometry s;
    s.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    s.triangles.vertexFormat = VK_FORMAT_R16G16B16A16_SNORM;
    s.triangles.vertexOffset = append(scene, snorm);
    s.triangles.vertexStride = 8;
    s.triangles.maxVertex = 2;
    s.range.primitiveCount = 1;
    // R16G16_SFLOAT (z = 0): 0x3800 0.5, 0x4000 2, 0xBE00 -1.5.
    const std::vector<uint16_t> half = {0x3800, 0x3800, 0x4000, 0x3800, 0x3800, 0xBE00};
    Geometry h;
    h.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    h.triangles.vertexFormat = VK_FORMAT_R16G16_SFLOAT;
    h.triangles.vertexOffset = append(scene, half);
    h.triangles.vertexStride = 4;
    h.triangles.maxVertex = 2;
    h.range.primitiveCount = 1;
    const VkBuildAccelerationStructureFlagsKHR access = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
    scene.instances.push_back(instance(addBlas(scene, {s}, access)));
    scene.instances.push_back(instance(addBlas(scene, {h}, access), translation(10, 0, 0)));

    // snorm: (-1,-1,1) (1,-1,1) (-1,1,1); half: (0.5,0.5,0) (2,0.5,0) (0.5,-1.5,0), both hit at u = v = 0.25.
    const std::vector<Result> r = run(scene, {ray(-0.5f, -0.5f, 0, 0, 0, 1), ray(10.875f, 0, -3, 0, 0, 1)});
    expectTriangle(r[0], 0, 0, 0, 1.0f, 0.25f, 0.25f, false);
    expectTriangle(r[1], 1, 0, 0, 3.0f, 0.25f, 0.25f, true);
    if (side_->hasPositionFetch()) {
        expectPositions(r[0], {{-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}});
        expectPositions(r[1], {{0.5f, 0.5f, 0}, {2, 0.5f, 0}, {0.5f, -1.5f, 0}});
    }
}

// A quad (-1,-1) (1,-1) (1,1) (-1,1) at z = 2 with stride 16 (a padding float), as two triangles (q0 q1 q2) and
// (q0 q2 q3); ray (0.5, -0.5) hits triangle 0 at u = 0.5, v = 0.25, ray (-0.5, 0.5) triangle 1 at u = 0.25, v = 0.5
// (both back faces for a ray along +z).
const std::vector<float> kQuad = {-1, -1, 2, 0, 1, -1, 2, 0, 1, 1, 2, 0, -1, 1, 2, 0};

TEST_F(LavapipeSideTest, IndexedWithPrimitiveOffset) {
    Scene scene;
    // The quad, then four decoy vertices at x, y in [50, 51]; three decoy indices (a decoy triangle) precede the
    // quad's two triangles and primitiveOffset skips them.
    std::vector<float> vertices = kQuad;
    vertices.insert(vertices.end(), {50, 50, 2, 0, 51, 50, 2, 0, 51, 51, 2, 0, 50, 51, 2, 0});
    const std::vector<uint32_t> indices = {4, 5, 6, 0, 1, 2, 0, 2, 3};
    auto quad = [&](VkIndexType type) {
        Geometry g;
        g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
        g.triangles.vertexOffset = append(scene, vertices);
        g.triangles.vertexStride = 16;
        g.triangles.maxVertex = 7;
        g.triangles.indexType = type;
        if (type == VK_INDEX_TYPE_UINT16) {
            g.triangles.indexOffset = append(scene, std::vector<uint16_t>(indices.begin(), indices.end()));
            g.range.primitiveOffset = 3 * sizeof(uint16_t);
        } else {
            g.triangles.indexOffset = append(scene, indices);
            g.range.primitiveOffset = 3 * sizeof(uint32_t);
        }
        g.range.primitiveCount = 2;
        return g;
    };
    scene.instances.push_back(instance(addBlas(scene, {quad(VK_INDEX_TYPE_UINT16)})));
    scene.instances.push_back(instance(addBlas(scene, {quad(VK_INDEX_TYPE_UINT32)}), translation(10, 0, 0)));

    const std::vector<Result> r =
        run(scene, {ray(0.5f, -0.5f, 0, 0, 0, 1), ray(-0.5f, 0.5f, 0, 0, 0, 1), ray(10.5f, -0.5f, 0, 0, 0, 1),
                    ray(9.5f, 0.5f, 0, 0, 0, 1), ray(50.75f, 50.25f, 0, 0, 0, 1), ray(60.75f, 50.25f, 0, 0, 0, 1)});
    for (uint32_t i = 0; i < 2; ++i) {
        SCOPED_TRACE(i);
        expectTriangle(r[2 * i], i, 0, 0, 2.0f, 0.5f, 0.25f, false);
        expectTriangle(r[2 * i + 1], i, 0, 1, 2.0f, 0.25f, 0.5f, false);
        expectMiss(r[4 + i]);  // the decoy triangle is not in the range
    }
}

// firstVertex, indexed and not, without the workaround. Mesa 25.0.7's lavapipe adds firstVertex twice (it reads
// vertex index + 2 firstVertex): the test accepts exactly that wrong answer, naming the defect (LavapipeSide folds
// firstVertex into the vertex address for the differential cases while it lasts), or the spec's answer; anything
// else fails.
TEST_F(LavapipeSideTest, FirstVertex) {
    Scene scene;
    // Three copies of the quad, at x = 0, 30 and 60; firstVertex selects the second.
    std::vector<float> indexedVertices, listVertices;
    for (float x : {0.0f, 30.0f, 60.0f}) {
        std::vector<float> q = kQuad;
        for (size_t v = 0; v < 4; ++v) q[4 * v] += x;
        indexedVertices.insert(indexedVertices.end(), q.begin(), q.end());
        for (size_t v : {0, 1, 2, 0, 2, 3}) listVertices.insert(listVertices.end(), &q[4 * v], &q[4 * v + 4]);
    }
    Geometry indexed;
    indexed.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    indexed.triangles.vertexOffset = append(scene, indexedVertices);
    indexed.triangles.vertexStride = 16;
    indexed.triangles.maxVertex = 11;
    indexed.triangles.indexType = VK_INDEX_TYPE_UINT32;
    indexed.triangles.indexOffset = append(scene, std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
    indexed.range.primitiveCount = 2;
    indexed.range.firstVertex = 4;
    Geometry list;
    list.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    list.triangles.vertexOffset = append(scene, listVertices);
    list.triangles.vertexStride = 16;
    list.triangles.maxVertex = 17;
    list.range.primitiveCount = 2;
    list.range.firstVertex = 6;
    scene.instances.push_back(instance(addBlas(scene, {indexed})));
    scene.instances.push_back(instance(addBlas(scene, {list}), translation(0, 10, 0)));

    std::vector<Ray> rays;
    for (float y : {0.0f, 10.0f})
        for (float x : {30.0f, 60.0f}) {
            rays.push_back(ray(x + 0.5f, y - 0.5f, 0, 0, 0, 1));
            rays.push_back(ray(x - 0.5f, y + 0.5f, 0, 0, 0, 1));
        }
    // With the workaround (what the differential cases use): the spec's vertices.
    const std::vector<Result> folded = run(scene, rays);
    for (uint32_t i = 0; i < 2; ++i) {
        SCOPED_TRACE("with foldFirstVertex, instance " + std::to_string(i));
        expectTriangle(folded[4 * i], i, 0, 0, 2.0f, 0.5f, 0.25f, false);
        expectTriangle(folded[4 * i + 1], i, 0, 1, 2.0f, 0.25f, 0.5f, false);
        expectMiss(folded[4 * i + 2]);
        expectMiss(folded[4 * i + 3]);
    }
    side_->setWorkarounds({.foldFirstVertex = false});  // the raw behaviour
    const std::vector<Result> r = run(scene, rays);
    side_->setWorkarounds({});
    // Rays 0, 1 (indexed) and 4, 5 (list) on the second copy; 2, 3 and 6, 7 on the third.
    const bool hitsThird = r[2].committedType == kCommittedTriangle && r[3].committedType == kCommittedTriangle &&
                           r[6].committedType == kCommittedTriangle && r[7].committedType == kCommittedTriangle &&
                           r[0].committedType == kCommittedNone && r[1].committedType == kCommittedNone &&
                           r[4].committedType == kCommittedNone && r[5].committedType == kCommittedNone;
    if (hitsThird) {
        std::cout << "[ DEFECT   ] " << side_->deviceDescription()
                  << " applies VkAccelerationStructureBuildRangeInfoKHR::firstVertex twice (LavapipeSide::Workarounds::"
                     "foldFirstVertex works around it; docs/CONFORMANCE.md)"
                  << std::endl;
        return;
    }
    for (uint32_t i = 0; i < 2; ++i) {
        SCOPED_TRACE(i);
        expectTriangle(r[4 * i], i, 0, 0, 2.0f, 0.5f, 0.25f, false);
        expectTriangle(r[4 * i + 1], i, 0, 1, 2.0f, 0.25f, 0.5f, false);
        expectMiss(r[4 * i + 2]);
        expectMiss(r[4 * i + 3]);
    }
}

// Issue 16 asks for micromap cases in the differential test if the lavapipe of the test setup exposes
// VK_EXT_opacity_micromap. Mesa 25.0.7 (bookworm-backports) does not: neither the extension in
// vkEnumerateDeviceExtensionProperties nor VkPhysicalDeviceOpacityMicromapFeaturesEXT::micromap. docs/CONFORMANCE.md
// states that fact; this fails when a newer lavapipe makes it false, because the differential test then owes
// micromap cases.
TEST_F(LavapipeSideTest, OpacityMicromapNotExposed) {
    EXPECT_FALSE(side_->hasOpacityMicromap())
        << side_->deviceDescription()
        << " exposes VK_EXT_opacity_micromap: add micromap cases to the differential test and update "
           "docs/CONFORMANCE.md";
}

TEST_F(LavapipeSideTest, InvalidSceneThrows) {
    Scene scene;
    scene.instances.push_back(instance(0));  // there is no BLAS 0
    EXPECT_THROW(run(scene, {ray(0, 0, 0, 0, 0, 1)}), std::runtime_error);
    // The side is still usable afterwards.
    scene.instances.clear();
    expectMiss(run(scene, {ray(0, 0, 0, 0, 0, 1)})[0]);
}

}  // namespace
