// [EXT-OMM] Opacity micromaps in bottom-level structures and traversal (CTS group opacity_micromap), through the
// public API, against the oracle (tests/support/oracle_micromap.*), which decodes the application's micromap data
// and maps barycentrics to micro-triangles by a recursive descent in double precision:
//   - the micro-triangle index vkas computes (the spec's reference mapping) equals the descent's at every level;
//   - random micromaps of both formats and levels 0-9, every index type, special indices, baseTriangle, every
//     instance flag (FORCE_OPAQUE, FORCE_NO_OPAQUE, FORCE_OPACITY_MICROMAP_2_STATE, DISABLE_OPACITY_MICROMAPS) under
//     random transforms, every opacity ray flag and ForceOpacityMicromap2State: ray queries and vkasTraceRays match
//     the oracle, and vkasTraceRays gives the ray query's hit bit for bit;
//   - each special index under each opacity rule, decided exactly;
//   - rays through micro-edges and micro-vertices: never dropped, and decided by the state their barycentrics select;
//   - the micromap may be destroyed after the build; updates with ALLOW_OPACITY_MICROMAP_DATA_UPDATE and
//     ALLOW_OPACITY_MICROMAP_UPDATE take the new micromap's states; clones, compaction and serialization keep them;
//     rebuilds are byte-identical.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <vector>

#include "engine/trace/opacity_micromap.hpp"
#include "meshes.hpp"
#include "oracle_micromap.hpp"
#include "vkas_test.hpp"

namespace {

using namespace vt;

constexpr uint16_t k2State = VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT, k4State = VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT;

// The application's side of a micromap build.
struct MicromapInput {
    std::vector<VkMicromapTriangleEXT> triangles;
    std::vector<uint8_t> data;
    std::vector<VkMicromapUsageEXT> usage;
    void add(uint16_t format, uint16_t level, const std::vector<uint8_t>& states) {
        VkMicromapTriangleEXT t{uint32_t(data.size()), level, format};
        const uint32_t bits = format == k2State ? 1 : 2;
        std::vector<uint8_t> bytes((states.size() * bits + 7) / 8, 0);
        for (size_t j = 0; j < states.size(); ++j) bytes[j * bits / 8] |= uint8_t(states[j] << (j * bits % 8));
        data.insert(data.end(), bytes.begin(), bytes.end());
        triangles.push_back(t);
        for (auto& u : usage)
            if (u.format == format && u.subdivisionLevel == level) {
                ++u.count;
                return;
            }
        usage.push_back({1, level, format});
    }
};

// A geometry's VkAccelerationStructureTrianglesOpacityMicromapEXT and the memory it points to.
struct GeometryOmm {
    VkAccelerationStructureTrianglesOpacityMicromapEXT info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT};
    std::vector<uint8_t> indices;
    std::vector<VkMicromapUsageEXT> usage;
};

class OpacityMicromapTest : public VkasTest {
  protected:
    PFN_vkCreateMicromapEXT createMicromap = nullptr;
    PFN_vkDestroyMicromapEXT destroyMicromap = nullptr;
    PFN_vkGetMicromapBuildSizesEXT micromapSizes = nullptr;
    PFN_vkBuildMicromapsEXT buildMicromaps = nullptr;
    std::vector<VkMicromapEXT> micromaps;
    std::deque<GeometryOmm> omms;
    std::deque<std::unique_ptr<GeometryData>> geometries;

    void SetUp() override {
        VkasTest::SetUp();
        if (HasFatalFailure()) return;
        createMicromap = reinterpret_cast<PFN_vkCreateMicromapEXT>(vkasGetDeviceProcAddr(device, "vkCreateMicromapEXT"));
        destroyMicromap = reinterpret_cast<PFN_vkDestroyMicromapEXT>(vkasGetDeviceProcAddr(device, "vkDestroyMicromapEXT"));
        micromapSizes =
            reinterpret_cast<PFN_vkGetMicromapBuildSizesEXT>(vkasGetDeviceProcAddr(device, "vkGetMicromapBuildSizesEXT"));
        buildMicromaps = reinterpret_cast<PFN_vkBuildMicromapsEXT>(vkasGetDeviceProcAddr(device, "vkBuildMicromapsEXT"));
        ASSERT_TRUE(createMicromap && destroyMicromap && micromapSizes && buildMicromaps);
    }
    void TearDown() override {
        for (VkMicromapEXT m : micromaps) destroyMicromap(device, m, nullptr);
        oracle::forgetMicromaps();
        VkasTest::TearDown();
    }

