// vkasTraceRays's batch kernel (engine/trace_kernel.*) against the ray query run to completion: the kernel must
// give bit for bit what the query gives when every triangle candidate is confirmed (type, t, ids, barycentrics,
// facing), ties between coincident triangles included, for every ray flag, instance flag, mask and build flag, and
// for closest-hit and any-hit (TerminateOnFirstHit) mode. CTest runs this group twice: with the CPU's best kernel
// and with VKAS_TRACE_KERNEL=sse2 (the baseline), so both instruction sets are held to the query.
#include <iterator>
#include <limits>

#include "api/validate/ray.hpp"

#include "meshes.hpp"

using namespace vt;

namespace {

constexpr uint32_t kRayFlagChoices[] = {
    0,
    VKAS_RAY_FLAG_OPAQUE,
    VKAS_RAY_FLAG_NO_OPAQUE,
    VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES,
    VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES,
    VKAS_RAY_FLAG_CULL_OPAQUE,
    VKAS_RAY_FLAG_CULL_NO_OPAQUE,
    VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT,
    VKAS_RAY_FLAG_SKIP_TRIANGLES,
    VKAS_RAY_FLAG_NO_OPAQUE | VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES,
};

constexpr uint32_t kInstanceFlagChoices[] = {
    0,
    VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR,
    VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR,
    VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
    VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR,
};

// A triangle soup in which some triangles appear twice (same vertices: the same t to the last bit) and some
// twice with the opposite winding, so that closest hits tie and only the traversal order decides.
Mesh soupWithTies(Rng& rng) {
    Mesh m = triangleSoup(600, rng, 0.2f);
    const size_t n = m.triangleCount();
    for (size_t k = 0; k < 150; ++k) {
        const size_t t = rng.u32() % n;
        const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        if (rng.coin())
            m.indices.insert(m.indices.end(), {a, b, c});
        else
            m.indices.insert(m.indices.end(), {a, c, b});
    }
    return m;
}

VkasRay toBatch(const oracle::Ray& r) {
    VkasRay b{};
    for (int k = 0; k < 3; ++k) b.origin[k] = r.origin[k], b.direction[k] = r.direction[k];
    b.tMin = r.tMin;
    b.tMax = r.tMax;
    return b;
}

}  // namespace

struct BatchParam {
    int build;  // 0 default, 1 fast_trace, 2 fast_build
    bool manyInstances;
};

class batch_trace : public VkasTest, public ::testing::WithParamInterface<BatchParam> {};

TEST_P(batch_trace, matches_ray_query) {
    const VkBuildAccelerationStructureFlagsKHR buildFlags[3] = {
        0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
        VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR};
    BuildOptions opt;
    opt.flags = buildFlags[GetParam().build];
    auto soup = makeGeometry(soupWithTies(rng), VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    auto sphere = makeGeometry(icosphere(3), VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* soupBlas = buildBlas(*soup, opt);
    AccelStruct* sphereBlas = buildBlas(*sphere, opt);
    std::vector<Instance> instances;
    const int count = GetParam().manyInstances ? 12 : 1;
    for (int i = 0; i < count; ++i) {
        Instance inst;
        if (count > 1) {
            inst.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 1.5f);
            inst.customIndex = rng.u32() & 0xFFFFFF;
            inst.sbtOffset = rng.u32() & 0xFFFFFF;
            inst.mask = rng.u32() & 0xFF;
            inst.flags = kInstanceFlagChoices[rng.u32() % std::size(kInstanceFlagChoices)];
        }
        inst.blas = i % 3 == 2 ? sphereBlas : soupBlas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances, opt);
    auto rays = randomRays(*tlas->scene, 300);
    const auto targeted = targetedRays(*tlas->scene, 200);
    rays.insert(rays.end(), targeted.begin(), targeted.end());

    size_t hits = 0;
    for (int pass = 0; pass < 6; ++pass) {
        // Pass 0 culls nothing, so the hit count below cannot fail on the luck of the draw (seed
        // 17002106594184038196 drew CULL_OPAQUE or SKIP_TRIANGLES for all six passes over an opaque soup: no hits).
        const uint32_t flags = pass == 0 ? 0u : kRayFlagChoices[rng.u32() % std::size(kRayFlagChoices)];
        const uint32_t cullMask = pass == 0 ? 0xFF : rng.u32() & 0xFF;
        std::vector<VkasRay> batch;
        for (const auto& r : rays) batch.push_back(toBatch(r));
        for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
            std::vector<VkasHit> out(rays.size());
            ASSERT_EQ(vkasTraceRays(device, tlas->handle, mode, flags, cullMask, uint32_t(rays.size()), batch.data(),
                                    out.data()),
                      VK_SUCCESS);
            const uint32_t queryFlags = flags | (mode == VKAS_TRACE_MODE_ANY_HIT ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0);
            for (size_t i = 0; i < rays.size(); ++i) {
                const QueryTrace q = query(tlas->handle, rays[i], queryFlags, cullMask, Confirm::All);
                const Hit got = fromBatch(out[i]);
                hits += q.committed.type != 0;
                EXPECT_TRUE(identical(q.committed, got))
                    << "ray " << i << " " << describe(rays[i]) << " flags 0x" << std::hex << flags << " mask 0x"
                    << cullMask << std::dec << " mode " << int(mode) << ": query " << q.committed.str() << ", batch "
                    << got.str();
            }
        }
    }
    EXPECT_GT(hits, rays.size());  // the rays do meet the scene
}

