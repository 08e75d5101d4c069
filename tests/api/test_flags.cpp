// CTS `flags`: every build-flag combination (0/fasttrace/fastbuild x update x compaction x lowmemory) gives the
// oracle's hits; pGeometries vs ppGeometries and instance arrays vs arrays of pointers ("aop"); structures created
// as GENERIC; structures created before their buffer memory is bound.
#include "meshes.hpp"

using namespace vt;

namespace {
struct FlagsParam {
    VkBuildAccelerationStructureFlagsKHR flags;
    bool aop;
    int generic;  // bit 0: bottom generic, bit 1: top generic
    int serial;   // for the bind-after-create pattern
};

std::string paramName(const ::testing::TestParamInfo<FlagsParam>& info) {
    const auto& p = info.param;
    std::string n = (p.aop ? "triangles_aop_" : "triangles_");
    n += p.flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR   ? "fasttrace"
         : p.flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR ? "fastbuild"
                                                                                : "0";
    n += p.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR ? "_update" : "_0";
    n += p.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR ? "_compaction" : "_0";
    n += p.flags & VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR ? "_lowmemory" : "_0";
    static const char* gen[4] = {"", "_bottomgeneric", "_topgeneric", "_bothgeneric"};
    n += gen[p.generic];
    return n;
}

std::vector<FlagsParam> allParams() {
    std::vector<FlagsParam> out;
    int serial = 0;
    using F = VkBuildAccelerationStructureFlagsKHR;
    const F opts[3] = {0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
                       VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR};
    for (F opt : opts)
        for (F upd : {F(0), F(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR)})
            for (F cmp : {F(0), F(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR)})
                for (F low : {F(0), F(VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR)})
                    for (bool aop : {false, true})
                        for (int generic = 0; generic < 4; ++generic)
                            out.push_back({opt | upd | cmp | low, aop, generic, serial++});
    return out;
}
}  // namespace

class flags : public VkasTest, public ::testing::WithParamInterface<FlagsParam> {};

TEST_P(flags, cpu_built) {
    const FlagsParam& P = GetParam();
    // Two geometries (one opaque, one not, one with a degenerate and an inactive-free soup), several instances.
    Mesh a = terrain(8, rng);
    Mesh b = triangleSoup(150, rng, 0.2f);
    b.indices.insert(b.indices.end(), {0, 0, 1});  // a degenerate triangle (repeated index)
    const VkTransformMatrixKHR xf = randomTransform(rng, 0.5f, 1.5f, false, 0.5f);
    auto ga = makeGeometry(a, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR, &xf);
    auto gb = makeGeometry(b, VK_INDEX_TYPE_NONE_KHR, VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR);

    BuildOptions bottom;
    bottom.flags = P.flags;
    bottom.usePointers = P.aop;
    bottom.createGeneric = P.generic & 1;
    bottom.bindAfterCreate = P.serial % 3 == 0;
    AccelStruct* blas = buildBlas(std::vector<const GeometryData*>{ga.get(), gb.get()}, bottom);

    BuildOptions top;
    top.flags = P.flags;
    top.usePointers = P.aop;
    top.createGeneric = P.generic & 2;
    top.bindAfterCreate = P.serial % 7 == 0;
    top.instancePrimitiveOffset = 16 * rng.below(3);
    std::vector<Instance> instances;
    const bool identical = P.serial % 2 == 0;  // identical_instances / different_instances
    for (int i = 0; i < 5; ++i) {
        Instance inst;
        inst.transform = identical ? translation(2.5f * i, 0, 0) : randomTransform(rng, 0.5f, 1.5f, rng.coin(), 3.0f);
        inst.customIndex = uint32_t(i);
        inst.blas = blas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances, top);
    auto rays = randomRays(*tlas->scene, 200);
    const auto t = targetedRays(*tlas->scene, 100);
    rays.insert(rays.end(), t.begin(), t.end());
    EXPECT_GT(checkRays(tlas, rays), rays.size() / 4);
}

INSTANTIATE_TEST_SUITE_P(triangles, flags, ::testing::ValuesIn(allParams()), paramName);
