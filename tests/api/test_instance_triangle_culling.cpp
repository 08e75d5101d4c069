// CTS `instance_triangle_culling`: index types x {transformed, notransform} x {noflags, ccw (FLIP_FACING), nocull
// (FACING_CULL_DISABLE), ccw_nocull} against the CULL_BACK / CULL_FRONT ray flags. Facing is decided in object
// space: a mirroring instance transform does not change it, a mirroring geometry transform does.
#include "meshes.hpp"

using namespace vt;

namespace {
struct CullParam {
    VkIndexType indexType;
    bool transformed;
    uint32_t instanceFlags;
};
std::string paramName(const ::testing::TestParamInfo<CullParam>& info) {
    const auto& p = info.param;
    std::string n = p.indexType == VK_INDEX_TYPE_NONE_KHR ? "index_none" : p.indexType == VK_INDEX_TYPE_UINT16 ? "index_uint16" : "index_uint32";
    n += p.transformed ? "_transformed" : "_notransform";
    const bool ccw = p.instanceFlags & VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR;
    const bool nocull = p.instanceFlags & VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
    n += ccw && nocull ? "_ccw_nocull" : ccw ? "_ccw" : nocull ? "_nocull" : "_noflags";
    return n;
}
std::vector<CullParam> allParams() {
    std::vector<CullParam> out;
    for (VkIndexType t : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
        for (bool xf : {true, false})
            for (uint32_t f : {0u, uint32_t(VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR),
                               uint32_t(VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR),
                               uint32_t(VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR |
                                        VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR)})
                out.push_back({t, xf, f});
    return out;
}
constexpr uint32_t kCullFlags[3] = {0, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES};
}  // namespace

class instance_triangle_culling : public VkasTest, public ::testing::WithParamInterface<CullParam> {};

TEST_P(instance_triangle_culling, cpu_built) {
    const CullParam& P = GetParam();
    // A grid whose triangles are randomly wound: counter-clockwise (front from +z) or clockwise.
    Mesh m = grid(6, 6);
    std::vector<bool> ccwFromTop(m.triangleCount());
    for (size_t t = 0; t < m.triangleCount(); ++t) {
        ccwFromTop[t] = rng.coin();
        if (!ccwFromTop[t]) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
    }
    auto g = makeGeometry(m, P.indexType, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*g);
    const VkTransformMatrixKHR xf = P.transformed ? randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f) : identityTransform();
    AccelStruct* tlas = buildTlas({Instance{xf, 0, 0xFF, 0, P.instanceFlags, blas}});
    const bool flip = P.instanceFlags & VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR;
    const bool noCull = P.instanceFlags & VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;

    std::vector<oracle::Ray> rays;
    for (uint32_t cull : kCullFlags) {
        for (size_t t = 0; t < m.triangleCount(); ++t) {
            Float3 c{0, 0, 0};
            for (int k = 0; k < 3; ++k)
                for (int j = 0; j < 3; ++j) c[j] += m.positions[m.indices[3 * t + k]][j] / 3.0f;
            for (bool fromTop : {true, false}) {
                const float z = fromTop ? 1.0f : -1.0f;
                const Float3 o = transformPoint(xf, {c[0], c[1], z}), e = transformPoint(xf, {c[0], c[1], -z});
                oracle::Ray r;
                r.origin = o;
                r.direction = {e[0] - o[0], e[1] - o[1], e[2] - o[2]};
                r.tMin = 0;
                r.tMax = 1;
                rays.push_back(r);
                // Analytic expectation.
                const bool front = (ccwFromTop[t] == fromTop) != flip;
                const bool culled = !noCull && ((cull == VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES && !front) ||
                                                (cull == VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES && front));
                const Hit h = traceClosest(tlas, r, cull);
                if (culled) {
                    EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_NONE) << "triangle " << t << " should be culled";
                } else {
                    EXPECT_EQ(h.primitiveIndex, int32_t(t)) << h.str();
                    EXPECT_EQ(h.frontFace, front) << "triangle " << t << (fromTop ? " from +z" : " from -z");
                }
            }
        }
        checkRays(tlas, rays, cull);
        checkRays(tlas, randomRays(*tlas->scene, 100), cull);
    }
}

INSTANTIATE_TEST_SUITE_P(cpu_built, instance_triangle_culling, ::testing::ValuesIn(allParams()), paramName);

using instance_triangle_culling_facing = VkasTest;

TEST_F(instance_triangle_culling_facing, mirroring_and_edge_on) {
    // One triangle, counter-clockwise seen from +z: a ray going down from +z sees its front.
    Mesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    m.indices = {0, 1, 2};
    VkTransformMatrixKHR mirrorX = identityTransform();
    mirrorX.matrix[0][0] = -1;
    auto plain = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto mirroredGeometry = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR, &mirrorX);
    AccelStruct* blasPlain = buildBlas(*plain);
    AccelStruct* blasMirrored = buildBlas(*mirroredGeometry);
    oracle::Ray down;
    down.origin = {0.1f, -0.2f, 2.0f};
    down.direction = {0, 0, -1};
    down.tMin = 0;
    down.tMax = 100;
    // Instance mirroring: facing unchanged.
    for (const VkTransformMatrixKHR& xf : {identityTransform(), mirrorX}) {
        AccelStruct* tlas = buildTlas({Instance{xf, 0, 0xFF, 0, 0, blasPlain}});
        Hit h = traceClosest(tlas, down);
        ASSERT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE);
        EXPECT_TRUE(h.frontFace) << "a mirroring instance transform must not change facing";
        EXPECT_EQ(traceClosest(tlas, down, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES).type, 0u);
        EXPECT_EQ(traceClosest(tlas, down, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES).type, 1u);
        checkRays(tlas, {down}, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES);
    }
    // Geometry mirroring: baked into the BLAS, so facing flips.
    AccelStruct* tlas = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, 0, blasMirrored}});
    Hit h = traceClosest(tlas, down);
    ASSERT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE);
    EXPECT_FALSE(h.frontFace) << "a mirroring geometry transform changes facing";
    EXPECT_EQ(traceClosest(tlas, down, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES).type, 0u);
    EXPECT_EQ(traceClosest(tlas, down, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES).type, 1u);
    checkRays(tlas, {down}, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES);
    // Edge-on rays never hit, whatever the flags.
    oracle::Ray edgeOn;
    edgeOn.origin = {-3.0f, -0.5f, 0.0f};
    edgeOn.direction = {1, 0, 0};
    edgeOn.tMin = 0;
    edgeOn.tMax = 100;
    for (uint32_t f : {0u, uint32_t(VKAS_RAY_FLAG_NO_OPAQUE), uint32_t(VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES)})
        EXPECT_EQ(traceClosest(tlas, edgeOn, f).type, 0u) << "edge-on, flags " << f;
}
