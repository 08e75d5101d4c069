// CTS `ray_cull_mask`: instance masks against ray cull masks (4-bit and 16-bit patterns, normal and reversed);
// only the low 8 bits of the cull mask are used; mask 0 is never hit.
#include "meshes.hpp"

using namespace vt;

namespace {
enum class Variant { bits4, bits4_reverse, bits16, bits16_reverse };
std::string variantName(Variant v) {
    switch (v) {
        case Variant::bits4: return "4_bits";
        case Variant::bits4_reverse: return "4_bits_reverse";
        case Variant::bits16: return "16_bits";
        case Variant::bits16_reverse: return "16_bits_reverse";
    }
    return "?";
}
}  // namespace

class ray_cull_mask : public VkasTest, public ::testing::WithParamInterface<Variant> {};

TEST_P(ray_cull_mask, cpu_built) {
    const Variant v = GetParam();
    const Mesh m = grid(1, 1);
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT16, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    AccelStruct* blas = buildBlas(*g);
    // Instance masks: every value of the pattern (plus 0), one instance per mask, side by side.
    std::vector<uint32_t> instanceMasks, cullMasks;
    switch (v) {
        case Variant::bits4:
            for (uint32_t i = 0; i < 16; ++i) instanceMasks.push_back(i), cullMasks.push_back(i);
            break;
        case Variant::bits4_reverse:
            for (uint32_t i = 0; i < 16; ++i) instanceMasks.push_back(i << 4), cullMasks.push_back(i << 4);
            break;
        case Variant::bits16:
            for (uint32_t i = 0; i < 24; ++i) instanceMasks.push_back(i == 0 ? 0 : rng.u32() & 0xFF);
            for (uint32_t i = 0; i < 32; ++i) cullMasks.push_back(rng.u32() & 0xFFFF);
            cullMasks.push_back(0xFFFFFFFFu);
            cullMasks.push_back(0);
            break;
        case Variant::bits16_reverse:
            // Bits above the low 8 must be ignored: masks that only differ there.
            for (uint32_t i = 0; i < 24; ++i) instanceMasks.push_back(i == 0 ? 0 : rng.u32() & 0xFF);
            for (uint32_t i = 0; i < 32; ++i) cullMasks.push_back((rng.u32() & 0xFF00u) | (i < 8 ? 0 : rng.u32() & 0xFF));
            cullMasks.push_back(0xFFFFFF00u);
            break;
    }
    std::vector<Instance> instances;
    for (size_t i = 0; i < instanceMasks.size(); ++i) {
        Instance inst;
        inst.transform = translation(2.0f * float(i), 0, 0);
        inst.mask = instanceMasks[i];
        inst.blas = blas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances);
    std::vector<oracle::Ray> rays;
    for (size_t i = 0; i < instances.size(); ++i) {
        oracle::Ray r;
        r.origin = {2.0f * float(i) + rng.uniformf(0.1f, 0.9f), rng.uniformf(0.1f, 0.9f), 1.0f};
        r.direction = {0, 0, -1};
        r.tMin = 0;
        r.tMax = 2;
        rays.push_back(r);
    }
    for (uint32_t cull : cullMasks) {
        for (size_t i = 0; i < instances.size(); ++i) {
            const Hit h = traceClosest(tlas, rays[i], 0, cull);
            const bool expectHit = (instanceMasks[i] & cull & 0xFFu) != 0;
            EXPECT_EQ(h.type, expectHit ? 1u : 0u) << "instance mask 0x" << std::hex << instanceMasks[i] << " cull mask 0x" << cull;
            if (expectHit) {
                EXPECT_EQ(h.instanceId, int32_t(i));
            }
        }
        checkRays(tlas, rays, 0, cull);
    }
    checkRays(tlas, randomRays(*tlas->scene, 100), 0, cullMasks[rng.below(uint32_t(cullMasks.size()))]);
}

INSTANTIATE_TEST_SUITE_P(cpu_built, ray_cull_mask,
                         ::testing::Values(Variant::bits4, Variant::bits4_reverse, Variant::bits16, Variant::bits16_reverse),
                         [](const auto& info) { return variantName(info.param); });