    // Builds the micromap (and tells the oracle what it was given).
    VkMicromapEXT buildMicromap(const MicromapInput& in) {
        VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
        info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
        info.usageCountsCount = uint32_t(in.usage.size());
        info.pUsageCounts = in.usage.data();
        info.data.hostAddress = in.data.data();
        info.triangleArray.hostAddress = in.triangles.data();
        info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
        VkMicromapBuildSizesInfoEXT sizes{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
        micromapSizes(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &sizes);
        EXPECT_TRUE(sizes.discardable);
        HostBuffer* buffer = createBuffer(sizes.micromapSize, VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT);
        VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
        ci.buffer = buffer->buffer;
        ci.size = sizes.micromapSize;
        ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        VkMicromapEXT m = VK_NULL_HANDLE;
        EXPECT_EQ(createMicromap(device, &ci, nullptr, &m), VK_SUCCESS);
        info.dstMicromap = m;
        std::vector<uint8_t> scratch(sizes.buildScratchSize + 64);
        info.scratchData.hostAddress = scratch.data();
        EXPECT_EQ(buildMicromaps(device, VK_NULL_HANDLE, 1, &info), VK_SUCCESS);
        oracle::registerMicromap(m, oracle::decodeMicromap(info, uint32_t(in.triangles.size())));
        micromaps.push_back(m);
        return m;
    }
    void destroy(VkMicromapEXT m) {
        destroyMicromap(device, m, nullptr);
        micromaps.erase(std::find(micromaps.begin(), micromaps.end(), m));
    }

    // Random states for a triangle of that format and level; `bias` in [0, 1]: the share of transparent states.
    std::vector<uint8_t> randomStates(uint16_t format, uint16_t level, double bias) {
        std::vector<uint8_t> s(size_t(1) << (2 * level));
        for (auto& x : s) x = rng.coin(bias) ? 0 : uint8_t(format == k2State ? 1 : 1 + rng.below(3));
        return s;
    }
    uint16_t randomLevel() {
        const double r = rng.uniform(0, 1);
        return uint16_t(r < 0.15 ? 0 : r < 0.9 ? 1 + rng.below(5) : 6 + rng.below(4));
    }
    MicromapInput randomMicromap(uint32_t triangles) {
        MicromapInput in;
        const double bias = rng.uniform(0.1, 0.7);
        for (uint32_t i = 0; i < triangles; ++i) {
            const uint16_t format = rng.coin() ? k2State : k4State, level = randomLevel();
            in.add(format, level, randomStates(format, level, bias));
        }
        return in;
    }

    // Attaches to `g` an opacity micromap `m` (of `triangles` micromap triangles): a random index type, special
    // indices with probability `special`, a random baseTriangle; usage counts after indirection, as the spec says.
    GeometryOmm& attach(GeometryData& g, VkMicromapEXT m, const MicromapInput& in, double special,
                        VkIndexType forced = VK_INDEX_TYPE_MAX_ENUM) {
        const uint32_t n = g.range.primitiveCount, available = uint32_t(in.triangles.size());
        GeometryOmm& o = omms.emplace_back();
        const VkIndexType types[3] = {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32};
        o.info.indexType = forced != VK_INDEX_TYPE_MAX_ENUM ? forced : (available >= n ? types[rng.below(3)] : types[1 + rng.below(2)]);
        if (m == VK_NULL_HANDLE) o.info.indexType = rng.coin() ? VK_INDEX_TYPE_UINT16 : VK_INDEX_TYPE_UINT32;
        o.info.micromap = m;
        std::vector<int64_t> used(n);
        if (o.info.indexType == VK_INDEX_TYPE_NONE_KHR) {
            o.info.baseTriangle = rng.below(available - n + 1);
            for (uint32_t i = 0; i < n; ++i) used[i] = int64_t(i) + o.info.baseTriangle;
        } else {
            const uint32_t size = o.info.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
            o.info.indexStride = size * (1 + rng.below(3));
            o.info.baseTriangle = m ? rng.below(std::min(available, 8u)) : 0;
            o.indices.assign(size_t(n) * o.info.indexStride + 8, 0xAB);
            for (uint32_t i = 0; i < n; ++i) {
                int64_t value;
                if (!m || rng.coin(special)) {
                    value = -1 - int64_t(rng.below(4));  // a special index
                    used[i] = value;
                } else {
                    value = rng.below(available - o.info.baseTriangle);
                    used[i] = value + o.info.baseTriangle;
                }
                const uint32_t raw = uint32_t(value);  // the unsigned cast
                if (size == 2) {
                    const uint16_t r16 = uint16_t(raw);
                    std::memcpy(o.indices.data() + size_t(i) * o.info.indexStride, &r16, 2);
                } else {
                    std::memcpy(o.indices.data() + size_t(i) * o.info.indexStride, &raw, 4);
                }
            }
            o.info.indexBuffer.hostAddress = o.indices.data();
        }
        for (int64_t u : used) {
            if (u < 0) continue;
            const auto& t = in.triangles[size_t(u)];
            bool found = false;
            for (auto& x : o.usage)
                if (x.format == t.format && x.subdivisionLevel == t.subdivisionLevel) ++x.count, found = true;
            if (!found) o.usage.push_back({1, t.subdivisionLevel, t.format});
        }
        o.info.usageCountsCount = uint32_t(o.usage.size());
        o.info.pUsageCounts = o.usage.data();
        o.info.pNext = nullptr;
        g.geometry.geometry.triangles.pNext = &o.info;
        return o;
    }

    std::vector<oracle::Ray> raysFor(const AccelStruct* tlas, size_t n) {
        auto rays = randomRays(*tlas->scene, n / 2);
        auto targeted = targetedRays(*tlas->scene, n / 2);
        rays.insert(rays.end(), targeted.begin(), targeted.end());
        return rays;
    }

    // vkasTraceRays gives every ray the ray query's committed hit, bit for bit.
    void expectBatchEqualsQuery(const AccelStruct* tlas, const std::vector<oracle::Ray>& rays, uint32_t flags) {
        std::vector<VkasRay> batch(rays.size());
        for (size_t i = 0; i < rays.size(); ++i) {
            for (int k = 0; k < 3; ++k) batch[i].origin[k] = rays[i].origin[k], batch[i].direction[k] = rays[i].direction[k];
            batch[i].tMin = rays[i].tMin, batch[i].tMax = rays[i].tMax;
        }
        std::vector<VkasHit> out(rays.size());
        ASSERT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, flags, 0xFF, uint32_t(rays.size()),
                                batch.data(), out.data()),
                  VK_SUCCESS);
        size_t differ = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const Hit q = query(tlas->handle, rays[i], flags, 0xFF, Confirm::All).committed;
            const Hit b = fromBatch(out[i]);
            if (!identical(q, b) && ++differ <= 5)
                ADD_FAILURE() << "flags 0x" << std::hex << flags << std::dec << ": vkasTraceRays " << b.str()
                              << " but the ray query " << q.str() << " for " << describe(rays[i]) << ", seed " << seed;
        }
        EXPECT_EQ(differ, 0u);
    }
};

