// CTS `ray_flags`: opacity (none, opaque, noopaque, cullopaque, cullnoopaque) x geometry opacity x instance FORCE_*,
// terminate_on_first_hit, face culling, skip_triangles; the confirmation semantics of ray queries (non-opaque
// candidates come back from Proceed and are committed only by ConfirmIntersection; candidate vs committed
// getters; Terminate) and the strict tMin < t < tMax rule for triangles.
#include <cmath>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {
constexpr uint32_t kOpacityFlags[5] = {0, VKAS_RAY_FLAG_OPAQUE, VKAS_RAY_FLAG_NO_OPAQUE, VKAS_RAY_FLAG_CULL_OPAQUE,
                                       VKAS_RAY_FLAG_CULL_NO_OPAQUE};
const char* kOpacityNames[5] = {"none", "opaque", "noopaque", "cullopaque", "cullnoopaque"};
constexpr uint32_t kInstanceOpacity[3] = {0, VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                          VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR};
const char* kInstanceOpacityNames[3] = {"noforce", "forceopaque", "forcenoopaque"};

// Horizontal square layers at z = 0, -1, -2, ... (one geometry each), so a ray from z = 1 straight down meets layer
// k at t = k + 1 exactly.
Mesh layer(float z) {
    Mesh m;
    m.positions = {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}
oracle::Ray downRay(float x, float y) {
    oracle::Ray r;
    r.origin = {x, y, 1.0f};
    r.direction = {0, 0, -1};
    r.tMin = 0;
    r.tMax = 100;
    return r;
}
}  // namespace

// ---- opacity ----------------------------------------------------------------------------------------------------
struct OpacityParam {
    int rayOpacity;
    bool geometryOpaque;
    int instanceOpacity;
};

class ray_flags_opacity : public VkasTest, public ::testing::WithParamInterface<OpacityParam> {};

TEST_P(ray_flags_opacity, triangles) {
    const OpacityParam& P = GetParam();
    const uint32_t rayFlags = kOpacityFlags[P.rayOpacity];
    auto g = makeGeometry(layer(0), VK_INDEX_TYPE_UINT32, P.geometryOpaque ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    AccelStruct* tlas = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, kInstanceOpacity[P.instanceOpacity], buildBlas(*g)}});
    // Expected opacity: geometry, then instance FORCE_*, then ray OPAQUE / NO_OPAQUE.
    bool opaque = P.geometryOpaque;
    if (P.instanceOpacity == 1) opaque = true;
    if (P.instanceOpacity == 2) opaque = false;
    if (rayFlags == VKAS_RAY_FLAG_OPAQUE) opaque = true;
    if (rayFlags == VKAS_RAY_FLAG_NO_OPAQUE) opaque = false;
    const bool culled = (rayFlags == VKAS_RAY_FLAG_CULL_OPAQUE && opaque) || (rayFlags == VKAS_RAY_FLAG_CULL_NO_OPAQUE && !opaque);
    for (int i = 0; i < 20; ++i) {
        const oracle::Ray r = downRay(rng.uniformf(-0.9f, 0.9f), rng.uniformf(-0.9f, 0.9f));
        const QueryTrace all = query(tlas->handle, r, rayFlags, 0xFF, Confirm::All);
        EXPECT_EQ(all.problems, "");
        EXPECT_EQ(all.candidates.size(), size_t(!culled && !opaque ? 1 : 0))
            << "non-opaque candidates (only) come back from Proceed";
        EXPECT_EQ(all.committed.type, culled ? 0u : 1u);
        const QueryTrace none = query(tlas->handle, r, rayFlags, 0xFF, Confirm::None);
        EXPECT_EQ(none.committed.type, !culled && opaque ? 1u : 0u) << "opaque hits commit without confirmation";
        checkRays(tlas, {r}, rayFlags);
    }
}

