// CTS `empty`: inactive triangles (NaN X in any of the 3 vertices: 7 patterns), inactive instances (reference 0,
// still counted in instance ids), geometryCount = 0 BLAS, primitiveCount = 0 BLAS and TLAS.
#include <cmath>
#include <cstring>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {
const VkIndexType kIndexTypes[3] = {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32};
std::string indexName(VkIndexType t) {
    return t == VK_INDEX_TYPE_NONE_KHR ? "index_none" : t == VK_INDEX_TYPE_UINT16 ? "index_uint16" : "index_uint32";
}
// A grid mesh with unshared vertices (3 per triangle), so that a NaN affects exactly one triangle.
Mesh unsharedGrid(int n) {
    Mesh g = grid(n, n), out;
    for (uint32_t i : g.indices) {
        out.positions.push_back(g.positions[i]);
        out.indices.push_back(uint32_t(out.positions.size() - 1));
    }
    return out;
}
// Rays straight down at every triangle's centroid of a mesh (instance transform applied).
std::vector<oracle::Ray> raysAtCentroids(const Mesh& m, const VkTransformMatrixKHR& xf) {
    std::vector<oracle::Ray> rays;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
        Float3 c{0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) c[j] += m.positions[m.indices[3 * t + k]][j] / 3.0f;
        const Float3 top = transformPoint(xf, {c[0], c[1], 1.0f}), bottom = transformPoint(xf, {c[0], c[1], -1.0f});
        oracle::Ray r;
        r.origin = top;
        r.direction = {bottom[0] - top[0], bottom[1] - top[1], bottom[2] - top[2]};
        r.tMin = 0;
        r.tMax = 10;
        rays.push_back(r);
    }
    return rays;
}
}  // namespace

class empty : public VkasTest, public ::testing::WithParamInterface<VkIndexType> {};

TEST_P(empty, inactive_triangles) {
    const Mesh base = unsharedGrid(6);  // 72 triangles
    for (int pattern = 1; pattern <= 7; ++pattern) {
        SCOPED_TRACE("NaN pattern " + std::to_string(pattern));
        Mesh m = base;
        std::vector<bool> inactive(m.triangleCount());
        for (size_t t = 0; t < m.triangleCount(); ++t) {
            inactive[t] = rng.coin();
            if (!inactive[t]) continue;
            for (int k = 0; k < 3; ++k)
                if (pattern & (1 << k)) m.positions[m.indices[3 * t + k]][0] = std::numeric_limits<float>::quiet_NaN();
        }
        auto g = makeGeometry(m, GetParam());
        AccelStruct* blas = buildBlas(*g);
        const VkTransformMatrixKHR xf = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 2.0f);
        AccelStruct* tlas = buildTlas({Instance{xf, 0, 0xFF, 0, 0, blas}});
        for (size_t t = 0; t < m.triangleCount(); ++t)
            ASSERT_EQ(tlas->scene->instances[0].blas->geometries[0].triangles[t].active, !inactive[t]);
        const auto rays = raysAtCentroids(base, xf);
        checkRays(tlas, rays);
        // Analytic expectation: a ray at an active triangle's centroid hits it; at an inactive one it misses.
        for (size_t t = 0; t < rays.size(); ++t) {
            const Hit h = traceClosest(tlas, rays[t]);
            if (inactive[t])
                EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_NONE) << "triangle " << t << " is inactive: " << h.str();
            else
                EXPECT_EQ(h.primitiveIndex, int32_t(t)) << h.str();
        }
    }
    // Every triangle inactive: nothing is ever hit.
    Mesh all = base;
    for (auto& p : all.positions) p[0] = std::numeric_limits<float>::quiet_NaN();
    auto g = makeGeometry(all, GetParam());
    AccelStruct* tlas = buildSingleInstanceTlas(buildBlas(*g));
    for (const auto& r : raysAtCentroids(base, identityTransform())) EXPECT_EQ(traceClosest(tlas, r).type, 0u);
}