// ---- The mapping --------------------------------------------------------------------------------------------------

using opacity_micromap = OpacityMicromapTest;

TEST_F(opacity_micromap, micro_triangle_index_is_the_recursive_descent) {
    // Every micro-triangle's centroid at levels 0-7, and random points at every level up to 12.
    for (uint32_t level = 0; level <= 7; ++level) {
        const uint32_t n = 1u << level;
        std::vector<uint8_t> seen(size_t(n) * n, 0);
        for (uint32_t i = 0; i < n; ++i)
            for (uint32_t j = 0; i + j < n; ++j)
                for (int upper = 0; upper < 2 && (upper == 0 || i + j + 1 < n); ++upper) {
                    // The grid cell (i, j)'s lower triangle has centroid (i + 1/3, j + 1/3) / n; its upper one
                    // (i + 2/3, j + 2/3) / n.
                    const double cu = (i + (upper ? 2.0 : 1.0) / 3) / n, cv = (j + (upper ? 2.0 : 1.0) / 3) / n;
                    const uint32_t expected = oracle::microTriangleOf(cu, cv, level);
                    ASSERT_EQ(vkas::microTriangleIndex(float(cu), float(cv), level), expected)
                        << "level " << level << " cell " << i << "," << j << (upper ? " upper" : " lower");
                    ASSERT_LT(expected, n * n);
                    EXPECT_EQ(seen[expected]++, 0) << "level " << level << ": index " << expected << " twice";
                }
    }
    size_t compared = 0;
    for (int k = 0; k < 200000; ++k) {
        const uint32_t level = rng.below(13);
        float u = float(rng.uniform(0, 1)), v = float(rng.uniform(0, 1));
        if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
        double margin;
        const uint32_t expected = oracle::microTriangleOf(u, v, level, &margin);
        if (margin < 1e-6) continue;  // on a micro-edge: the float rule decides, tested below
        ++compared;
        ASSERT_EQ(vkas::microTriangleIndex(u, v, level), expected) << "level " << level << " u " << u << " v " << v
                                                                   << " seed " << seed;
    }
    EXPECT_GT(compared, 190000u);
}