// Camera rays (an image, row by row, from one eye): the batch traces them as packets (engine/trace/packet_gather.hpp),
// and each must still get the ray query's hit, ties included.
TEST_P(batch_trace, camera_rays_match_ray_query) {
    const VkBuildAccelerationStructureFlagsKHR buildFlags[3] = {
        0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
        VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR};
    BuildOptions opt;
    opt.flags = buildFlags[GetParam().build];
    auto soup = makeGeometry(soupWithTies(rng), VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    auto knot = makeGeometry(torusKnot(80, 10), VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* soupBlas = buildBlas(*soup, opt);
    AccelStruct* knotBlas = buildBlas(*knot, opt);
    std::vector<Instance> instances;
    const int count = GetParam().manyInstances ? 12 : 1;
    for (int i = 0; i < count; ++i) {
        Instance inst;
        if (count > 1) {
            inst.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 1.5f);
            inst.mask = rng.u32() & 0xFF;
            inst.flags = kInstanceFlagChoices[rng.u32() % std::size(kInstanceFlagChoices)];
        }
        inst.blas = i % 2 ? knotBlas : soupBlas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances, opt);
    size_t hits = 0;
    for (int pass = 0; pass < 4; ++pass) {
        const uint32_t flags = pass == 0 ? 0u : kRayFlagChoices[rng.u32() % std::size(kRayFlagChoices)];
        const uint32_t cullMask = pass == 0 ? 0xFF : rng.u32() & 0xFF;
        const float eye[3] = {rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(3, 5)};
        const uint32_t side = 64;
        std::vector<oracle::Ray> rays;
        for (uint32_t y = 0; y < side; ++y)
            for (uint32_t x = 0; x < side; ++x) {
                oracle::Ray r;
                const float sx = 0.15f * (2.0f * (x + 0.5f) / side - 1.0f), sy = 0.15f * (1.0f - 2.0f * (y + 0.5f) / side);
                // (pixels 0.0047 apart: runs of 8 are within the gather's 0.05 and become packets)
                for (int a = 0; a < 3; ++a) r.origin[a] = eye[a];
                r.direction = {sx - 0.1f * eye[0], sy - 0.1f * eye[1], -1.0f};
                r.tMin = 0.0f;
                r.tMax = INFINITY;
                rays.push_back(r);
            }
        std::vector<VkasRay> batch;
        for (const auto& r : rays) batch.push_back(toBatch(r));
        for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
            std::vector<VkasHit> out(rays.size());
            ASSERT_EQ(vkasTraceRays(device, tlas->handle, mode, flags, cullMask, uint32_t(rays.size()), batch.data(),
                                    out.data()),
                      VK_SUCCESS);
            const uint32_t queryFlags = flags | (mode == VKAS_TRACE_MODE_ANY_HIT ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0);
            for (size_t i = 0; i < rays.size(); ++i) {
                const QueryTrace q = query(tlas->handle, rays[i], queryFlags, cullMask, Confirm::All);
                const Hit got = fromBatch(out[i]);
                hits += q.committed.type != 0;
                ASSERT_TRUE(identical(q.committed, got))
                    << "ray " << i << " " << describe(rays[i]) << " flags 0x" << std::hex << flags << " mask 0x"
                    << cullMask << std::dec << " mode " << int(mode) << ": query " << q.committed.str() << ", batch "
                    << got.str();
            }
        }
    }
    EXPECT_GT(hits, 400u);  // pass 0 culls nothing and the image looks at the scene
}

const BatchParam kBatchParams[] = {{0, false}, {0, true}, {1, true}, {2, false}, {2, true}};