TEST_P(empty, inactive_instances) {
    const Mesh m = grid(2, 2);
    auto g = makeGeometry(m, GetParam());
    AccelStruct* blas = buildBlas(*g);
    std::vector<Instance> instances;
    std::vector<VkTransformMatrixKHR> transforms;
    for (int i = 0; i < 40; ++i) {
        Instance inst;
        inst.transform = translation(3.0f * (i % 8), 3.0f * (i / 8), 0);
        inst.customIndex = 1000 + i;
        inst.blas = rng.coin(0.4) ? nullptr : blas;
        instances.push_back(inst);
    }
    instances[0].blas = nullptr;
    instances[39].blas = nullptr;
    AccelStruct* tlas = buildTlas(instances);
    std::vector<oracle::Ray> all;
    for (int i = 0; i < 40; ++i) {
        const auto rays = raysAtCentroids(m, instances[i].transform);
        for (const auto& r : rays) {
            const Hit h = traceClosest(tlas, r);
            if (!instances[i].blas) {
                EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_NONE) << "instance " << i << " is inactive";
            } else {
                EXPECT_EQ(h.instanceId, i) << "inactive instances still count in instance ids";
                EXPECT_EQ(h.customIndex, 1000 + i);
            }
        }
        all.insert(all.end(), rays.begin(), rays.end());
    }
    checkRays(tlas, all);
    const auto more = randomRays(*tlas->scene, 200);
    checkRays(tlas, more);
    // All instances inactive.
    for (auto& inst : instances) inst.blas = nullptr;
    AccelStruct* none = buildTlas(instances);
    EXPECT_EQ(checkRays(none, all), 0u);
}

TEST_P(empty, no_geometries_bottom) {
    AccelStruct* emptyBlas = buildBlas(std::vector<VkAccelerationStructureGeometryKHR>{},
                                       std::vector<VkAccelerationStructureBuildRangeInfoKHR>{});
    const Mesh m = grid(2, 2);
    auto g = makeGeometry(m, GetParam());
    AccelStruct* blas = buildBlas(*g);
    AccelStruct* onlyEmpty = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, 0, emptyBlas}});
    const auto rays = raysAtCentroids(m, identityTransform());
    EXPECT_EQ(checkRays(onlyEmpty, rays), 0u);
    EXPECT_EQ(checkRays(onlyEmpty, randomRays(oracle::Scene{}, 100)), 0u);
    // Mixed with a non-empty instance: the non-empty one is found with its instance id.
    AccelStruct* mixed = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, 0, emptyBlas},
                                    Instance{identityTransform(), 7, 0xFF, 0, 0, blas}});
    for (const auto& r : rays) EXPECT_EQ(traceClosest(mixed, r).instanceId, 1);
    checkRays(mixed, rays);
}

TEST_P(empty, no_primitives_bottom) {
    const Mesh m = grid(3, 3);
    auto zero = makeGeometry(m, GetParam());
    zero->range.primitiveCount = 0;
    auto full = makeGeometry(m, GetParam());
    // Only zero-primitive geometries.
    AccelStruct* emptyBlas = buildBlas(std::vector<const GeometryData*>{zero.get(), zero.get()});
    AccelStruct* tlas = buildSingleInstanceTlas(emptyBlas);
    const auto rays = raysAtCentroids(m, identityTransform());
    EXPECT_EQ(checkRays(tlas, rays), 0u);
    // A zero-primitive geometry before a full one: geometry index 1 is reported.
    AccelStruct* blas = buildBlas(std::vector<const GeometryData*>{zero.get(), full.get()});
    AccelStruct* tlas2 = buildSingleInstanceTlas(blas);
    for (size_t t = 0; t < rays.size(); ++t) {
        const Hit h = traceClosest(tlas2, rays[t]);
        EXPECT_EQ(h.geometryIndex, 1) << h.str();
        EXPECT_EQ(h.primitiveIndex, int32_t(t)) << h.str();
    }
    checkRays(tlas2, rays);
}

TEST_P(empty, no_primitives_top) {
    AccelStruct* tlas = buildTlas({});
    const Mesh m = grid(2, 2);
    EXPECT_EQ(checkRays(tlas, raysAtCentroids(m, identityTransform())), 0u);
    // primitiveCount = 0 with instance data present (not read).
    auto g = makeGeometry(m, GetParam());
    AccelStruct* blas = buildBlas(*g);
    auto pb = prepareTlas({Instance{identityTransform(), 0, 0xFF, 0, 0, blas}});
    pb->ranges[0].primitiveCount = 0;
    pb->scene->instances.clear();
    submit({pb.get()});
    EXPECT_EQ(checkRays(pb->as, raysAtCentroids(m, identityTransform())), 0u);
}

INSTANTIATE_TEST_SUITE_P(cpu_built, empty, ::testing::ValuesIn(kIndexTypes),
                         [](const auto& info) { return indexName(info.param); });