// ---- Random scenes against the oracle ------------------------------------------------------------------------------

TEST_F(opacity_micromap, random_micromaps_match_the_oracle) {
    for (int scene = 0; scene < 6; ++scene) {
        SCOPED_TRACE("scene " + std::to_string(scene) + ", seed " + std::to_string(seed));
        // Two or three geometries: large triangles (a soup and a terrain), one with an opacity micromap each, one
        // possibly without; geometry flags random.
        std::vector<const GeometryData*> gs;
        const int count = 2 + int(rng.below(2));
        for (int g = 0; g < count; ++g) {
            const Mesh mesh = g == 1 ? terrain(6, rng) : triangleSoup(40 + int(rng.below(60)), rng, 0.8f);
            geometries.push_back(makeGeometry(mesh, VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
            GeometryData& gd = *geometries.back();
            if (g < 2 || rng.coin()) {
                const bool nullMicromap = rng.coin(0.1);
                const MicromapInput in = randomMicromap(gd.range.primitiveCount + 4 + rng.below(20));
                const VkMicromapEXT m = nullMicromap ? VK_NULL_HANDLE : buildMicromap(in);
                attach(gd, m, in, rng.uniform(0, 0.3));
            }
            gs.push_back(&gd);
        }
        BuildOptions opt;
        opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DISABLE_OPACITY_MICROMAPS_EXT;
        if (rng.coin()) opt.flags |= VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
        AccelStruct* blas = buildBlas(gs, opt);
        // Instances with every opacity-related flag under random transforms.
        std::vector<Instance> instances;
        const uint32_t flagSets[] = {0,
                                     VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                     VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR,
                                     VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_EXT,
                                     VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_EXT,
                                     VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_EXT |
                                         VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR,
                                     VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR};
        for (uint32_t k = 0; k < 7; ++k) {
            Instance inst;
            inst.blas = blas;
            inst.flags = flagSets[k];
            inst.transform = compose(translation(float(k) * 3.0f - 9.0f, 0, 0), randomTransform(rng, 0.5f, 2.0f, rng.coin(), 0.5f));
            instances.push_back(inst);
        }
        AccelStruct* tlas = buildTlas(instances);
        const auto rays = raysFor(tlas, 700);
        const uint32_t rayFlags[] = {0,
                                     VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE,
                                     VKAS_RAY_FLAG_OPAQUE,
                                     VKAS_RAY_FLAG_NO_OPAQUE,
                                     VKAS_RAY_FLAG_CULL_OPAQUE,
                                     VKAS_RAY_FLAG_CULL_NO_OPAQUE | VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE,
                                     VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES};
        const uint32_t flags = rayFlags[scene % 7];
        const uint32_t other = rayFlags[(scene + 3) % 7];
        checkRays(tlas, rays, flags);
        checkRays(tlas, rays, other);
        expectBatchEqualsQuery(tlas, rays, flags);
        expectBatchEqualsQuery(tlas, rays, other);
        if (HasFailure()) return;
    }
}

// ---- Special indices, exactly -------------------------------------------------------------------------------------

TEST_F(opacity_micromap, special_indices_follow_the_tables) {
    // One triangle per special index, each under its own instance; a ray at the centroid.
    struct Expect {
        int32_t special;
        int normal, forced;  // 0 ignored, 1 opaque, 2 non-opaque
    };
    const Expect table[] = {{-1, 0, 0}, {-2, 1, 1}, {-3, 2, 0}, {-4, 2, 1}};
    for (const Expect& e : table)
        for (int geometryOpaque = 0; geometryOpaque < 2; ++geometryOpaque)
            for (uint32_t instFlags : {0u, uint32_t(VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_EXT),
                                       uint32_t(VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_EXT),
                                       uint32_t(VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR)})
                for (uint32_t rayFlags : {0u, VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE, VKAS_RAY_FLAG_NO_OPAQUE}) {
                    SCOPED_TRACE("special " + std::to_string(e.special) + " opaque " + std::to_string(geometryOpaque) +
                                 " instance 0x" + std::to_string(instFlags) + " ray 0x" + std::to_string(rayFlags));
                    Mesh mesh;
                    mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
                    mesh.indices = {0, 1, 2};
                    geometries.push_back(
                        makeGeometry(mesh, VK_INDEX_TYPE_UINT32, geometryOpaque ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
                    GeometryOmm& o = omms.emplace_back();
                    o.info.indexType = VK_INDEX_TYPE_UINT32;
                    o.info.indexStride = 4;
                    o.indices.resize(4);
                    std::memcpy(o.indices.data(), &e.special, 4);
                    o.info.indexBuffer.hostAddress = o.indices.data();
                    geometries.back()->geometry.geometry.triangles.pNext = &o.info;
                    BuildOptions opt;
                    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DISABLE_OPACITY_MICROMAPS_EXT;
                    AccelStruct* blas = buildBlas(*geometries.back(), opt);
                    Instance inst;
                    inst.blas = blas;
                    inst.flags = instFlags;
                    AccelStruct* tlas = buildTlas({inst});
                    oracle::Ray ray;
                    ray.origin = {0, -0.3f, 2};
                    ray.direction = {0, 0, -1};
                    ray.tMax = 10;
                    // The expected outcome, written from the tables and the opacity rules.
                    int outcome;
                    if (instFlags & VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_EXT)
                        outcome = geometryOpaque ? 1 : 2;
                    else
                        outcome = (instFlags & VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_EXT) ||
                                          (rayFlags & VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE)
                                      ? e.forced
                                      : e.normal;
                    if (outcome != 0 && (instFlags & VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR)) outcome = 1;
                    if (outcome != 0 && (rayFlags & VKAS_RAY_FLAG_NO_OPAQUE)) outcome = 2;
                    const QueryTrace none = query(tlas->handle, ray, rayFlags, 0xFF, Confirm::None);
                    EXPECT_EQ(none.candidates.size(), outcome == 2 ? 1u : 0u);
                    EXPECT_EQ(none.committed.type,
                              outcome == 1 ? VKAS_COMMITTED_INTERSECTION_TRIANGLE : VKAS_COMMITTED_INTERSECTION_NONE);
                    const Hit all = traceClosest(tlas, ray, rayFlags);
                    EXPECT_EQ(all.type, outcome == 0 ? VKAS_COMMITTED_INTERSECTION_NONE : VKAS_COMMITTED_INTERSECTION_TRIANGLE);
                    checkRays(tlas, {ray}, rayFlags);
                    if (HasFailure()) return;
                }
}

// ---- Micro-edges ----------------------------------------------------------------------------------------------------

TEST_F(opacity_micromap, rays_on_micro_edges_are_decided_by_their_barycentrics) {
    // A 4-state micromap of opaque (1) and unknown (2) micro-triangles: every ray that meets the triangle is either
    // committed (opaque) or handed back (non-opaque), never dropped, and the state the reported barycentrics select
    // is the one that decided it. Rays through micro-vertices and micro-edge midpoints of levels 1-6.
    for (uint16_t level = 1; level <= 6; ++level) {
        SCOPED_TRACE("level " + std::to_string(level));
        std::vector<uint8_t> states(size_t(1) << (2 * level));
        for (auto& s : states) s = uint8_t(1 + rng.below(2));
        MicromapInput in;
        in.add(k4State, level, states);
        const VkMicromapEXT m = buildMicromap(in);
        Mesh mesh;
        mesh.positions = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
        mesh.indices = {0, 1, 2};
        geometries.push_back(makeGeometry(mesh, VK_INDEX_TYPE_UINT32));
        attach(*geometries.back(), m, in, 0.0, VK_INDEX_TYPE_NONE_KHR);
        AccelStruct* blas = buildBlas(*geometries.back());
        Instance inst;
        inst.blas = blas;
        AccelStruct* tlas = buildTlas({inst});
        const uint32_t n = 1u << level;
        size_t rays = 0;
        for (uint32_t i = 0; i <= 2 * n; ++i)
            for (uint32_t j = 0; i + j <= 2 * n; ++j) {
                const float u = float(i) / float(2 * n), v = float(j) / float(2 * n);
                if (u <= 0 || v <= 0 || u + v >= 1) continue;  // the triangle's own edges: the watertight rule's business
                oracle::Ray ray;
                ray.origin = {4 * u, 4 * v, 1};
                ray.direction = {0, 0, -1};
                ray.tMax = 10;
                ++rays;
                const QueryTrace q = query(tlas->handle, ray, 0, 0xFF, Confirm::None);
                const bool handedBack = q.candidates.size() == 1;
                const Hit& h = handedBack ? q.candidates[0] : q.committed;
                ASSERT_TRUE(handedBack != (q.committed.type == VKAS_COMMITTED_INTERSECTION_TRIANGLE))
                    << "the ray at (" << u << ", " << v << ") was dropped or decided twice";
                const uint32_t at = vkas::microTriangleIndex(h.bary[0], h.bary[1], level);
                EXPECT_EQ(states[at], handedBack ? 2 : 1) << "at (" << u << ", " << v << ")";
            }
        EXPECT_GT(rays, size_t(n) * n / 2);
    }
}

// ---- Lifetime, updates, copies ----------------------------------------------------------------------------------

TEST_F(opacity_micromap, the_micromap_may_be_destroyed_after_the_build) {
    geometries.push_back(makeGeometry(triangleSoup(80, rng, 0.8f), VK_INDEX_TYPE_UINT32));
    const MicromapInput in = randomMicromap(90);
    const VkMicromapEXT m = buildMicromap(in);
    attach(*geometries.back(), m, in, 0.1);
    AccelStruct* blas = buildBlas(*geometries.back());
    Instance inst;
    inst.blas = blas;
    AccelStruct* tlas = buildTlas({inst});
    destroy(m);  // "the micromap can be destroyed after the acceleration structure build concludes"
    const auto rays = raysFor(tlas, 600);
    checkRays(tlas, rays, 0);
    // The same inputs build the same bytes.
    const MicromapInput again = in;
    const VkMicromapEXT m2 = buildMicromap(again);
    omms.back().info.micromap = m2;
    AccelStruct* twin = buildBlas(*geometries.back());
    ASSERT_EQ(vkasGetDeviceProcAddr(device, "vkCmdBuildMicromapsEXT"), nullptr);
    EXPECT_EQ(std::memcmp(blas->data(), twin->data(), size_t(std::min(blas->size, twin->size))), 0);
}

TEST_F(opacity_micromap, updates_take_the_new_states) {
    for (VkBuildAccelerationStructureFlagsKHR updateFlag :
         {VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT),
          VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT)}) {
        SCOPED_TRACE("update flag 0x" + std::to_string(updateFlag));
        geometries.push_back(makeGeometry(triangleSoup(60, rng, 0.8f), VK_INDEX_TYPE_UINT32));
        GeometryData& gd = *geometries.back();
        const MicromapInput in = randomMicromap(60);
        attach(gd, buildMicromap(in), in, 0.1, VK_INDEX_TYPE_NONE_KHR);
        BuildOptions opt;
        opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR | updateFlag;
        AccelStruct* blas = buildBlas(gd, opt);
        // The same structure, other states (a data update) or other levels too (a full micromap update).
        MicromapInput next;
        for (const auto& t : in.triangles) {
            const uint16_t level = updateFlag == VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT
                                       ? uint16_t(std::min<int>(t.subdivisionLevel, 3))
                                       : t.subdivisionLevel;
            next.add(t.format, level, randomStates(t.format, level, 0.5));
        }
        const VkMicromapEXT m2 = buildMicromap(next);
        GeometryOmm& o = omms.back();
        o.info.micromap = m2;
        o.usage = next.usage;  // every triangle used once, in order
        o.info.usageCountsCount = uint32_t(o.usage.size());
        o.info.pUsageCounts = o.usage.data();
        auto pb = prepareBlas({&gd}, opt);
        pb->as = blas;
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = blas->handle;
        pb->info.dstAccelerationStructure = blas->handle;
        pb->info.scratchData.hostAddress = nullptr;
        submit({pb.get()});
        blas->blas = pb->blas;  // the oracle's view of the new inputs
        blasRegistry[blas->reference()] = pb->blas;
        Instance inst;
        inst.blas = blas;
        AccelStruct* tlas = buildTlas({inst});
        const auto rays = raysFor(tlas, 600);
        checkRays(tlas, rays, 0);
        checkRays(tlas, rays, VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE);
        if (HasFailure()) return;
    }
}

TEST_F(opacity_micromap, clones_compaction_and_serialization_keep_the_micromaps) {
    auto copyAs = reinterpret_cast<PFN_vkCopyAccelerationStructureKHR>(
        vkasGetDeviceProcAddr(device, "vkCopyAccelerationStructureKHR"));
    auto toMemory = reinterpret_cast<PFN_vkCopyAccelerationStructureToMemoryKHR>(
        vkasGetDeviceProcAddr(device, "vkCopyAccelerationStructureToMemoryKHR"));
    auto fromMemory = reinterpret_cast<PFN_vkCopyMemoryToAccelerationStructureKHR>(
        vkasGetDeviceProcAddr(device, "vkCopyMemoryToAccelerationStructureKHR"));
    auto properties = reinterpret_cast<PFN_vkWriteAccelerationStructuresPropertiesKHR>(
        vkasGetDeviceProcAddr(device, "vkWriteAccelerationStructuresPropertiesKHR"));
    geometries.push_back(makeGeometry(triangleSoup(100, rng, 0.8f), VK_INDEX_TYPE_UINT32));
    const MicromapInput in = randomMicromap(120);
    attach(*geometries.back(), buildMicromap(in), in, 0.2);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* blas = buildBlas(*geometries.back(), opt);
    VkDeviceSize sizes[2] = {};
    const VkAccelerationStructureKHR handles[1] = {blas->handle};
    ASSERT_EQ(properties(device, 1, handles, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, 8, &sizes[0], 8),
              VK_SUCCESS);
    ASSERT_EQ(properties(device, 1, handles, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR, 8, &sizes[1], 8),
              VK_SUCCESS);
    AccelStruct* compact = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sizes[0], {});
    VkCopyAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    ci.src = blas->handle;
    ci.dst = compact->handle;
    ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
    ASSERT_EQ(copyAs(device, VK_NULL_HANDLE, &ci), VK_SUCCESS);
    std::vector<uint64_t> blob(size_t(sizes[1] / 8 + 2));
    VkCopyAccelerationStructureToMemoryInfoKHR si{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    si.src = blas->handle;
    si.dst.hostAddress = blob.data();
    si.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    ASSERT_EQ(toMemory(device, VK_NULL_HANDLE, &si), VK_SUCCESS);
    AccelStruct* loaded = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    VkCopyMemoryToAccelerationStructureInfoKHR di{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    di.src.hostAddress = blob.data();
    di.dst = loaded->handle;
    di.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    ASSERT_EQ(fromMemory(device, VK_NULL_HANDLE, &di), VK_SUCCESS);
    for (AccelStruct* as : {compact, loaded}) {
        as->blas = blas->blas;
        blasRegistry[as->reference()] = blas->blas;
        Instance inst;
        inst.blas = as;
        AccelStruct* tlas = buildTlas({inst});
        checkRays(tlas, raysFor(tlas, 400), 0);
    }
    EXPECT_NE(reinterpret_cast<const vkas::format::Header*>(blas->data())->opacityOffset, 0u);
}

}  // namespace
