// CTS `complex_geometry`: icosphere, terrain, torus knot and triangle soup x index type x build preference x
// single/multiple instances (random rotations, scales, mirroring). Random rays against the oracle, through the
// query loop and vkasTraceRays (closest and any-hit).
#include "meshes.hpp"

using namespace vt;

namespace {
enum class Shape { icosphere, terrain, torusknot, trianglesoup };
struct ComplexParam {
    Shape shape;
    VkIndexType indexType;
    int build;  // 0 default, 1 fast_trace, 2 fast_build, 3 compaction
    bool multipleInstances;
};
const char* kShapeNames[4] = {"icosphere", "terrain", "torusknot", "trianglesoup"};
const char* kBuildNames[4] = {"default", "fast_trace", "fast_build", "compaction"};
const VkBuildAccelerationStructureFlagsKHR kBuildFlags[4] = {0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
                                                             VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR,
                                                             VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR};
}  // namespace

class complex_geometry : public VkasTest, public ::testing::WithParamInterface<ComplexParam> {};

TEST_P(complex_geometry, cpu_built) {
    const ComplexParam& P = GetParam();
    Mesh mesh;
    switch (P.shape) {
        case Shape::icosphere: mesh = icosphere(3); break;             // 1280 triangles
        case Shape::terrain: mesh = terrain(32, rng); break;           // 2048 triangles
        case Shape::torusknot: mesh = torusKnot(128, 12); break;       // 3072 triangles
        case Shape::trianglesoup: mesh = triangleSoup(1500, rng, 0.15f); break;
    }
    auto g = makeGeometry(mesh, P.indexType, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    BuildOptions opt;
    opt.flags = kBuildFlags[P.build];
    AccelStruct* blas = buildBlas(*g, opt);
    std::vector<Instance> instances;
    if (!P.multipleInstances) {
        Instance inst;
        inst.blas = blas;
        instances.push_back(inst);
    } else {
        for (int i = 0; i < 6; ++i) {
            Instance inst;
            inst.transform = randomTransform(rng, 0.4f, 1.6f, rng.coin(), 2.5f);
            inst.customIndex = rng.u32() & 0xFFFFFF;
            inst.sbtOffset = rng.u32() & 0xFFFFFF;
            inst.blas = blas;
            instances.push_back(inst);
        }
    }
    AccelStruct* tlas = buildTlas(instances, opt);
    auto rays = randomRays(*tlas->scene, 200);
    const auto t = targetedRays(*tlas->scene, 100);
    rays.insert(rays.end(), t.begin(), t.end());
    EXPECT_GT(checkRays(tlas, rays), rays.size() / 3);
}

INSTANTIATE_TEST_SUITE_P(cpu, complex_geometry, ::testing::ValuesIn([] {
                             std::vector<ComplexParam> v;
                             for (Shape s : {Shape::icosphere, Shape::terrain, Shape::torusknot, Shape::trianglesoup})
                                 for (VkIndexType t : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
                                     for (int b = 0; b < 4; ++b)
                                         for (bool m : {false, true}) v.push_back({s, t, b, m});
                             return v;
                         }()),
                         [](const auto& info) {
                             const auto& p = info.param;
                             return std::string(kShapeNames[int(p.shape)]) + "_" +
                                    (p.indexType == VK_INDEX_TYPE_NONE_KHR ? "no_indices" : p.indexType == VK_INDEX_TYPE_UINT16 ? "uint16_indices" : "uint32_indices") +
                                    "_" + kBuildNames[p.build] + (p.multipleInstances ? "_multiple_instances" : "_single_instance");
                         });