INSTANTIATE_TEST_SUITE_P(cpu_built, ray_flags_opacity, ::testing::ValuesIn([] {
                             std::vector<OpacityParam> v;
                             for (int r = 0; r < 5; ++r)
                                 for (bool g : {false, true})
                                     for (int i = 0; i < 3; ++i) v.push_back({r, g, i});
                             return v;
                         }()),
                         [](const auto& info) {
                             const auto& p = info.param;
                             return std::string(kOpacityNames[p.rayOpacity]) + (p.geometryOpaque ? "_opaquegeometry" : "_noopaquegeometry") +
                                    "_" + kInstanceOpacityNames[p.instanceOpacity];
                         });

// ---- all flag combinations against the oracle on a random scene ----------------------------------------------------
class ray_flags : public VkasTest, public ::testing::WithParamInterface<uint32_t> {
  protected:
    AccelStruct* randomScene() {
        geoms_.push_back(makeGeometry(terrain(12, rng), VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR));
        geoms_.push_back(makeGeometry(triangleSoup(200, rng, 0.25f), VK_INDEX_TYPE_NONE_KHR));
        geoms_.push_back(makeGeometry(icosphere(2), VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        AccelStruct* a = buildBlas(*geoms_[0]);
        AccelStruct* b = buildBlas(std::vector<const GeometryData*>{geoms_[1].get(), geoms_[2].get()});
        std::vector<Instance> instances;
        const uint32_t instanceFlags[8] = {0, 1, 2, 3, 4, 8, 4 | 1, 8 | 2};
        for (int i = 0; i < 8; ++i) {
            Instance inst;
            inst.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 1.5f);
            inst.flags = instanceFlags[rng.below(8)];
            inst.blas = i % 2 ? a : b;
            instances.push_back(inst);
        }
        return buildTlas(instances);
    }
    std::vector<std::unique_ptr<GeometryData>> geoms_;
};

TEST_P(ray_flags, random_scene) {
    const uint32_t flags = GetParam() | (rng.coin() ? VKAS_RAY_FLAG_SKIP_CLOSEST_HIT_SHADER : 0);
    AccelStruct* tlas = randomScene();
    auto rays = randomRays(*tlas->scene, 200);
    const auto t = targetedRays(*tlas->scene, 100);
    rays.insert(rays.end(), t.begin(), t.end());
    const size_t hits = checkRays(tlas, rays, flags);
    if (flags & VKAS_RAY_FLAG_SKIP_TRIANGLES) {
        EXPECT_EQ(hits, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(cpu_built, ray_flags, ::testing::ValuesIn([] {
                             std::vector<uint32_t> v;
                             for (uint32_t o : kOpacityFlags)
                                 for (uint32_t f : {0u, uint32_t(VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES),
                                                    uint32_t(VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES),
                                                    uint32_t(VKAS_RAY_FLAG_SKIP_TRIANGLES)})
                                     for (uint32_t t : {0u, uint32_t(VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT)}) v.push_back(o | f | t);
                             return v;
                         }()),
                         [](const auto& info) {
                             const uint32_t f = info.param;
                             std::string n;
                             for (int i = 0; i < 5; ++i)
                                 if (f & 0xC3u ? (f & 0xC3u) == kOpacityFlags[i] : i == 0) n += kOpacityNames[i];
                             if (f & VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES) n += "_cullbackfacingtriangles";
                             if (f & VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES) n += "_cullfrontfacingtriangles";
                             if (f & VKAS_RAY_FLAG_SKIP_TRIANGLES) n += "_skiptriangles";
                             if (f & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT) n += "_terminateonfirsthit";
                             return n;
                         });

// ---- confirmation, termination, t bounds ------------------------------------------------------------------------
class ray_flags_query : public VkasTest {
  protected:
    // Three non-opaque layers at t = 1, 2, 3 and, optionally, an opaque one at t = 4.
    AccelStruct* layers(bool opaqueLast) {
        for (int k = 0; k < 4; ++k)
            geoms_.push_back(makeGeometry(layer(-float(k)), VK_INDEX_TYPE_UINT16,
                                          k == 3 && opaqueLast ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        std::vector<const GeometryData*> gp;
        for (int k = 0; k < (opaqueLast ? 4 : 3); ++k) gp.push_back(geoms_[geoms_.size() - 4 + k].get());
        return buildTlas({Instance{identityTransform(), 5, 0xFF, 9, 0, buildBlas(gp)}});
    }
    std::vector<std::unique_ptr<GeometryData>> geoms_;
};

TEST_F(ray_flags_query, confirmation) {
    AccelStruct* tlas = layers(false);
    for (int confirmLayer = -1; confirmLayer < 3; ++confirmLayer) {
        SCOPED_TRACE("confirming layer " + std::to_string(confirmLayer));
        const oracle::Ray r = downRay(rng.uniformf(-0.9f, 0.9f), rng.uniformf(-0.9f, 0.9f));
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
        std::vector<int> seen;
        bool committedSomething = false;
        float committedT = 0;
        while (vkasRayQueryProceed(&q)) {
            ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_FALSE), VKAS_CANDIDATE_INTERSECTION_TRIANGLE);
            const Hit c = readHit(q, false);
            ASSERT_GE(c.geometryIndex, 0);
            ASSERT_LT(c.geometryIndex, 3);
            EXPECT_NEAR(c.t, float(c.geometryIndex + 1), 1e-5f) << "layer k is at t = k + 1; got " << std::hexfloat << c.t << std::defaultfloat << " " << describe(r);
            EXPECT_EQ(c.customIndex, 5);
            EXPECT_EQ(c.sbtOffset, 9u);
            EXPECT_TRUE(c.frontFace);
            const float b0 = c.bary[0], b1 = c.bary[1];
            EXPECT_TRUE(b0 >= 0 && b1 >= 0 && b0 + b1 <= 1.0f + 1e-6f) << c.str();
            seen.push_back(c.geometryIndex);
            // Before confirmation the committed values are untouched.
            const Hit before = readHit(q, true);
            EXPECT_EQ(before.type, committedSomething ? 1u : 0u);
            if (committedSomething) {
                EXPECT_EQ(before.t, committedT);
                EXPECT_LT(c.t, committedT) << "candidates beyond the committed hit must not be returned";
            }
            if (c.geometryIndex == confirmLayer) {
                vkasRayQueryConfirmIntersection(&q);
                committedSomething = true;
                committedT = c.t;
                const Hit after = readHit(q, true);
                EXPECT_TRUE(identical([&] { Hit x = c; x.type = 1; return x; }(), after)) << after.str() << " vs " << c.str();
            }
        }
        // Each layer whose t is below the committed t (or every layer) came exactly once.
        std::sort(seen.begin(), seen.end());
        const std::vector<int> unique(seen.begin(), std::unique(seen.begin(), seen.end()));
        EXPECT_EQ(unique.size(), seen.size()) << "a candidate came back twice";
        EXPECT_TRUE(std::find(seen.begin(), seen.end(), 0) != seen.end()) << "the nearest layer is always a candidate";
        const Hit final = readHit(q, true);
        if (confirmLayer < 0) {
            EXPECT_EQ(final.type, VKAS_COMMITTED_INTERSECTION_NONE) << "nothing confirmed: nothing committed";
        } else {
            EXPECT_EQ(final.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE);
            EXPECT_EQ(final.geometryIndex, confirmLayer);
            EXPECT_NEAR(final.t, float(confirmLayer + 1), 1e-5f);
        }
    }
}

TEST_F(ray_flags_query, terminate) {
    AccelStruct* tlas = layers(true);
    const oracle::Ray r = downRay(0.3f, -0.2f);
    // Terminate() right after the first candidate: Proceed returns false, nothing committed.
    {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
        ASSERT_TRUE(vkasRayQueryProceed(&q));
        vkasRayQueryTerminate(&q);
        EXPECT_FALSE(vkasRayQueryProceed(&q));
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
    }
    // Confirm then Terminate(): the confirmed candidate stays committed.
    {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
        ASSERT_TRUE(vkasRayQueryProceed(&q));
        const Hit c = readHit(q, false);
        vkasRayQueryConfirmIntersection(&q);
        vkasRayQueryTerminate(&q);
        EXPECT_FALSE(vkasRayQueryProceed(&q));
        const Hit h = readHit(q, true);
        EXPECT_EQ(h.type, 1u);
        EXPECT_EQ(h.geometryIndex, c.geometryIndex);
        EXPECT_EQ(h.t, c.t);
    }
    // TerminateOnFirstHit: the first confirmed candidate ends traversal.
    {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT, 0xFF, r.origin.data(), r.tMin,
                               r.direction.data(), r.tMax);
        int n = 0;
        while (vkasRayQueryProceed(&q)) {
            ++n;
            vkasRayQueryConfirmIntersection(&q);
        }
        EXPECT_LE(n, 1) << "after the first confirmation traversal must end";
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), 1u);
    }
    // TerminateOnFirstHit with only the opaque layer visible (the others culled): it commits without Proceed
    // returning true.
    {
        const QueryTrace tr = query(tlas->handle, r, VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT | VKAS_RAY_FLAG_CULL_NO_OPAQUE, 0xFF);
        EXPECT_EQ(tr.candidates.size(), 0u);
        EXPECT_EQ(tr.committed.type, 1u);
        EXPECT_EQ(tr.committed.geometryIndex, 3);
        EXPECT_NEAR(tr.committed.t, 4.0f, 1e-5f);
    }
    // Without confirmation, every non-opaque layer before the opaque one is a candidate; the opaque one commits.
    {
        const QueryTrace tr = query(tlas->handle, r, 0, 0xFF, Confirm::None);
        EXPECT_EQ(tr.problems, "");
        EXPECT_EQ(tr.committed.type, 1u);
        EXPECT_EQ(tr.committed.geometryIndex, 3);
        // All three non-opaque layers lie before the opaque one, so each comes back exactly once.
        EXPECT_EQ(tr.candidates.size(), 3u);
    }
}

TEST_F(ray_flags_query, t_bounds_are_strict_for_triangles) {
    // A triangle at t = 1 exactly (all values exactly representable).
    AccelStruct* tlas = layers(false);
    const oracle::Ray base = downRay(0.25f, 0.5f);
    auto firstT = [&](float tMin, float tMax) {
        oracle::Ray r = base;
        r.tMin = tMin;
        r.tMax = tMax;
        Hit h = traceClosest(tlas, r);
        return h.type ? h.t : -1.0f;
    };
    EXPECT_EQ(firstT(0.0f, 1.0f), -1.0f) << "t == tMax is not a candidate";
    EXPECT_EQ(firstT(0.5f, std::nextafter(1.0f, 2.0f)), 1.0f);
    EXPECT_EQ(firstT(1.0f, 1.5f), -1.0f) << "t == tMin is not a candidate";
    EXPECT_EQ(firstT(std::nextafter(1.0f, 0.0f), 1.5f), 1.0f);
    EXPECT_EQ(firstT(1.0f, 2.0f), -1.0f) << "both layers at the bounds";
    EXPECT_EQ(firstT(1.0f, std::nextafter(2.0f, 3.0f)), 2.0f);
    EXPECT_EQ(firstT(0.0f, std::numeric_limits<float>::infinity()), 1.0f);
    EXPECT_EQ(firstT(5.0f, 5.0f), -1.0f);
}

TEST_F(ray_flags_query, skip_triangles) {
    AccelStruct* tlas = layers(true);
    for (uint32_t extra : {0u, uint32_t(VKAS_RAY_FLAG_OPAQUE), uint32_t(VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT)}) {
        VkasRayQuery q;
        const oracle::Ray r = downRay(0.1f, 0.1f);
        vkasRayQueryInitialize(&q, tlas->handle, VKAS_RAY_FLAG_SKIP_TRIANGLES | extra, 0xFF, r.origin.data(), r.tMin,
                               r.direction.data(), r.tMax);
        EXPECT_FALSE(vkasRayQueryProceed(&q));
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
    }
}
