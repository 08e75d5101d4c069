// CTS `instance_index`: instance custom index (24 bits), instance id (inactive instances count), SBT record offset
// (24 bits), geometry index and primitive index, for candidates and committed hits, plus the object-space getters.
#include <cmath>

#include "meshes.hpp"

using namespace vt;

class instance_index : public VkasTest, public ::testing::WithParamInterface<VkIndexType> {};

TEST_P(instance_index, cpu_built) {
    // BLAS: 5 geometries, each a row of 4 quads (8 triangles) placed by a geometry transform at y = 1.5 g.
    const Mesh row = grid(4, 1);
    std::vector<std::unique_ptr<GeometryData>> geoms;
    std::vector<VkTransformMatrixKHR> geomXf;
    for (int gi = 0; gi < 5; ++gi) {
        geomXf.push_back(translation(0, 1.5f * gi, 0));
        geoms.push_back(makeGeometry(row, GetParam(), gi % 2 ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0, &geomXf.back()));
    }
    std::vector<const GeometryData*> gp;
    for (auto& g : geoms) gp.push_back(g.get());
    AccelStruct* blas = buildBlas(gp);
    // Instances: random 24-bit values (including the extremes), random transforms, some inactive.
    std::vector<Instance> instances;
    for (int i = 0; i < 60; ++i) {
        Instance inst;
        inst.transform = compose(randomTransform(rng, 0.5f, 2.0f, rng.coin(), 0.0f), translation(0, 0, 0));
        inst.transform.matrix[0][3] = 40.0f * float(i);  // far enough apart never to overlap
        inst.customIndex = i == 1 ? 0xFFFFFFu : i == 2 ? 0 : rng.u32() & 0xFFFFFFu;
        inst.sbtOffset = i == 1 ? 0xFFFFFFu : i == 2 ? 0 : rng.u32() & 0xFFFFFFu;
        inst.mask = 0x80 | (rng.u32() & 0x7F);
        inst.flags = rng.coin() ? VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR : 0;
        inst.blas = rng.coin(0.2) ? nullptr : blas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances);
    const oracle::Scene& scene = *tlas->scene;

    std::vector<oracle::Ray> rays;
    for (int i = 0; i < 60; ++i) {
        for (int n = 0; n < 6; ++n) {
            const int gi = int(rng.below(5)), quad = int(rng.below(4)), upper = int(rng.below(2));
            // Object-space point inside triangle 2 quad + upper of geometry gi.
            const float a = rng.uniformf(0.05f, 0.45f), b = rng.uniformf(0.55f, 0.95f);
            const float x = float(quad) + (upper ? a : b), y = 1.5f * float(gi) + (upper ? b : a);
            const Float3 o = transformPoint(instances[i].transform, {x, y, 1.0f});
            const Float3 e = transformPoint(instances[i].transform, {x, y, -1.0f});
            oracle::Ray r;
            r.origin = o;
            r.direction = {e[0] - o[0], e[1] - o[1], e[2] - o[2]};
            r.tMin = 0;
            r.tMax = 1;
            rays.push_back(r);
            const bool active = instances[i].blas != nullptr;
            const bool opaque = gi % 2;
            VkasRayQuery q;
            vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
            auto checkIds = [&](bool committed) {
                const Hit h = readHit(q, committed);
                EXPECT_EQ(h.instanceId, i) << (committed ? "committed" : "candidate");
                EXPECT_EQ(h.customIndex, int32_t(instances[i].customIndex));
                EXPECT_EQ(h.sbtOffset, instances[i].sbtOffset);
                EXPECT_EQ(h.geometryIndex, gi);
                EXPECT_EQ(h.primitiveIndex, 2 * quad + upper);
                // Object-space getters against the oracle's instance transform.
                const VkBool32 c = committed ? VK_TRUE : VK_FALSE;
                float o2w[3][4], w2o[3][4], oo[3], od[3];
                vkasRayQueryGetIntersectionObjectToWorld(&q, c, o2w);
                vkasRayQueryGetIntersectionWorldToObject(&q, c, w2o);
                vkasRayQueryGetIntersectionObjectRayOrigin(&q, c, oo);
                vkasRayQueryGetIntersectionObjectRayDirection(&q, c, od);
                const auto& inst = scene.instances[i];
                for (int rr = 0; rr < 3; ++rr) {
                    for (int k = 0; k < 4; ++k) {
                        EXPECT_EQ(o2w[rr][k], instances[i].transform.matrix[rr][k]) << "ObjectToWorld[" << rr << "][" << k << "]";
                        EXPECT_NEAR(w2o[rr][k], inst.toObject[rr][k], 1e-5 * (1 + std::fabs(inst.toObject[rr][k])))
                            << "WorldToObject[" << rr << "][" << k << "]";
                    }
                    double expO = inst.toObject[rr][3], expD = 0;
                    for (int k = 0; k < 3; ++k) {
                        expO += inst.toObject[rr][k] * r.origin[k];
                        expD += inst.toObject[rr][k] * r.direction[k];
                    }
                    EXPECT_NEAR(oo[rr], expO, 1e-4 * (1 + std::fabs(r.origin[0]) + std::fabs(r.origin[1]) + std::fabs(r.origin[2])));
                    EXPECT_NEAR(od[rr], expD, 1e-5 * (1 + std::fabs(expD)));
                }
            };
            int candidates = 0;
            while (vkasRayQueryProceed(&q)) {
                ++candidates;
                EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_FALSE), VKAS_CANDIDATE_INTERSECTION_TRIANGLE);
                checkIds(false);
                vkasRayQueryConfirmIntersection(&q);
            }
            EXPECT_EQ(candidates, active && !opaque ? 1 : 0);
            ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), active ? 1u : 0u) << "instance " << i;
            if (active) checkIds(true);
            if (HasFailure()) return;
        }
    }
    checkRays(tlas, rays);
    checkRays(tlas, randomRays(scene, 200));
}

INSTANTIATE_TEST_SUITE_P(cpu_built, instance_index,
                         ::testing::Values(VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32),
                         [](const auto& info) {
                             return std::string(info.param == VK_INDEX_TYPE_NONE_KHR ? "index_none"
                                                : info.param == VK_INDEX_TYPE_UINT16 ? "index_uint16"
                                                                                     : "index_uint32");
                         });
