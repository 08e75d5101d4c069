// CTS `build`: large counts. level_primitives (one geometry, up to 2^20 triangles), level_geometries (many
// geometries sharing one vertex/index buffer through primitiveOffset), level_instances (up to 2^16 instances).
// Rays are checked against the analytic answer of the grid (cheap oracle), and a sample against the brute-force
// oracle where that stays affordable.
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <iostream>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {
struct GridTarget {
    oracle::Ray ray;
    int32_t quad;       // j * nx + i
    int32_t upper;      // 0: below the diagonal, 1: above it
    float b1, b2;       // expected barycentrics
};
// A vertical ray into quad (i, j) of a grid in the plane z = 0, at a point well inside one of its triangles.
GridTarget gridTarget(Rng& rng, int nx, int ny, float x0 = 0, float y0 = 0) {
    GridTarget g;
    const int i = int(rng.below(uint32_t(nx))), j = int(rng.below(uint32_t(ny)));
    g.upper = int(rng.below(2));
    float u = rng.uniformf(0.1f, 0.9f), v = rng.uniformf(0.1f, 0.9f);
    if (std::fabs(u - v) < 0.05f) v = u + (g.upper ? 0.1f : -0.1f);
    if ((v > u) != bool(g.upper)) std::swap(u, v);
    u = std::clamp(u, 0.02f, 0.98f);
    v = std::clamp(v, 0.02f, 0.98f);
    g.quad = j * nx + i;
    // Lower triangle (a, b, c) = ((0,0), (1,0), (1,1)): b1 = u - v, b2 = v. Upper (a, c, d): b1 = u, b2 = v - u.
    g.b1 = g.upper ? u : u - v;
    g.b2 = g.upper ? v - u : v;
    g.ray.origin = {x0 + float(i) + u, y0 + float(j) + v, 1.0f};
    g.ray.direction = {0, 0, -1};
    g.ray.tMin = 0;
    g.ray.tMax = 10;
    return g;
}
std::pair<int, int> gridShape(uint32_t triangles) {  // nx * ny * 2 == triangles
    int nx = 1;
    while (2 * nx * nx < int(triangles)) nx *= 2;
    return {nx, int(triangles / (2 * nx))};
}
double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

class build : public VkasTest, public ::testing::WithParamInterface<uint32_t> {};

TEST_P(build, level_primitives) {
    const uint32_t count = GetParam();
    const auto [nx, ny] = gridShape(count);
    ASSERT_EQ(uint32_t(2 * nx * ny), count);
    auto g = makeGeometry(grid(nx, ny), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    const auto t0 = std::chrono::steady_clock::now();
    AccelStruct* blas = buildBlas(*g);
    std::cout << "  built " << count << " triangles in " << seconds(t0) << " s, size " << blas->size << " bytes, scratch "
              << blas->sizes.buildScratchSize << " bytes" << std::endl;
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    for (int k = 0; k < 2000; ++k) {
        const GridTarget gt = gridTarget(rng, nx, ny);
        const Hit h = traceClosest(tlas, gt.ray);
        ASSERT_EQ(h.type, 1u) << describe(gt.ray) << " seed " << seed;
        EXPECT_EQ(h.primitiveIndex, 2 * gt.quad + gt.upper) << describe(gt.ray);
        EXPECT_EQ(h.geometryIndex, 0);
        EXPECT_NEAR(h.t, 1.0f, 1e-5f);
        EXPECT_NEAR(h.bary[0], gt.b1, 1e-3f);
        EXPECT_NEAR(h.bary[1], gt.b2, 1e-3f);
        if (HasFailure()) return;
    }
    // Rays outside the grid miss.
    for (int k = 0; k < 100; ++k) {
        oracle::Ray r = gridTarget(rng, nx, ny).ray;
        r.origin[0] += float(nx + 1);
        EXPECT_EQ(traceClosest(tlas, r).type, 0u);
    }
    if (count <= (1u << 17)) checkRays(tlas, randomRays(*tlas->scene, count <= (1u << 14) ? 200 : 40));
}

TEST_P(build, level_geometries) {
    const uint32_t geometries = GetParam();
    // One grid of `geometries` quads; geometry k is quad k, selected through primitiveOffset into the shared
    // index buffer (alternately also through firstVertex into a shifted copy of the vertices).
    const auto [nx, ny] = gridShape(2 * geometries);
    const Mesh m = grid(nx, ny);
    auto shared = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    std::vector<VkAccelerationStructureGeometryKHR> geoms(geometries, shared->geometry);
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges(geometries);
    for (uint32_t k = 0; k < geometries; ++k) {
        ranges[k].primitiveCount = 2;
        ranges[k].primitiveOffset = k * 6 * 4;
        if (k % 3 == 0) geoms[k].flags = 0;  // some non-opaque
    }
    const auto t0 = std::chrono::steady_clock::now();
    AccelStruct* blas = buildBlas(geoms, ranges);
    std::cout << "  built " << geometries << " geometries in " << seconds(t0) << " s, size " << blas->size << std::endl;
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    for (int k = 0; k < 2000; ++k) {
        const GridTarget gt = gridTarget(rng, nx, ny);
        const Hit h = traceClosest(tlas, gt.ray);
        ASSERT_EQ(h.type, 1u) << describe(gt.ray) << " seed " << seed;
        EXPECT_EQ(h.geometryIndex, gt.quad);
        EXPECT_EQ(h.primitiveIndex, gt.upper);
        EXPECT_NEAR(h.bary[0], gt.b1, 1e-3f);
        EXPECT_NEAR(h.bary[1], gt.b2, 1e-3f);
        if (HasFailure()) return;
    }
    checkRays(tlas, randomRays(*tlas->scene, geometries <= (1u << 14) ? 200 : 50));
}

TEST_P(build, level_instances) {
    const uint32_t count = GetParam();
    // Two BLASes (a 2x1 grid, and the same grid shifted through a geometry transform), alternating.
    const Mesh m = grid(2, 1);
    const VkTransformMatrixKHR shift = translation(0, 0, -0.5f);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto g1 = makeGeometry(m, VK_INDEX_TYPE_NONE_KHR, 0, &shift);
    AccelStruct* blas[2] = {buildBlas(*g0), buildBlas(*g1)};
    int nx = 1;
    while (nx * nx < int(count)) nx *= 2;
    std::vector<Instance> instances(count);
    for (uint32_t k = 0; k < count; ++k) {
        instances[k].transform = translation(3.0f * float(k % nx), 2.0f * float(k / nx), 0);
        instances[k].customIndex = (k * 2654435761u) & 0xFFFFFF;
        instances[k].sbtOffset = k;
        instances[k].blas = blas[k % 2];
    }
    const auto t0 = std::chrono::steady_clock::now();
    AccelStruct* tlas = buildTlas(instances);
    std::cout << "  built " << count << " instances in " << seconds(t0) << " s, size " << tlas->size << std::endl;
    for (int n = 0; n < 2000; ++n) {
        const uint32_t k = rng.below(count);
        // Quad 0 or 1 of the instance, at a point well away from quad borders (float rounding of the world x).
        const int quad = int(rng.below(2));
        const float frac = rng.uniformf(0.05f, 0.95f), v = rng.uniformf(0.05f, 0.95f);
        const float u = float(quad) + frac;
        oracle::Ray r;
        r.origin = {3.0f * float(k % nx) + u, 2.0f * float(k / nx) + v, 1.0f};
        r.direction = {0, 0, -1};
        r.tMin = 0;
        r.tMax = 10;
        if (std::fabs(frac - v) < 0.02f) continue;  // too close to a diagonal
        const Hit h = traceClosest(tlas, r);
        ASSERT_EQ(h.type, 1u) << describe(r) << " seed " << seed;
        EXPECT_EQ(h.instanceId, int32_t(k));
        EXPECT_EQ(h.customIndex, int32_t(instances[k].customIndex));
        EXPECT_EQ(h.sbtOffset, k);
        EXPECT_EQ(h.primitiveIndex, 2 * quad + (v > frac ? 1 : 0)) << describe(r);
        EXPECT_NEAR(h.t, k % 2 ? 1.5f : 1.0f, 1e-5f);
        if (HasFailure()) return;
    }
    checkRays(tlas, randomRays(*tlas->scene, count <= (1u << 14) ? 100 : 30));
}

INSTANTIATE_TEST_SUITE_P(cpu, build, ::testing::Values(1u << 10, 1u << 14, 1u << 16),
                         [](const auto& info) { return "2pow" + std::to_string(int(std::log2(info.param))); });

using build_large = VkasTest;

TEST_F(build_large, level_primitives_2pow20) {
    // One geometry of 2^20 triangles (non-indexed, so 3 * 2^20 vertices).
    const int nx = 1024, ny = 512;
    auto g = makeGeometry(grid(nx, ny), VK_INDEX_TYPE_NONE_KHR, VK_GEOMETRY_OPAQUE_BIT_KHR);
    ASSERT_EQ(g->range.primitiveCount, 1u << 20);
    const auto t0 = std::chrono::steady_clock::now();
    AccelStruct* blas = buildBlas(*g);
    std::cout << "  built 2^20 triangles in " << seconds(t0) << " s, size " << blas->size << " bytes, scratch "
              << blas->sizes.buildScratchSize << " bytes" << std::endl;
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    for (int k = 0; k < 2000; ++k) {
        const GridTarget gt = gridTarget(rng, nx, ny);
        const Hit h = traceClosest(tlas, gt.ray);
        ASSERT_EQ(h.type, 1u) << describe(gt.ray) << " seed " << seed;
        EXPECT_EQ(h.primitiveIndex, 2 * gt.quad + gt.upper) << describe(gt.ray);
        EXPECT_NEAR(h.bary[0], gt.b1, 1e-3f);
        EXPECT_NEAR(h.bary[1], gt.b2, 1e-3f);
        if (HasFailure()) return;
    }
}

// The provisional name of the range structure (<vkas/vkas_compat.h>): an application written against it passes its
// ranges unchanged, and the final rules apply: with transformData NULL, transformOffset is ignored and no transform
// is read, although the provisional wording said one is always consumed.
class build_provisional : public VkasTest {};

TEST_F(build_provisional, offset_info_name) {
    static_assert(sizeof(VkAccelerationStructureBuildOffsetInfoKHR) == 16);
    static_assert(offsetof(VkAccelerationStructureBuildOffsetInfoKHR, transformOffset) == 12);
    auto g = makeGeometry(grid(8, 8), VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    VkAccelerationStructureBuildOffsetInfoKHR offsetInfo{};
    offsetInfo.primitiveCount = g->range.primitiveCount;
    offsetInfo.transformOffset = 48;  // no transformData: ignored
    const std::vector<VkAccelerationStructureBuildOffsetInfoKHR> offsetInfos{offsetInfo};
    AccelStruct* blas = buildBlas({g->geometry}, offsetInfos);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    EXPECT_GT(checkRays(tlas, randomRays(*tlas->scene, 300)), 0u);
}

// Vertices with infinite coordinates are valid input (no VUID restricts vertex values). Their bounds have NaN
// surface areas, which once left the builder unable to split a node: it recursed without end (more than a leaf of
// such triangles), or wrote more nodes than the size query allows (past the structure, into the canary submit()
// checks). Found by the build fuzzer (docs/FUZZING.md). The finite triangles must still be hit.
class build_nonfinite : public VkasTest {};

TEST_F(build_nonfinite, infinite_vertex_coordinates) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    for (int infinite : {5, 37}) {
        for (int nx : {0, 12}) {
            SCOPED_TRACE(testing::Message() << infinite << " infinite triangles, a grid of " << nx << " x 10 quads");
            Mesh mesh = nx ? grid(nx, 10) : Mesh{};
            for (int i = 0; i < infinite; ++i) {
                const uint32_t base = uint32_t(mesh.positions.size());
                for (int j = 0; j < 3; ++j) mesh.positions.push_back({float(3 * i + j), kInf, 1.0f});
                mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
            }
            auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32);
            BuildOptions opt;
            opt.flags = nx ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR : 0;
            const AccelStruct* blas = buildBlas(*geometry, opt);  // checks the canary after the structure
            const AccelStruct* tlas = buildSingleInstanceTlas(blas);
            for (int k = 0; nx && k < 50; ++k) {
                const GridTarget target = gridTarget(rng, nx, 10);
                const Hit hit = traceClosest(tlas, target.ray);
                ASSERT_EQ(hit.type, uint32_t(VKAS_COMMITTED_INTERSECTION_TRIANGLE)) << describe(target.ray);
                EXPECT_EQ(hit.primitiveIndex, 2 * target.quad + target.upper) << describe(target.ray);
            }
        }
    }
}