std::string batchParamName(const ::testing::TestParamInfo<BatchParam>& info) {
    static const char* const kBuilds[3] = {"default", "fast_trace", "fast_build"};
    return std::string(kBuilds[info.param.build]) + (info.param.manyInstances ? "_instances" : "_single");
}

INSTANTIATE_TEST_SUITE_P(cpu, batch_trace, ::testing::ValuesIn(kBatchParams), batchParamName);

// The quick checks of a ray (rayValuesValid: the batch's vector one, the query's scalar one) give rayValueRules'
// verdict for every ray: each component
// drawn from ordinary values, zeros of both signs, negatives, infinities, NaN and denormals.
TEST(batch_trace_ray_rules, vector_check_equals_the_rules) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const float values[] = {0.0f, -0.0f, 1.0f, -1.0f, 2.5f, inf, -inf, nan, -nan,
                            std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                            std::numeric_limits<float>::max(), 1e-20f};
    const uint64_t seed = vt::chooseSeed();
    std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
    vt::Rng rng{seed};
    uint64_t valid = 0;
    for (int iter = 0; iter < 500000; ++iter) {
        VkasRay r;
        float* f = &r.origin[0];
        for (int i = 0; i < 8; ++i) {
            // Mostly valid values, so that every single broken component is met alone as well as together.
            f[i] = rng.coin(0.8) ? rng.uniformf(0.0f, 10.0f) : values[rng.below(uint32_t(std::size(values)))];
        }
        const bool expected = vkas::rayValueRules(r.origin, r.tMin, r.direction, r.tMax).all();
        ASSERT_EQ(vkas::rayValuesValid(r.origin, r.tMin, r.direction, r.tMax), expected)
            << "iteration " << iter << " (the scalar check)";
        ASSERT_EQ(vkas::rayValuesValid(r), expected)
            << "iteration " << iter << ": origin " << r.origin[0] << " " << r.origin[1] << " " << r.origin[2]
            << " tMin " << r.tMin << " direction " << r.direction[0] << " " << r.direction[1] << " "
            << r.direction[2] << " tMax " << r.tMax;
        valid += expected;
    }
    EXPECT_GT(valid, 1000u);  // both verdicts met
}

// A batch's ray rules (api/validate/ray.hpp): a valid ray is checked without a message being built (issue 36), an
// invalid one is reported with its index, each broken rule once, at most 8 messages a call, and nothing is traced.
class batch_trace_rules : public VkasTest {};

TEST_F(batch_trace_rules, each_broken_ray_is_named_by_its_index) {
    Mesh m = triangleSoup(50, rng, 0.2f);
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* tlas = buildSingleInstanceTlas(buildBlas(*g));
    std::vector<VkasRay> rays(1000);
    for (VkasRay& r : rays) r = VkasRay{{0, 0, -5}, 0.0f, {0, 0, 1}, 100.0f};
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    rays[3].origin[1] = nan;     // 06348
    rays[17].direction[2] = inf;  // 06348
    rays[400].tMin = nan;         // 06351
    rays[401].tMax = -1.0f;       // 06349 (and 06350: tMin 0 > tMax -1)
    rays[999].tMin = 200.0f;      // 06350
    std::vector<VkasHit> hits(rays.size());
    EXPECT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                            rays.data(), hits.data()),
              VK_ERROR_VALIDATION_FAILED_EXT);
    const std::vector<std::string> errors = takeValidationErrors();
    const std::vector<std::pair<const char*, const char*>> expected = {
        {"pRays[3]: the ray origin", "06348"},     {"pRays[17]: the ray direction", "06348"},
        {"pRays[400]: RayTmin nan", "06351"},      {"pRays[401]: RayTmin 0 and RayTmax -1", "06349"},
        {"pRays[401]: RayTmin 0 is greater", "06350"}, {"pRays[999]: RayTmin 200 is greater", "06350"}};
    ASSERT_EQ(errors.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_NE(errors[i].find(expected[i].first), std::string::npos) << errors[i];
        EXPECT_NE(errors[i].find(expected[i].second), std::string::npos) << errors[i];
    }
    // Many broken rays: at most 8 messages.
    for (VkasRay& r : rays) r.tMin = -1.0f;
    EXPECT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_ANY_HIT, 0, 0xFF, uint32_t(rays.size()),
                            rays.data(), hits.data()),
              VK_ERROR_VALIDATION_FAILED_EXT);
    EXPECT_EQ(takeValidationErrors().size(), 8u);
}
