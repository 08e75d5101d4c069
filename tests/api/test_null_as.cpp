// CTS `null_as`: a null top-level structure is a valid "nothing": every ray misses, for queries and batches.
#include <cstring>

#include "meshes.hpp"

using namespace vt;

using null_as = VkasTest;

TEST_F(null_as, ray_query) {
    const auto rays = randomRays(oracle::Scene{}, 50);
    for (uint32_t flags : {0u, uint32_t(VKAS_RAY_FLAG_OPAQUE), uint32_t(VKAS_RAY_FLAG_NO_OPAQUE),
                           uint32_t(VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT), uint32_t(VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES)}) {
        for (const auto& r : rays) {
            VkasRayQuery q;
            std::memset(&q, 0xAA, sizeof q);
            vkasRayQueryInitialize(&q, VK_NULL_HANDLE, flags, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
            EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
            EXPECT_FALSE(vkasRayQueryProceed(&q));
            EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
            EXPECT_EQ(vkasRayQueryGetRayFlags(&q), flags);
            EXPECT_EQ(vkasRayQueryGetRayTMin(&q), r.tMin);
        }
    }
}

TEST_F(null_as, trace_rays) {
    const auto rays = randomRays(oracle::Scene{}, 300);
    EXPECT_EQ(checkRays(nullptr, rays), 0u);  // query loop + vkasTraceRays (closest and any-hit)
}

TEST_F(null_as, mixed_with_real_structure) {
    // Rays that hit a real structure still miss through the null one, alternating (mixed_dispatches).
    auto g = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT16);
    AccelStruct* tlas = buildSingleInstanceTlas(buildBlas(*g));
    const auto rays = targetedRays(*tlas->scene, 50);
    for (const auto& r : rays) {
        EXPECT_EQ(traceClosest(tlas, r).type, VKAS_COMMITTED_INTERSECTION_TRIANGLE);
        EXPECT_EQ(traceClosest(nullptr, r).type, VKAS_COMMITTED_INTERSECTION_NONE);
    }
    checkRays(tlas, rays);
    checkRays(nullptr, rays);
}
