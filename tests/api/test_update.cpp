// CTS `update` and `instance_update`: VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR refits a structure built with
// ALLOW_UPDATE to new inputs (moved vertices, boxes, geometry transforms, instance definitions), in place
// (src == dst) or into another structure, and from a compacted copy. Every result is checked against the
// brute-force oracle on the new inputs. Also: a triangle collapsed to a point in the build is hit again once the
// update gives it area; an update with the build's inputs traces identically; and every update VUID is reported
// alone, with the destination untouched.
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {

constexpr VkBuildAccelerationStructureFlagsKHR kAllowUpdate = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
const float kNaN = std::numeric_limits<float>::quiet_NaN();


// Vertex data of a mesh in one of several vertex formats (non-indexed or indexed like makeGeometry).
struct FormattedGeometry {
    std::vector<uint8_t> vertices, indices, transform;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
};

void encodeVertex(VkFormat format, const Float3& p, uint8_t* out) {
    auto snorm16 = [](float f) { return int16_t(std::lround(std::clamp(f, -1.0f, 1.0f) * 32767.0f)); };
    auto snorm8 = [](float f) { return int8_t(std::lround(std::clamp(f, -1.0f, 1.0f) * 127.0f)); };
    switch (format) {
        case VK_FORMAT_R32G32B32_SFLOAT: std::memcpy(out, p.data(), 12); break;
        case VK_FORMAT_R32G32B32A32_SFLOAT: {
            const float v[4] = {p[0], p[1], p[2], 1.0f};
            std::memcpy(out, v, 16);
            break;
        }
        case VK_FORMAT_R64G64B64_SFLOAT: {
            const double v[3] = {p[0], p[1], p[2]};
            std::memcpy(out, v, 24);
            break;
        }
        case VK_FORMAT_R16G16B16A16_SNORM: {
            const int16_t v[4] = {snorm16(p[0]), snorm16(p[1]), snorm16(p[2]), 0};
            std::memcpy(out, v, 8);
            break;
        }
        case VK_FORMAT_R8G8B8A8_SNORM: {
            const int8_t v[4] = {snorm8(p[0]), snorm8(p[1]), snorm8(p[2]), 0};
            std::memcpy(out, v, 4);
            break;
        }
        default: FAIL() << "format " << format;
    }
}
uint32_t formatSize(VkFormat f) {
    switch (f) {
        case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
        case VK_FORMAT_R64G64B64_SFLOAT: return 24;
        case VK_FORMAT_R16G16B16A16_SNORM: return 8;
        case VK_FORMAT_R8G8B8A8_SNORM: return 4;
        default: return 12;
    }
}

std::unique_ptr<FormattedGeometry> makeFormatted(const Mesh& mesh, VkFormat format, VkIndexType indexType,
                                                 VkGeometryFlagsKHR flags, const VkTransformMatrixKHR* transform,
                                                 uint32_t firstVertex = 0) {
    auto g = std::make_unique<FormattedGeometry>();
    const uint32_t stride = formatSize(format);
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = flags;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = format;
    tri.vertexStride = stride;
    tri.indexType = indexType;
    std::vector<Float3> verts;
    if (indexType == VK_INDEX_TYPE_NONE_KHR) {
        for (uint32_t i : mesh.indices) verts.push_back(mesh.positions[i]);
    } else {
        verts = mesh.positions;
        const uint32_t size = indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        g->indices.resize(std::max<size_t>(mesh.indices.size() * size, 4));
        for (size_t i = 0; i < mesh.indices.size(); ++i) {
            if (size == 2) {
                const uint16_t v = uint16_t(mesh.indices[i]);
                std::memcpy(g->indices.data() + 2 * i, &v, 2);
            } else {
                std::memcpy(g->indices.data() + 4 * i, &mesh.indices[i], 4);
            }
        }
        tri.indexData.hostAddress = g->indices.data();
    }
    // Room for firstVertex up to 8; maxVertex does not depend on firstVertex (an update must keep it: 03764).
    g->vertices.assign((verts.size() + 8) * stride, 0xAA);
    for (size_t i = 0; i < verts.size(); ++i) encodeVertex(format, verts[i], g->vertices.data() + (firstVertex + i) * stride);
    tri.vertexData.hostAddress = g->vertices.data();
    tri.maxVertex = uint32_t(verts.size() + 7);
    if (transform) {
        g->transform.resize(sizeof(VkTransformMatrixKHR));
        std::memcpy(g->transform.data(), transform, sizeof(VkTransformMatrixKHR));
        tri.transformData.hostAddress = g->transform.data();
    }
    g->range.primitiveCount = uint32_t(mesh.triangleCount());
    g->range.firstVertex = firstVertex;
    return g;
}

// Moves every vertex by a random offset of up to `amount` (a deformation that keeps the index buffer).
Mesh deform(const Mesh& m, Rng& rng, float amount) {
    Mesh out = m;
    for (auto& p : out.positions)
        for (float& c : p) c += rng.uniformf(-amount, amount);
    return out;
}

std::vector<VkAabbPositionsKHR> randomBoxes(Rng& rng, size_t n, float extent, double inactiveFraction) {
    std::vector<VkAabbPositionsKHR> boxes(n);
    for (auto& b : boxes) {
        const float x = rng.uniformf(-extent, extent), y = rng.uniformf(-extent, extent), z = rng.uniformf(-extent, extent);
        const float s = rng.uniformf(0.05f, 0.4f);
        b = {x, y, z, x + s, y + rng.uniformf(0.05f, 0.4f), z + rng.uniformf(0.0f, 0.4f)};
        if (rng.coin(inactiveFraction)) b.minX = kNaN;
    }
    return boxes;
}

VkAccelerationStructureGeometryKHR aabbGeometry(const std::vector<VkAabbPositionsKHR>& boxes, VkGeometryFlagsKHR flags) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.flags = flags;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    g.geometry.aabbs.data.hostAddress = boxes.data();
    g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    return g;
}


// [NV-LSS] One sphere or LSS geometry over plain buffers: R32G32B32_SFLOAT positions, R32_SFLOAT radii, optional
// UINT32 indices (SUCCESSIVE needs them). Not copyable: the structures point into it.
struct SweptInput {
    bool lss = false;
    std::vector<Float3> positions;
    std::vector<float> radii;
    std::vector<uint32_t> indices;
    uint32_t indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
    uint32_t endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV;
    VkAccelerationStructureGeometrySpheresDataNV spheres{};
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lssData{};
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    SweptInput() = default;
    SweptInput(const SweptInput&) = delete;
    SweptInput& operator=(const SweptInput&) = delete;
};

// Points the structures at the buffers (call again after changing a vector's size).
void wireSwept(SweptInput& d, uint32_t primitiveCount, VkGeometryFlagsKHR flags) {
    const void* idx = d.indices.empty() ? nullptr : d.indices.data();
    const VkIndexType it = d.indices.empty() ? VK_INDEX_TYPE_NONE_KHR : VK_INDEX_TYPE_UINT32;
    d.geometry = VkAccelerationStructureGeometryKHR{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    d.geometry.flags = flags;
    if (d.lss) {
        auto& l = d.lssData;
        l = VkAccelerationStructureGeometryLinearSweptSpheresDataNV{};
        l.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV;
        l.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        l.vertexData.hostAddress = d.positions.data();
        l.vertexStride = sizeof(Float3);
        l.radiusFormat = VK_FORMAT_R32_SFLOAT;
        l.radiusData.hostAddress = d.radii.data();
        l.radiusStride = 4;
        l.indexType = it;
        l.indexData.hostAddress = idx;
        l.indexStride = idx ? 4 : 0;
        l.indexingMode = VkRayTracingLssIndexingModeNV(d.indexingMode);
        l.endCapsMode = VkRayTracingLssPrimitiveEndCapsModeNV(d.endCapsMode);
        d.geometry.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
        d.geometry.pNext = &d.lssData;
    } else {
        auto& sp = d.spheres;
        sp = VkAccelerationStructureGeometrySpheresDataNV{};
        sp.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV;
        sp.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        sp.vertexData.hostAddress = d.positions.data();
        sp.vertexStride = sizeof(Float3);
        sp.radiusFormat = VK_FORMAT_R32_SFLOAT;
        sp.radiusData.hostAddress = d.radii.data();
        sp.radiusStride = 4;
        sp.indexType = it;
        sp.indexData.hostAddress = idx;
        sp.indexStride = idx ? 4 : 0;
        d.geometry.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
        d.geometry.pNext = &d.spheres;
    }
    d.range = {};
    d.range.primitiveCount = primitiveCount;
}

// The same geometry (indices, modes, flags, count) with other positions and radii: what an update may change.
std::unique_ptr<SweptInput> withData(const SweptInput& base, std::vector<Float3> positions, std::vector<float> radii) {
    auto d = std::make_unique<SweptInput>();
    d->lss = base.lss;
    d->positions = std::move(positions);
    d->radii = std::move(radii);
    d->indices = base.indices;
    d->indexingMode = base.indexingMode;
    d->endCapsMode = base.endCapsMode;
    wireSwept(*d, base.range.primitiveCount, base.geometry.flags);
    return d;
}

// Random spheres (lss = false) or LSS in [-1, 1]^3: some zero radii (degenerate: LSS with both radii zero), some
// inactive (NaN radius; in SUCCESSIVE mode whole chains: a chain must be all active or all inactive).
std::unique_ptr<SweptInput> randomSwept(Rng& rng, bool lss, uint32_t indexing, uint32_t caps, uint32_t n) {
    auto d = std::make_unique<SweptInput>();
    d->lss = lss;
    d->indexingMode = lss ? indexing : 0;
    d->endCapsMode = lss ? caps : 0;
    auto point = [&] { return Float3{rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)}; };
    auto radius = [&] { return rng.coin(0.15) ? 0.0f : rng.uniformf(0.03f, 0.15f); };
    if (!lss) {
        for (uint32_t i = 0; i < n; ++i) d->positions.push_back(point()), d->radii.push_back(radius());
        if (rng.coin())
            for (uint32_t i = 0; i < n; ++i) d->indices.push_back(n - 1 - i);
        for (float& r : d->radii)
            if (rng.coin(0.05)) r = kNaN;
    } else if (indexing == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV) {
        // Polylines of 1-4 segments separated by an unused vertex, so a chain breaks where an index skips one.
        uint32_t made = 0;
        while (made < n) {
            const uint32_t len = std::min(n - made, 1 + rng.below(4));
            const bool inactive = rng.coin(0.08);
            const uint32_t first = uint32_t(d->positions.size());
            Float3 p = point();
            for (uint32_t k = 0; k <= len; ++k) {
                d->positions.push_back(p);
                d->radii.push_back(inactive ? kNaN : radius());
                for (float& c : p) c = std::clamp(c + rng.uniformf(-0.3f, 0.3f), -1.0f, 1.0f);
            }
            for (uint32_t k = 0; k < len; ++k) d->indices.push_back(first + k);
            d->positions.push_back(point()), d->radii.push_back(0.5f);  // the unused vertex between chains
            made += len;
        }
        // Some primitives degenerate: both of their radii zero.
        for (uint32_t i = 0; i < n; ++i)
            if (rng.coin(0.1) && !std::isnan(d->radii[d->indices[i]]))
                d->radii[d->indices[i]] = d->radii[d->indices[i] + 1] = 0.0f;
    } else {
        for (uint32_t i = 0; i < n; ++i) {
            Float3 a = point(), b = a;
            for (float& c : b) c = std::clamp(c + rng.uniformf(-0.4f, 0.4f), -1.0f, 1.0f);
            float ra = radius(), rb = radius();
            if (rng.coin(0.1)) ra = rb = 0.0f;  // degenerate
            if (rng.coin(0.05)) ra = kNaN;      // inactive
            d->positions.push_back(a), d->radii.push_back(ra);
            d->positions.push_back(b), d->radii.push_back(rb);
        }
        if (rng.coin())
            for (uint32_t i = 0; i < n; ++i) {
                const uint32_t p = n - 1 - i;  // reversed pairs, endpoints swapped
                d->indices.push_back(2 * p + 1), d->indices.push_back(2 * p);
            }
    }
    wireSwept(*d, n, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    return d;
}

// New positions and radii for an update: every vertex moved, radii re-drawn; zero radii get a radius and positive
// ones lose it now and then (degenerate both ways); NaN (inactive) stays NaN and nothing else becomes NaN.
std::unique_ptr<SweptInput> movedSwept(const SweptInput& base, Rng& rng, float amount) {
    std::vector<Float3> pos = base.positions;
    std::vector<float> radii = base.radii;
    for (auto& p : pos)
        for (float& c : p) c += rng.uniformf(-amount, amount);
    for (float& r : radii) {
        if (std::isnan(r)) continue;
        if (r == 0.0f)
            r = rng.coin(0.6) ? rng.uniformf(0.03f, 0.2f) : 0.0f;
        else
            r = rng.coin(0.15) ? 0.0f : rng.uniformf(0.03f, 0.2f);
    }
    if (base.lss)  // some primitives degenerate now: both radii zero
        for (uint32_t i = 0; i < base.range.primitiveCount; ++i) {
            if (!rng.coin(0.1)) continue;
            uint32_t v0 = base.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV ? i : 2 * i, v1 = v0 + 1;
            if (!base.indices.empty()) {
                v0 = base.indices[v0];
                v1 = base.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV ? v0 + 1 : base.indices[2 * i + 1];
            }
            if (!std::isnan(radii[v0]) && !std::isnan(radii[v1])) radii[v0] = radii[v1] = 0.0f;
        }
    return withData(base, std::move(pos), std::move(radii));
}

// [NV-motion] A triangle geometry with R32G32B32_SFLOAT positions at time 0 and time 1
// (VkAccelerationStructureGeometryMotionTrianglesDataNV), indexed (UINT32) or not.
struct MotionInput {
    std::vector<Float3> v0, v1;
    std::vector<uint32_t> indices;
    VkAccelerationStructureGeometryMotionTrianglesDataNV motion{};
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    MotionInput() = default;
    MotionInput(const MotionInput&) = delete;
    MotionInput& operator=(const MotionInput&) = delete;
};

std::unique_ptr<MotionInput> makeMotionInput(const Mesh& m, const std::vector<Float3>& at1, bool indexed,
                                             VkGeometryFlagsKHR flags) {
    auto g = std::make_unique<MotionInput>();
    if (indexed) {
        g->v0 = m.positions, g->v1 = at1, g->indices = m.indices;
    } else {
        for (uint32_t i : m.indices) g->v0.push_back(m.positions[i]), g->v1.push_back(at1[i]);
    }
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = flags;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    tri.vertexStride = sizeof(Float3);
    tri.vertexData.hostAddress = g->v0.data();
    tri.maxVertex = uint32_t(g->v0.size() - 1);
    tri.indexType = indexed ? VK_INDEX_TYPE_UINT32 : VK_INDEX_TYPE_NONE_KHR;
    if (indexed) tri.indexData.hostAddress = g->indices.data();
    g->motion.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV;
    g->motion.vertexData.hostAddress = g->v1.data();
    tri.pNext = &g->motion;
    g->range.primitiveCount = uint32_t(m.triangleCount());
    return g;
}

// [NV-motion] One VkAccelerationStructureMotionInstanceNV: type 0 static (m0), 1 matrix (m0 -> m1), 2 SRT (s0 -> s1).
struct MotionDesc {
    uint32_t type = 0;
    VkTransformMatrixKHR m0 = identityTransform(), m1 = identityTransform();
    VkSRTDataNV s0{}, s1{};
    uint32_t customIndex = 0, mask = 0xFF, sbtOffset = 0, flags = 0;
    const AccelStruct* blas = nullptr;  // null: inactive
};

VkTransformMatrixKHR zRotation(double angle) {
    VkTransformMatrixKHR m = identityTransform();
    m.matrix[0][0] = float(std::cos(angle)), m.matrix[0][1] = float(-std::sin(angle));
    m.matrix[1][0] = float(std::sin(angle)), m.matrix[1][1] = float(std::cos(angle));
    return m;
}

VkSRTDataNV randomSrtData(Rng& rng, float maxTranslation) {
    VkSRTDataNV s{};
    s.sx = rng.uniformf(0.5f, 1.5f), s.sy = rng.uniformf(0.5f, 1.5f), s.sz = rng.uniformf(0.5f, 1.5f);
    s.a = rng.uniformf(-0.2f, 0.2f), s.b = rng.uniformf(-0.2f, 0.2f), s.c = rng.uniformf(-0.2f, 0.2f);
    s.pvx = rng.uniformf(-0.5f, 0.5f), s.pvy = rng.uniformf(-0.5f, 0.5f), s.pvz = rng.uniformf(-0.5f, 0.5f);
    double q[4], n = 0;
    for (double& c : q) c = rng.uniform(-1, 1), n += c * c;
    n = std::sqrt(n);
    s.qx = float(q[0] / n), s.qy = float(q[1] / n), s.qz = float(q[2] / n), s.qw = float(q[3] / n);
    s.tx = rng.uniformf(-maxTranslation, maxTranslation);
    s.ty = rng.uniformf(-maxTranslation, maxTranslation);
    s.tz = rng.uniformf(-maxTranslation, maxTranslation);
    return s;
}

// A random motion instance of `type` over `blas`: matrix motion turns by at most 60 degrees about z and moves
// (every interpolated matrix stays invertible); SRT motion goes to another SRT whose quaternion is on the same
// side (the interpolated quaternion never passes near zero).
MotionDesc randomMotionDesc(Rng& rng, const AccelStruct* blas, uint32_t type) {
    MotionDesc d;
    d.type = type;
    d.blas = blas;
    d.customIndex = rng.u32() & 0xFFFFFF;
    d.sbtOffset = rng.u32() & 0xFFFFFF;
    d.mask = rng.coin(0.8) ? 0xFF : (rng.u32() & 0xFF);
    if (type != 2) {
        d.m0 = randomTransform(rng, 0.5f, 1.5f, rng.coin(0.2), 4.0f);
        d.m1 = type == 0 ? d.m0
                         : compose(translation(rng.uniformf(-2, 2), rng.uniformf(-2, 2), rng.uniformf(-2, 2)),
                                   compose(zRotation(rng.uniform(-M_PI / 3, M_PI / 3)), d.m0));
    } else {
        d.s0 = randomSrtData(rng, 4.0f);
        d.s1 = randomSrtData(rng, 4.0f);
        if (d.s0.qx * d.s1.qx + d.s0.qy * d.s1.qy + d.s0.qz * d.s1.qz + d.s0.qw * d.s1.qw < 0)
            d.s1.qx = -d.s1.qx, d.s1.qy = -d.s1.qy, d.s1.qz = -d.s1.qz, d.s1.qw = -d.s1.qw;
    }
    return d;
}

}  // namespace

class update : public VkasTest {
  protected:
    // An UPDATE of `src` with new inputs, into `dst` (nullptr: a fresh structure of src's size; src: in place).
    // On success the oracle's view of the destination follows the new inputs.
    AccelStruct* updateBlas(AccelStruct* src, AccelStruct* dst, const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                            const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges, const BuildOptions& opt) {
        auto pb = prepareBlas(geometries, ranges, opt);
        return submitUpdate(*pb, src, dst);
    }
    AccelStruct* updateTlas(AccelStruct* src, AccelStruct* dst, const std::vector<Instance>& instances,
                            const BuildOptions& opt) {
        auto pb = prepareTlas(instances, opt);
        return submitUpdate(*pb, src, dst);
    }
    AccelStruct* submitUpdate(PreparedBuild& pb, AccelStruct* src, AccelStruct* dst) {
        EXPECT_EQ(pb.as->sizes.updateScratchSize, 0u);  // a refit needs no scratch
        pb.info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb.info.srcAccelerationStructure = src->handle;
        pb.info.scratchData.hostAddress = nullptr;
        if (dst) {
            pb.as = dst;
            pb.info.dstAccelerationStructure = dst->handle;
        }
        submit({&pb});
        return pb.as;
    }
    // A byte copy of [0, usedSize) through vkCopyAccelerationStructureKHR COMPACT into a structure of that size.
    AccelStruct* compactCopy(AccelStruct* src) {
        uint64_t used;
        std::memcpy(&used, src->data() + 16, 8);
        AccelStruct* dst = createAccelStruct(src->type, (used + 255) / 256 * 256, {});
        VkCopyAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        ci.src = src->handle;
        ci.dst = dst->handle;
        ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
        EXPECT_EQ(vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &ci), VK_SUCCESS);
        dst->blas = src->blas;
        dst->scene = src->scene;
        if (src->blas) blasRegistry[dst->reference()] = src->blas;
        return dst;
    }
    // [NV-LSS] Rays at random points inside the hittable spheres / LSS of every instance (from outside, sometimes
    // from inside), plus, for each active primitive that is degenerate (zero radii), rays exactly through its
    // centre / endpoints: a zero-radius ball would be met there, so a degenerate record that produced a candidate
    // would show against the oracle (for which it is never hit).
    std::vector<oracle::Ray> sweptRays(const oracle::Scene& scene, size_t count) {
        std::vector<oracle::Ray> rays;
        struct Target {
            const oracle::Instance* inst;
            const oracle::SweptPrimitive* sp;
        };
        std::vector<Target> hittable;
        auto toWorld = [](const oracle::Instance& in, const std::array<double, 3>& p) {
            oracle::Vec3 w;
            for (int k = 0; k < 3; ++k)
                w[k] = in.toWorld[k][0] * p[0] + in.toWorld[k][1] * p[1] + in.toWorld[k][2] * p[2] + in.toWorld[k][3];
            return w;
        };
        for (const auto& in : scene.instances) {
            if (!in.blas) continue;
            for (const auto& g : in.blas->geometries)
                for (const auto& sp : g.swept) {
                    if (sp.hittable()) {
                        hittable.push_back({&in, &sp});
                    } else if (sp.active && sp.r[0] == 0 && sp.r[1] == 0) {
                        for (int e = 0; e < 2; ++e) {  // straight down through the point (exact in object space)
                            oracle::Ray r;
                            const auto w = toWorld(in, {sp.p[e][0], sp.p[e][1], sp.p[e][2] + 3.0});
                            for (int k = 0; k < 3; ++k) r.origin[k] = float(w[k]);
                            for (int k = 0; k < 3; ++k) r.direction[k] = float(-in.toWorld[k][2]);
                            r.tMax = 100;
                            rays.push_back(r);
                        }
                    }
                }
        }
        for (size_t n = 0; n < count && !hittable.empty(); ++n) {
            const Target& t = hittable[rng.below(uint32_t(hittable.size()))];
            const double s = rng.uniform(0, 1), rad = (t.sp->r[0] + s * (t.sp->r[1] - t.sp->r[0])) * rng.uniform(0, 0.9);
            std::array<double, 3> dir, off, p;
            double dl, ol;
            do {
                for (double& x : dir) x = rng.uniform(-1, 1);
                dl = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            } while (dl > 1 || dl < 1e-2);
            do {
                for (double& x : off) x = rng.uniform(-1, 1);
                ol = std::sqrt(off[0] * off[0] + off[1] * off[1] + off[2] * off[2]);
            } while (ol > 1 || ol < 1e-2);
            for (int k = 0; k < 3; ++k) p[k] = t.sp->p[0][k] + s * (t.sp->p[1][k] - t.sp->p[0][k]) + off[k] / ol * rad;
            const auto w = toWorld(*t.inst, p);
            const double back = rng.coin(0.1) ? 0.0 : rng.uniform(1.0, 5.0);
            oracle::Ray r;
            for (int k = 0; k < 3; ++k) r.origin[k] = float(w[k] - back * dir[k] / dl), r.direction[k] = float(dir[k] / dl);
            r.tMax = 100;
            rays.push_back(r);
        }
        return rays;
    }
    // A sphere / LSS bottom level under one identity instance, against the oracle (closest, any hit, batch, with
    // and without forced opacity). Returns the query hits.
    size_t checkSweptBlas(const AccelStruct* blas, size_t rays = 150) {
        AccelStruct* tlas = buildSingleInstanceTlas(blas);
        auto r = sweptRays(*tlas->scene, rays);
        auto more = randomRays(*tlas->scene, rays / 3);
        r.insert(r.end(), more.begin(), more.end());
        return checkRays(tlas, r) + checkRays(tlas, r, VKAS_RAY_FLAG_NO_OPAQUE, 0xFF, false);
    }
    // How many records a structure stores (Header::recordCount, docs/FORMAT.md).
    static uint32_t recordCount(const AccelStruct* as) {
        uint32_t n;
        std::memcpy(&n, as->data() + 64, 4);
        return n;
    }

    // [NV-motion] A motion bottom level build (ALLOW_UPDATE), or an update of `src` into `dst` (nullptr: a fresh
    // structure; src: in place) when src is given; the oracle knows both times.
    AccelStruct* motionBlas(const std::vector<const MotionInput*>& inputs, AccelStruct* src = nullptr,
                            AccelStruct* dst = nullptr) {
        std::vector<VkAccelerationStructureGeometryKHR> g;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
        for (const auto* m : inputs) g.push_back(m->geometry), r.push_back(m->range);
        BuildOptions opt;
        opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        auto pb = prepareBlas(g, r, opt);
        auto later = std::make_shared<oracle::Blas>();
        for (size_t i = 0; i < g.size(); ++i) later->geometries.push_back(oracle::fetchTrianglesAtTime1(g[i], r[i]));
        later->computeBounds();
        pb->blas->atTime1 = later;
        if (src) return submitUpdate(*pb, src, dst);
        submit({pb.get()});
        return pb->as;
    }

    // [NV-motion] A motion top level of VkAccelerationStructureMotionInstanceNV (160-byte stride), built with
    // ALLOW_UPDATE, or an update of `src` into `dst` (nullptr: fresh; src: in place). `scene` receives the
    // oracle's view of the instances as written.
    AccelStruct* motionTlas(const std::vector<MotionDesc>& descs, oracle::MotionScene& scene, AccelStruct* src = nullptr,
                            AccelStruct* dst = nullptr) {
        auto pb = std::make_unique<PreparedBuild>();
        const size_t n = descs.size(), stride = 160;
        pb->instanceBytes.assign(stride * n + 16, 0xAA);
        for (size_t i = 0; i < n; ++i) {
            const MotionDesc& d = descs[i];
            VkAccelerationStructureMotionInstanceNV mi;
            std::memset(&mi, 0, sizeof mi);
            mi.type = VkAccelerationStructureMotionInstanceTypeNV(d.type);
            const uint64_t ref = d.blas ? d.blas->reference() : 0;
            auto common = [&](auto& x) {
                x.instanceCustomIndex = d.customIndex, x.mask = d.mask;
                x.instanceShaderBindingTableRecordOffset = d.sbtOffset, x.flags = d.flags;
                x.accelerationStructureReference = ref;
            };
            if (d.type == 0) {
                mi.data.staticInstance.transform = d.m0;
                common(mi.data.staticInstance);
            } else if (d.type == 1) {
                mi.data.matrixMotionInstance.transformT0 = d.m0, mi.data.matrixMotionInstance.transformT1 = d.m1;
                common(mi.data.matrixMotionInstance);
            } else {
                mi.data.srtMotionInstance.transformT0 = d.s0, mi.data.srtMotionInstance.transformT1 = d.s1;
                common(mi.data.srtMotionInstance);
            }
            std::memcpy(pb->instanceBytes.data() + stride * i, &mi, sizeof mi);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.data.hostAddress = pb->instanceBytes.data();
        pb->geometries.push_back(g);
        VkAccelerationStructureBuildRangeInfoKHR range{};
        range.primitiveCount = uint32_t(n);
        pb->ranges.push_back(range);
        auto& info = pb->info;
        info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        info.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.geometryCount = 1;
        info.pGeometries = pb->geometries.data();
        const uint32_t maxCount = uint32_t(n);
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                   &maxCount, &sizes);
        BuildOptions opt;
        opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        opt.motionMaxInstances = uint32_t(n);
        pb->as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, opt);
        pb->as->sizes = sizes;
        info.dstAccelerationStructure = pb->as->handle;
        pb->scratch.assign(sizes.buildScratchSize, 0xAA);
        info.scratchData.hostAddress = pb->scratch.empty() ? nullptr : pb->scratch.data();
        auto lookup = [this](uint64_t ref) -> std::shared_ptr<const oracle::Blas> {
            auto it = blasRegistry.find(ref);
            return it == blasRegistry.end() ? nullptr : it->second;
        };
        scene.instances.clear();
        for (size_t i = 0; i < n; ++i) {
            const uint8_t* p = pb->instanceBytes.data() + stride * i;
            scene.instances.push_back(oracle::decodeMotionInstance(descs[i].type, p + 8, lookup));
        }
        if (src) return submitUpdate(*pb, src, dst);
        submit({pb.get()});
        return pb->as;
    }

    // [NV-motion] Rays traced at each time: random and targeted rays of the oracle's scene at that time, through
    // vkasRayQueryInitializeMotion (every candidate confirmed; closest and, for a third of them, first hit) against
    // the oracle at that time; at time 0 also checkRays (plain initialize and vkasTraceRays trace at time 0).
    // Returns the hits.
    size_t checkMotion(const AccelStruct* tlas, const oracle::MotionScene& scene, size_t raysPerTime) {
        std::vector<float> times = {0.0f, 1.0f, 0.5f};
        for (int i = 0; i < 3; ++i) times.push_back(rng.uniformf(0.0f, 1.0f));
        size_t hits = 0, failures = 0;
        for (float time : times) {
            const oracle::Scene at = scene.at(time);
            auto rays = randomRays(at, raysPerTime / 2);
            auto targeted = targetedRays(at, raysPerTime - rays.size());
            rays.insert(rays.end(), targeted.begin(), targeted.end());
            for (size_t i = 0; i < rays.size(); ++i) {
                const oracle::Ray& ray = rays[i];
                const uint32_t flags = i % 3 == 2 ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0u;
                const oracle::Result ex = oracle::trace(at, ray, flags, 0xFF);
                VkasRayQuery q;
                vkasRayQueryInitializeMotion(&q, tlas->handle, flags, 0xFF, ray.origin.data(), ray.tMin,
                                             ray.direction.data(), ray.tMax, time);
                while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
                const Hit got = readHit(q, true);
                hits += got.type != VKAS_COMMITTED_INTERSECTION_NONE;
                const auto res = flags ? matchesAnyHit(ex, ray, got) : matchesClosest(ex, ray, got);
                if (!res && ++failures <= 10)
                    ADD_FAILURE() << "time " << time << " ray " << describe(ray) << ": " << res.message() << "\n  seed "
                                  << seed;
            }
            if (time == 0.0f) {
                AccelStruct view = *tlas;
                view.scene = std::make_shared<oracle::Scene>(at);
                hits += checkRays(&view, rays);
            }
        }
        return hits;
    }
    void checkBlas(const AccelStruct* blas, size_t rays = 150) {
        AccelStruct* tlas = buildSingleInstanceTlas(blas);
        checkRays(tlas, targetedRays(*tlas->scene, rays));
        checkRays(tlas, randomRays(*tlas->scene, rays / 2));
    }
};

// ---- bottom level -----------------------------------------------------------------------------------------------

// CTS update.cpu.*.vertices (and .transform): deform a mesh, refit in place and into another structure, for every
// index type and several vertex formats, with and without a geometry transform; and once more from the refitted
// structure.
TEST_F(update, triangles_vertices) {
    const VkFormat formats[] = {VK_FORMAT_R32G32B32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R64G64B64_SFLOAT,
                                VK_FORMAT_R16G16B16A16_SNORM, VK_FORMAT_R8G8B8A8_SNORM};
    for (VkFormat format : formats)
        for (VkIndexType it : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
            for (int transformed = 0; transformed < 2; ++transformed)
                for (int inPlace = 0; inPlace < 2; ++inPlace) {
                    SCOPED_TRACE(testing::Message() << "format " << format << " index " << it << " transform "
                                                    << transformed << " inPlace " << inPlace);
                    Mesh m = triangleSoup(200, rng, 0.3f);
                    for (auto& p : m.positions)
                        for (float& c : p) c *= 0.7f;  // room for the deformation within [-1, 1] (SNORM)
                    VkTransformMatrixKHR t0 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                    auto g0 = makeFormatted(m, format, it, VK_GEOMETRY_OPAQUE_BIT_KHR, transformed ? &t0 : nullptr, 3);
                    BuildOptions opt;
                    opt.flags = kAllowUpdate | (rng.coin() ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR : 0);
                    opt.usePointers = rng.coin();
                    AccelStruct* blas = buildBlas({g0->geometry}, {g0->range}, opt);
                    checkBlas(blas, 60);
                    // Deformed vertices, a new transform, another firstVertex (allowed to change since 1.3.289).
                    VkTransformMatrixKHR t1 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                    auto g1 = makeFormatted(deform(m, rng, 0.25f), format, it, VK_GEOMETRY_OPAQUE_BIT_KHR,
                                            transformed ? &t1 : nullptr, 7);
                    AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
                    checkBlas(out, 100);
                    // A second update, from the refitted structure.
                    auto g2 = makeFormatted(deform(m, rng, 0.25f), format, it, VK_GEOMETRY_OPAQUE_BIT_KHR,
                                            transformed ? &t0 : nullptr, 0);
                    AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
                    checkBlas(out2, 100);
                    if (HasFailure()) return;
                }
}

// Several geometries, large moves (the refitted tree is poor but exact), inactive triangles staying inactive.
TEST_F(update, triangles_many_geometries_and_inactive) {
    for (int round = 0; round < 4; ++round) {
        std::vector<Mesh> meshes;
        std::vector<std::unique_ptr<GeometryData>> data;
        std::vector<const GeometryData*> ptrs;
        const int geometries = 1 + int(rng.below(5));
        for (int g = 0; g < geometries; ++g) {
            Mesh m = triangleSoup(50 + int(rng.below(300)), rng, 0.4f);
            for (size_t i = 0; i < m.indices.size(); i += 3)  // some inactive triangles (NaN X in one vertex)
                if (rng.coin(0.05)) {
                    m.positions.push_back({kNaN, 0, 0});
                    m.indices[i + rng.below(3)] = uint32_t(m.positions.size() - 1);
                }
            meshes.push_back(m);
            data.push_back(makeGeometry(m, rng.coin() ? VK_INDEX_TYPE_UINT32 : VK_INDEX_TYPE_UINT16,
                                        rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
            ptrs.push_back(data.back().get());
        }
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas(ptrs, opt);
        std::vector<VkAccelerationStructureGeometryKHR> geoms;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
        std::vector<std::unique_ptr<GeometryData>> moved;
        for (int g = 0; g < geometries; ++g) {
            Mesh m = deform(meshes[g], rng, round < 2 ? 0.1f : 2.0f);  // NaN stays NaN
            moved.push_back(makeGeometry(m, data[g]->geometry.geometry.triangles.indexType, data[g]->geometry.flags));
            geoms.push_back(moved.back()->geometry);
            ranges.push_back(moved.back()->range);
        }
        AccelStruct* out = updateBlas(blas, round % 2 ? blas : nullptr, geoms, ranges, opt);
        checkBlas(out, 200);
        if (HasFailure()) return;
    }
}

// CTS update.cpu.*.degenerate: a triangle collapsed to a point in the first build is hit once an update gives it
// area again, and missed again once an update collapses it.
TEST_F(update, degenerate_revival) {
    for (int inPlace = 0; inPlace < 2; ++inPlace) {
        Mesh m;
        m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {2, 2, 0}, {2, 2, 0}, {2, 2, 0}};
        m.indices = {0, 1, 2, 3, 4, 5};  // triangle 1 is a point at (2, 2, 0)
        auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas(*g0, opt);
        oracle::Ray ray;
        ray.origin = {2.5f, 2.25f, 1.0f};
        ray.direction = {0, 0, -1};
        ray.tMax = 10;
        EXPECT_EQ(traceClosest(buildSingleInstanceTlas(blas), ray).type, 0u);
        Mesh real = m;
        real.positions[3] = {2, 2, 0}, real.positions[4] = {3, 2, 0}, real.positions[5] = {3, 3, 0};
        auto g1 = makeGeometry(real, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
        AccelStruct* tlas = buildSingleInstanceTlas(out);
        const Hit h = traceClosest(tlas, ray);
        EXPECT_EQ(h.type, 1u);
        EXPECT_EQ(h.primitiveIndex, 1);
        checkRays(tlas, targetedRays(*tlas->scene, 50));
        // Collapsed again (to a line this time): never hit.
        Mesh line = m;
        line.positions[3] = {2, 2, 0}, line.positions[4] = {3, 3, 0}, line.positions[5] = {2.5f, 2.5f, 0};
        auto g2 = makeGeometry(line, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
        AccelStruct* tlas2 = buildSingleInstanceTlas(out2);
        EXPECT_EQ(traceClosest(tlas2, ray).type, 0u);
        checkRays(tlas2, randomRays(*tlas2->scene, 50));
    }
}

// An update with the build's own inputs gives the build's bytes (the node boxes are the same min/max of the same
// record boxes; only the sign of a zero coordinate could differ, and no box test can tell it) and traces
// identically.
TEST_F(update, unchanged_inputs_trace_identically) {
    Mesh m = icosphere(3);
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT32, 0, nullptr);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* blas = buildBlas(*g, opt);
    uint64_t used;
    std::memcpy(&used, blas->data() + 16, 8);
    const std::vector<uint8_t> before(blas->data(), blas->data() + used);
    AccelStruct* other = updateBlas(blas, nullptr, {g->geometry}, {g->range}, opt);
    auto sameStructure = [&](const uint8_t* a, const uint8_t* b) {
        for (uint64_t i = 0; i < used; i += 4) {
            if (std::memcmp(a + i, b + i, 4) == 0) continue;
            float fa, fb;
            std::memcpy(&fa, a + i, 4), std::memcpy(&fb, b + i, 4);
            if (fa == 0.0f && fb == 0.0f) continue;  // +0 against -0
            return ::testing::AssertionFailure() << "byte " << i << " differs";
        }
        return ::testing::AssertionSuccess();
    };
    EXPECT_TRUE(sameStructure(before.data(), other->data()));
    AccelStruct* self = updateBlas(blas, blas, {g->geometry}, {g->range}, opt);
    EXPECT_TRUE(sameStructure(before.data(), self->data()));
    // Traces identically: the two structures give bit-identical hits.
    AccelStruct* t1 = buildSingleInstanceTlas(other);
    AccelStruct* t2 = buildSingleInstanceTlas(self);
    for (const auto& ray : randomRays(*t1->scene, 300)) {
        const Hit a = traceClosest(t1, ray), b = traceClosest(t2, ray);
        EXPECT_TRUE(identical(a, b)) << a.str() << " vs " << b.str();
    }
    checkRays(t1, targetedRays(*t1->scene, 100));
}

// CTS update.cpu.compact.*: an update of a compacted structure (a byte copy of [0, usedSize)).
TEST_F(update, compacted_source) {
    Mesh m = terrain(24, rng);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* blas = buildBlas(*g0, opt);
    AccelStruct* compact = compactCopy(blas);
    Mesh moved = deform(m, rng, 0.3f);
    auto g1 = makeGeometry(moved, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    // In place, and into another structure of the compacted size.
    AccelStruct* other = createAccelStruct(compact->type, compact->size, {});
    AccelStruct* out = updateBlas(compact, other, {g1->geometry}, {g1->range}, opt);
    checkBlas(out);
    AccelStruct* self = updateBlas(compact, compact, {g1->geometry}, {g1->range}, opt);
    checkBlas(self);
}

// AABBs: moved and resized boxes, inactive boxes staying inactive.
TEST_F(update, aabbs) {
    for (int round = 0; round < 6; ++round) {
        std::vector<VkAabbPositionsKHR> boxes = randomBoxes(rng, 20 + rng.below(400), 2.0f, 0.1);
        const auto g0 = aabbGeometry(boxes, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
        VkAccelerationStructureBuildRangeInfoKHR r{};
        r.primitiveCount = uint32_t(boxes.size());
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas({g0}, {r}, opt);
        std::vector<VkAabbPositionsKHR> moved = boxes;
        for (auto& b : moved) {
            if (std::isnan(b.minX)) continue;
            const float d[3] = {rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)};
            b.minX += d[0], b.maxX += d[0] + rng.uniformf(0, 0.3f);
            b.minY += d[1], b.maxY += d[1];
            b.minZ += d[2], b.maxZ += d[2];
        }
        const auto g1 = aabbGeometry(moved, g0.flags);
        AccelStruct* out = updateBlas(blas, round % 2 ? blas : nullptr, {g1}, {r}, opt);
        checkBlas(out, 200);
        if (HasFailure()) return;
    }
}

// ---- top level (CTS instance_update) ------------------------------------------------------------------------------

// New transforms, masks, custom indices, SBT offsets, flags and referenced bottom levels; inactive instances stay
// inactive. In place and into a fresh structure.
// CTS `instance_update`: top-level updates (transforms, masks, custom indices, SBT offsets, flags, the referenced
// bottom level, motion instances).
class instance_update : public update {};

TEST_F(instance_update, transforms_masks_ids_flags_and_references) {
    Mesh sphere = icosphere(2), knot = torusKnot(64, 8);
    auto ga = makeGeometry(sphere, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto gb = makeGeometry(knot, VK_INDEX_TYPE_UINT32, 0);
    std::vector<VkAabbPositionsKHR> boxes = randomBoxes(rng, 30, 1.0f, 0.0);
    const auto gc = aabbGeometry(boxes, VK_GEOMETRY_OPAQUE_BIT_KHR);
    VkAccelerationStructureBuildRangeInfoKHR rc{};
    rc.primitiveCount = uint32_t(boxes.size());
    AccelStruct* blases[3] = {buildBlas(*ga), buildBlas(*gb), buildBlas({gc}, {rc})};
    auto randomInstance = [&](Instance& in) {
        in.transform = randomTransform(rng, 0.3f, 1.5f, rng.coin(0.2), 8.0f);
        in.customIndex = rng.u32() & 0xFFFFFF;
        in.mask = rng.coin(0.8) ? 0xFF : rng.u32() & 0xFF;
        in.sbtOffset = rng.u32() & 0xFFFFFF;
        in.flags = (rng.u32() & 0x3) | (rng.coin() ? (rng.coin() ? 0x4 : 0x8) : 0);  // never FORCE_OPAQUE and NO_OPAQUE
        in.blas = blases[rng.below(3)];
    };
    for (int round = 0; round < 6; ++round) {
        const size_t n = 1 + rng.below(60);
        std::vector<Instance> instances(n);
        for (auto& in : instances) {
            randomInstance(in);
            if (rng.coin(0.1)) in.blas = nullptr;  // inactive
        }
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        opt.usePointers = rng.coin();
        AccelStruct* tlas = buildTlas(instances, opt);
        for (auto& in : instances)
            if (in.blas) randomInstance(in);
        AccelStruct* out = updateTlas(tlas, round % 2 ? tlas : nullptr, instances, opt);
        checkRays(out, randomRays(*out->scene, 150));
        checkRays(out, targetedRays(*out->scene, 150));
        checkRays(out, randomRays(*out->scene, 100), 0, 0x0F);
        if (HasFailure()) return;
    }
}

// CTS instance_update.update_in_place then copy: the refitted structure copied (CLONE) traces like the original.
TEST_F(instance_update, then_copy) {
    auto g = makeGeometry(icosphere(2), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*g);
    std::vector<Instance> instances(8);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f), in.blas = blas;
    BuildOptions opt;
    opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* tlas = buildTlas(instances, opt);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f);
    updateTlas(tlas, tlas, instances, opt);
    AccelStruct* copy = createAccelStruct(tlas->type, tlas->size, {});
    VkCopyAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    ci.src = tlas->handle;
    ci.dst = copy->handle;
    ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    ASSERT_EQ(vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &ci), VK_SUCCESS);
    copy->scene = tlas->scene;
    checkRays(copy, randomRays(*copy->scene, 200));
    // And a compacted copy of the TLAS updates again.
    AccelStruct* compact = compactCopy(tlas);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f);
    AccelStruct* out = updateTlas(compact, compact, instances, opt);
    checkRays(out, randomRays(*out->scene, 200));
}

// A refitted bottom level, then the top level updated: the instance boxes follow the new bottom-level bounds.
TEST_F(instance_update, blas_then_tlas) {
    Mesh m = icosphere(2);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* blas = buildBlas(*g0, opt);
    std::vector<Instance> instances(5);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 4.0f), in.blas = blas;
    AccelStruct* tlas = buildTlas(instances, opt);
    Mesh big = m;
    for (auto& p : big.positions)
        for (float& c : p) c *= 2.5f;
    auto g1 = makeGeometry(big, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    updateBlas(blas, blas, {g1->geometry}, {g1->range}, opt);
    AccelStruct* out = updateTlas(tlas, tlas, instances, opt);
    checkRays(out, targetedRays(*out->scene, 200));
    checkRays(out, randomRays(*out->scene, 200));
}

// ---- [NV-LSS] spheres and linear swept spheres --------------------------------------------------------------------

// Refit of spheres and LSS (LIST and SUCCESSIVE indexing, end caps NONE and CHAINED): moved positions and new radii,
// zero radii given a radius and positive ones taken away (degenerate both ways), inactive primitives staying
// inactive; in place and into another structure, then once more from the refitted structure. The ALLOW_UPDATE
// build stores the degenerate primitives (a build without it does not), and an update with the build's own inputs
// gives the build's bytes.
TEST_F(update, spheres_and_lss) {
    struct Case {
        bool lss;
        uint32_t indexing, caps;
    };
    const Case cases[] = {{false, 0, 0},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV,
                           VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV}};
    for (const Case& c : cases)
        for (int inPlace = 0; inPlace < 2; ++inPlace) {
            SCOPED_TRACE(testing::Message() << "lss " << c.lss << " indexing " << c.indexing << " caps " << c.caps
                                            << " inPlace " << inPlace);
            auto g0 = randomSwept(rng, c.lss, c.indexing, c.caps, 20 + rng.below(60));
            uint32_t degenerate = 0, hittable = 0;
            {
                const auto& sw = oracle::fetchGeometry(g0->geometry, g0->range).swept;
                for (const auto& sp : sw) degenerate += sp.active && sp.r[0] == 0 && sp.r[1] == 0, hittable += sp.hittable();
            }
            BuildOptions opt;
            opt.flags = kAllowUpdate;
            opt.usePointers = rng.coin();
            AccelStruct* blas = buildBlas({g0->geometry}, {g0->range}, opt);
            // Degenerate primitives are stored (never hit) by an ALLOW_UPDATE build only.
            EXPECT_EQ(recordCount(blas), hittable + degenerate);
            EXPECT_EQ(recordCount(buildBlas({g0->geometry}, {g0->range})), hittable);
            checkSweptBlas(blas, 80);
            // The build's own inputs: the same bytes (up to the sign of a zero box coordinate).
            {
                uint64_t used;
                std::memcpy(&used, blas->data() + 16, 8);
                AccelStruct* same = updateBlas(blas, nullptr, {g0->geometry}, {g0->range}, opt);
                for (uint64_t i = 0; i < used; i += 4) {
                    if (std::memcmp(blas->data() + i, same->data() + i, 4) == 0) continue;
                    float a, b;
                    std::memcpy(&a, blas->data() + i, 4), std::memcpy(&b, same->data() + i, 4);
                    ASSERT_TRUE(a == 0.0f && b == 0.0f) << "byte " << i << " differs";
                }
            }
            auto g1 = movedSwept(*g0, rng, 0.3f);
            AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
            EXPECT_GT(checkSweptBlas(out), 0u) << "seed " << seed;
            auto g2 = movedSwept(*g1, rng, 0.3f);
            AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
            EXPECT_GT(checkSweptBlas(out2), 0u) << "seed " << seed;
            if (HasFailure()) return;
        }
}

// A zero-radius sphere and a zero-radius LSS (both radii 0), built with ALLOW_UPDATE: never hit, not even by a ray
// through the point itself; an update that gives them a radius is valid (no VUID 03664) and makes them hit; an
// update back to zero makes them miss again. For every LSS indexing and end-caps mode; in place and into another
// structure.
TEST_F(update, zero_radius_revival) {
    struct Case {
        bool lss;
        uint32_t indexing, caps;
    };
    const Case cases[] = {{false, 0, 0},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV, VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV},
                          {true, VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV,
                           VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV}};
    for (const Case& c : cases)
        for (int inPlace = 0; inPlace < 2; ++inPlace) {
            SCOPED_TRACE(testing::Message() << "lss " << c.lss << " indexing " << c.indexing << " caps " << c.caps
                                            << " inPlace " << inPlace);
            // Primitive 0 is real at x = -2, primitive 1 degenerate at x = 2 (an LSS from (2, -1, 0) to (2, 1, 0)).
            SweptInput base;
            base.lss = c.lss;
            base.indexingMode = c.indexing;
            base.endCapsMode = c.caps;
            if (!c.lss) {
                base.positions = {{-2, 0, 0}, {2, 0, 0}};
                base.radii = {0.5f, 0.0f};
            } else {
                base.positions = {{-2, -1, 0}, {-2, 1, 0}, {2, -1, 0}, {2, 1, 0}};
                base.radii = {0.5f, 0.5f, 0.0f, 0.0f};
                if (c.indexing == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV) base.indices = {0, 2};
            }
            wireSwept(base, 2, 0);  // not opaque: every candidate goes back to the application
            BuildOptions opt;
            opt.flags = kAllowUpdate;
            AccelStruct* blas = buildBlas({base.geometry}, {base.range}, opt);
            EXPECT_EQ(recordCount(blas), 2u);
            oracle::Ray through, beside, onPoint;  // through the segment's middle / the sphere's centre, beside it
            through.origin = {2, 0, 3}, through.direction = {0, 0, -1}, through.tMax = 10;
            beside.origin = {2.3f, 0, 3}, beside.direction = {0, 0, -1}, beside.tMax = 10;
            onPoint.origin = {2, c.lss ? -1.0f : 0.0f, 3}, onPoint.direction = {0, 0, -1}, onPoint.tMax = 10;
            oracle::Ray real = through;
            real.origin[0] = -2;
            {
                AccelStruct* tlas = buildSingleInstanceTlas(blas);
                EXPECT_EQ(traceClosest(tlas, through).type, 0u);
                EXPECT_EQ(traceClosest(tlas, onPoint).type, 0u);
                const Hit h = traceClosest(tlas, real);
                EXPECT_EQ(h.type, 1u);
                EXPECT_EQ(h.primitiveIndex, 0);
                for (const auto& ray : {through, onPoint}) {
                    EXPECT_TRUE(query(tlas->handle, ray, 0, 0xFF).candidates.empty()) << "a degenerate candidate";
                    EXPECT_EQ(traceClosest(tlas, ray, VKAS_RAY_FLAG_OPAQUE).type, 0u);
                }
                checkRays(tlas, {through, beside, onPoint, real});
            }
            // Revived: radius 0.5 (LSS: both ends). Valid usage, so the fixture sees no validation message.
            std::vector<float> radii = base.radii;
            for (size_t v = c.lss ? 2 : 1; v < radii.size(); ++v) radii[v] = 0.5f;
            auto g1 = withData(base, base.positions, radii);
            AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
            EXPECT_TRUE(takeValidationErrors().empty());
            {
                AccelStruct* tlas = buildSingleInstanceTlas(out);
                const Hit h = traceClosest(tlas, through);
                EXPECT_EQ(h.type, 1u);
                EXPECT_EQ(h.primitiveIndex, 1);
                EXPECT_FLOAT_EQ(h.t, 2.5f);
                EXPECT_EQ(traceClosest(tlas, beside).primitiveIndex, 1);
                checkRays(tlas, {through, beside, onPoint, real});
                checkSweptBlas(out, 60);
            }
            // Back to zero (and moved): never hit again.
            std::vector<Float3> pos = base.positions;
            for (size_t v = c.lss ? 2 : 1; v < pos.size(); ++v) pos[v][2] = 0.25f;
            auto g2 = withData(base, pos, base.radii);
            AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
            {
                AccelStruct* tlas = buildSingleInstanceTlas(out2);
                EXPECT_EQ(traceClosest(tlas, through).type, 0u);
                EXPECT_EQ(traceClosest(tlas, onPoint).type, 0u);
                for (const auto& ray : {through, onPoint})
                    EXPECT_TRUE(query(tlas->handle, ray, 0, 0xFF).candidates.empty()) << "a degenerate candidate";
                checkRays(tlas, {through, beside, onPoint, real});
            }
            // And revived once more, from the refitted structure.
            auto g3 = withData(base, pos, radii);
            AccelStruct* out3 = updateBlas(out2, inPlace ? out2 : nullptr, {g3->geometry}, {g3->range}, opt);
            {
                AccelStruct* tlas = buildSingleInstanceTlas(out3);
                const Hit h = traceClosest(tlas, through);
                EXPECT_EQ(h.primitiveIndex, 1);
                EXPECT_FLOAT_EQ(h.t, 2.25f);
            }
            if (HasFailure()) return;
        }
}

// ---- [NV-motion] motion triangles and motion top levels ---------------------------------------------------------

// A motion bottom level (positions at time 0 and 1) refitted to moved positions at both times, in place and into
// another structure, under a plain and a motion top level; traced at several ray times against the oracle.
TEST_F(update, motion_triangles) {
    for (int round = 0; round < 4; ++round) {
        const bool inPlace = round % 2 == 1, indexed = round < 2;
        SCOPED_TRACE(testing::Message() << "inPlace " << inPlace << " indexed " << indexed);
        Mesh m = triangleSoup(40 + int(rng.below(80)), rng, 0.4f);
        Mesh s = triangleSoup(10 + int(rng.below(20)), rng, 0.3f);
        auto a0 = makeMotionInput(m, deform(m, rng, 0.5f).positions, indexed, VK_GEOMETRY_OPAQUE_BIT_KHR);
        auto b0 = makeMotionInput(s, deform(s, rng, 0.3f).positions, !indexed, 0);
        AccelStruct* blas = motionBlas({a0.get(), b0.get()});
        // New positions at both times (the index buffers stay).
        auto a1 = makeMotionInput(deform(m, rng, 0.3f), deform(m, rng, 0.8f).positions, indexed, VK_GEOMETRY_OPAQUE_BIT_KHR);
        auto b1 = makeMotionInput(deform(s, rng, 0.3f), deform(s, rng, 0.3f).positions, !indexed, 0);
        AccelStruct* out = motionBlas({a1.get(), b1.get()}, blas, inPlace ? blas : nullptr);
        // Under a plain top level (one identity instance; traced at the query's time all the same)...
        AccelStruct* plain = buildSingleInstanceTlas(out);
        oracle::MotionScene plainScene;
        oracle::MotionInstance mi;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) mi.transform0[r][c] = mi.transform1[r][c] = r == c ? 1.0 : 0.0;
        mi.base = plain->scene->instances[0];
        plainScene.instances.push_back(mi);
        EXPECT_GT(checkMotion(plain, plainScene, 60), 0u);
        // ...and under static, matrix and SRT instances of a motion top level.
        std::vector<MotionDesc> descs = {randomMotionDesc(rng, out, 0), randomMotionDesc(rng, out, 1),
                                         randomMotionDesc(rng, out, 2)};
        oracle::MotionScene scene;
        AccelStruct* tlas = motionTlas(descs, scene);
        EXPECT_GT(checkMotion(tlas, scene, 80), 0u);
        // A second refit, from the refitted structure, back to the first inputs.
        AccelStruct* out2 = motionBlas({a0.get(), b0.get()}, out, inPlace ? out : nullptr);
        AccelStruct* plain2 = buildSingleInstanceTlas(out2);
        plainScene.instances[0].base = plain2->scene->instances[0];
        EXPECT_GT(checkMotion(plain2, plainScene, 60), 0u);
        if (HasFailure()) return;
    }
}

// A motion top level (static, matrix-motion and SRT-motion instances, some inactive) refitted to new transforms,
// ids, masks and bottom levels (the type of each instance kept), in place and into another structure; then a motion
// bottom level refitted and the top level updated again so that its instance boxes follow. Traced at several times.
TEST_F(instance_update, motion_instances) {
    Mesh m = triangleSoup(30, rng, 0.4f);
    auto mg = makeMotionInput(m, deform(m, rng, 0.4f).positions, true, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* motion = motionBlas({mg.get()});
    auto ig = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* still = buildBlas(*ig);
    AccelStruct* blases[2] = {motion, still};
    for (int round = 0; round < 4; ++round) {
        const bool inPlace = round % 2 == 1;
        SCOPED_TRACE(testing::Message() << "round " << round);
        std::vector<MotionDesc> descs;
        const int n = 4 + int(rng.below(10));
        for (int i = 0; i < n; ++i)
            descs.push_back(randomMotionDesc(rng, rng.coin(0.15) ? nullptr : blases[rng.below(2)], rng.below(3)));
        oracle::MotionScene scene;
        AccelStruct* tlas = motionTlas(descs, scene);
        EXPECT_GT(checkMotion(tlas, scene, 60), 0u);
        for (auto& d : descs)  // inactive instances stay inactive, active ones stay active
            if (d.blas) d = randomMotionDesc(rng, blases[rng.below(2)], d.type);
        AccelStruct* out = motionTlas(descs, scene, tlas, inPlace ? tlas : nullptr);
        EXPECT_GT(checkMotion(out, scene, 100), 0u);
        if (HasFailure()) return;
    }
    // The motion bottom level refitted (larger at both times), then the top level updated in place.
    std::vector<MotionDesc> descs;
    for (int i = 0; i < 6; ++i) descs.push_back(randomMotionDesc(rng, motion, uint32_t(i % 3)));
    oracle::MotionScene scene;
    AccelStruct* tlas = motionTlas(descs, scene);
    Mesh big = m;
    for (auto& p : big.positions)
        for (float& c : p) c *= 2.0f;
    auto mg1 = makeMotionInput(big, deform(big, rng, 0.6f).positions, true, VK_GEOMETRY_OPAQUE_BIT_KHR);
    motionBlas({mg1.get()}, motion, motion);
    AccelStruct* out = motionTlas(descs, scene, tlas, tlas);
    EXPECT_GT(checkMotion(out, scene, 150), 0u);
}

// ---- refit cost ---------------------------------------------------------------------------------------------------

// 2^20 triangles: a refit costs a small fraction of a build (printed; docs/PERFORMANCE.md "Refit").
// A large refit (2^18 triangles, every vertex moved) traces right. How long it takes against a build is measured by
// bench/refit.cpp, not here (tests are not timed).
TEST_F(update, large_refit) {
    const int n = 256;  // 256 x 512 quads = 2^18 triangles
    Mesh m = grid(n, 2 * n);
    for (auto& p : m.positions) p[2] = 0.1f * std::sin(p[0] * 0.3f) * std::cos(p[1] * 0.2f);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    ASSERT_EQ(g0->range.primitiveCount, 1u << 18);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    auto pb = prepareBlas({g0.get()}, opt);
    submit({pb.get()});
    AccelStruct* blas = pb->as;
    Mesh moved = m;
    for (auto& p : moved.positions) p[2] += 0.05f * std::sin(p[0] * 0.7f + p[1]);
    auto g1 = makeGeometry(moved, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto pu = prepareBlas({g1.get()}, opt);
    submitUpdate(*pu, blas, blas);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    for (int k = 0; k < 200; ++k) {
        oracle::Ray r;
        r.origin = {rng.uniformf(1, float(n) - 1), rng.uniformf(1, float(2 * n) - 1), 1.0f};
        r.direction = {0, 0, -1};
        r.tMax = 10;
        const Hit h = traceClosest(tlas, r);
        ASSERT_EQ(h.type, 1u);
    }
    checkRays(tlas, randomRays(*tlas->scene, 100));
}

// ---- valid usage ----------------------------------------------------------------------------------------------------

class update_validation : public update {
  protected:
    struct Fixture {
        Mesh mesh;
        std::unique_ptr<GeometryData> data;
        AccelStruct* blas = nullptr;
        BuildOptions opt;
    };
    Fixture makeFixture(VkBuildAccelerationStructureFlagsKHR flags = kAllowUpdate, bool transform = false) {
        Fixture f;
        f.mesh = triangleSoup(40, rng, 0.3f);
        f.mesh.positions.push_back({kNaN, 0, 0});  // triangle 0 is inactive
        f.mesh.indices[0] = uint32_t(f.mesh.positions.size() - 1);
        const VkTransformMatrixKHR t = identityTransform();
        f.data = makeGeometry(f.mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR, transform ? &t : nullptr);
        f.opt.flags = flags;
        f.blas = buildBlas(*f.data, f.opt);
        return f;
    }
    // Runs one UPDATE (src into dst) and returns the validation messages; checks that dst was not written.
    std::vector<std::string> tryUpdate(VkAccelerationStructureKHR src, AccelStruct* dst,
                                       VkAccelerationStructureBuildGeometryInfoKHR info,
                                       const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
        EXPECT_TRUE(takeValidationErrors().empty());
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        info.srcAccelerationStructure = src;
        info.dstAccelerationStructure = dst->handle;
        info.scratchData.hostAddress = nullptr;
        const std::vector<uint8_t> before(dst->buffer->mapped, dst->buffer->mapped + dst->buffer->size);
        const VkAccelerationStructureBuildRangeInfoKHR* r = ranges.data();
        EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &r),
                  VK_ERROR_VALIDATION_FAILED_EXT);
        EXPECT_EQ(std::memcmp(before.data(), dst->buffer->mapped, before.size()), 0) << "dst was written";
        return takeValidationErrors();
    }
    VkAccelerationStructureBuildGeometryInfoKHR blasInfo(const std::vector<VkAccelerationStructureGeometryKHR>& g,
                                                         VkBuildAccelerationStructureFlagsKHR flags) {
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.flags = flags;
        info.geometryCount = uint32_t(g.size());
        info.pGeometries = g.data();
        return info;
    }
    static bool only(const std::vector<std::string>& errors, const char* vuid) {
        return errors.size() == 1 && errors[0].find(vuid) != std::string::npos;
    }
};

#define EXPECT_ONLY(errors, vuid)                                                       \
    do {                                                                                \
        const auto e_ = (errors);                                                       \
        EXPECT_TRUE(only(e_, vuid)) << vuid << ": got " << e_.size() << " messages"     \
                                    << (e_.empty() ? std::string() : ": " + e_[0]);     \
    } while (0)

TEST_F(update_validation, source) {
    Fixture f = makeFixture();
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    const auto info = blasInfo(g, f.opt.flags);
    AccelStruct* dst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {});
    EXPECT_ONLY(tryUpdate(VK_NULL_HANDLE, dst, info, {f.data->range}), "VUID-vkBuildAccelerationStructuresKHR-pInfos-04630");
    AccelStruct* dead = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 4096, {});
    const VkAccelerationStructureKHR deadHandle = dead->handle;
    destroyAccelStruct(dead);
    EXPECT_ONLY(tryUpdate(deadHandle, dst, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-srcAccelerationStructure-04629");
    {
        // A structure whose buffer has no memory: create it by hand.
        HostBuffer* b = createBuffer(f.blas->size, kAsBufferUsage, false);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = b->buffer;
        ci.size = f.blas->size;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        VkAccelerationStructureKHR h;
        ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &h), VK_SUCCESS);
        EXPECT_ONLY(tryUpdate(h, dst, info, {f.data->range}), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03708");
        vk.vkDestroyAccelerationStructureKHR(device, h, nullptr);
    }
    AccelStruct* unbuilt = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {});
    EXPECT_ONLY(tryUpdate(unbuilt->handle, dst, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667");
    Fixture noUpdate = makeFixture(0);
    EXPECT_ONLY(tryUpdate(noUpdate.blas->handle, dst, blasInfo(g, 0), {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667");
    // dst too small for the source's usedSize (and for a build).
    AccelStruct* tiny = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {});
    EXPECT_ONLY(tryUpdate(f.blas->handle, tiny, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-10126");
}

TEST_F(update_validation, aliasing) {
    Fixture f = makeFixture();
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    // A second structure over the second half of the source's buffer range: src != dst, memory overlaps.
    const VkDeviceSize size = f.blas->size;
    HostBuffer* b = createBuffer(2 * size + 512);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = b->buffer;
    ci.size = size;
    ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR a, c;
    ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &a), VK_SUCCESS);
    ci.offset = (size / 2 + 255) / 256 * 256;
    ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &c), VK_SUCCESS);
    // Build into a.
    auto pb = prepareBlas({f.data.get()}, f.opt);
    pb->info.dstAccelerationStructure = a;
    const VkAccelerationStructureBuildRangeInfoKHR* r = pb->ranges.data();
    ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &pb->info, &r), VK_SUCCESS);
    AccelStruct view;
    view.handle = c;
    view.buffer = b;
    view.offset = ci.offset;
    view.size = size;
    const auto errors = tryUpdate(a, &view, blasInfo(g, f.opt.flags), {f.data->range});
    EXPECT_ONLY(errors, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03668");
    vk.vkDestroyAccelerationStructureKHR(device, a, nullptr);
    vk.vkDestroyAccelerationStructureKHR(device, c, nullptr);
}

TEST_F(update_validation, must_match_last_build) {
    Fixture f = makeFixture();
    AccelStruct* dst = f.blas;  // in place: nothing may be written either
    const auto& base = f.data->geometry;
    auto expectOnly = [&](std::vector<VkAccelerationStructureGeometryKHR> g,
                          std::vector<VkAccelerationStructureBuildRangeInfoKHR> r,
                          VkBuildAccelerationStructureFlagsKHR flags, const char* vuid) {
        SCOPED_TRACE(vuid);
        EXPECT_ONLY(tryUpdate(f.blas->handle, dst, blasInfo(g, flags), r), vuid);
    };
    const auto range = f.data->range;
    // 03758 geometryCount.
    expectOnly({base, base}, {range, range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03758");
    // 03759 flags.
    expectOnly({base}, {range}, f.opt.flags | VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
               "VUID-vkBuildAccelerationStructuresKHR-pInfos-03759");
    // 03761 geometryType: AABBs instead of triangles, same count.
    std::vector<VkAabbPositionsKHR> boxes(range.primitiveCount, VkAabbPositionsKHR{0, 0, 0, 1, 1, 1});
    boxes[0].minX = kNaN;
    expectOnly({aabbGeometry(boxes, base.flags)}, {range}, f.opt.flags,
               "VUID-vkBuildAccelerationStructuresKHR-pInfos-03761");
    // 03762 geometry flags.
    {
        auto g = base;
        g.flags = 0;
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03762");
    }
    // 03763 vertexFormat: the same positions as R32G32B32A32_SFLOAT.
    auto wide = makeFormatted(f.mesh, VK_FORMAT_R32G32B32A32_SFLOAT, VK_INDEX_TYPE_UINT32, base.flags, nullptr);
    wide->geometry.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex;
    expectOnly({wide->geometry}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03763");
    // 03764 maxVertex.
    {
        auto g = base;
        g.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex + 1;
        std::vector<uint8_t> more(f.data->vertices);
        more.resize(more.size() + 12, 0);
        g.geometry.triangles.vertexData.hostAddress = more.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03764");
    }
    // 03765 indexType: the same index values as UINT16.
    auto narrow = makeFormatted(f.mesh, VK_FORMAT_R32G32B32_SFLOAT, VK_INDEX_TYPE_UINT16, base.flags, nullptr);
    narrow->geometry.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex;
    expectOnly({narrow->geometry}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03765");
    // 03766: a transform now, none in the build.
    {
        const VkTransformMatrixKHR t = identityTransform();
        auto g = base;
        g.geometry.triangles.transformData.hostAddress = &t;
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03766");
    }
    // 03767: no transform now, one in the build.
    {
        Fixture t = makeFixture(kAllowUpdate, true);
        auto g = t.data->geometry;
        g.geometry.triangles.transformData.hostAddress = nullptr;
        EXPECT_ONLY(tryUpdate(t.blas->handle, t.blas, blasInfo({g}, t.opt.flags), {t.data->range}),
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-03767");
    }
    // 03768: index values changed (triangle 1 names its corners in another order).
    {
        std::vector<uint8_t> idx(f.data->indices);
        uint32_t a, b;
        std::memcpy(&a, idx.data() + 12, 4), std::memcpy(&b, idx.data() + 16, 4);
        std::memcpy(idx.data() + 12, &b, 4), std::memcpy(idx.data() + 16, &a, 4);
        auto g = base;
        g.geometry.triangles.indexData.hostAddress = idx.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03768");
    }
    // 03769 primitiveCount.
    {
        auto r = range;
        r.primitiveCount -= 1;
        expectOnly({base}, {r}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769");
    }
    // 03663: an active triangle made inactive.
    {
        std::vector<uint8_t> v(f.data->vertices);
        uint32_t i2;
        std::memcpy(&i2, f.data->indices.data() + 4 * 3 * 5, 4);  // a vertex of triangle 5
        std::memcpy(v.data() + 12 * i2, &kNaN, 4);
        auto g = base;
        g.geometry.triangles.vertexData.hostAddress = v.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
    }
    // 03664: the inactive triangle 0 made active.
    {
        std::vector<uint8_t> v(f.data->vertices);
        const float zero = 0.5f;
        std::memcpy(v.data() + 12 * (f.mesh.positions.size() - 1), &zero, 4);
        auto g = base;
        g.geometry.triangles.vertexData.hostAddress = v.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03664");
    }
    // 03760 type: a top-level update of a bottom-level source (into a GENERIC destination).
    {
        auto blas = buildBlas(*f.data);
        Instance in;
        in.blas = blas;
        auto pb = prepareTlas({in}, {});
        BuildOptions generic;
        generic.createGeneric = true;
        AccelStruct* gdst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, f.blas->size, generic);
        auto info = pb->info;
        info.flags = f.opt.flags;
        EXPECT_ONLY(tryUpdate(f.blas->handle, gdst, info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03760");
    }
    // Still updatable after all that: nothing was written.
    checkBlas(f.blas, 50);
}

// [NV-LSS] 03663 / 03664 for spheres and LSS: a zero radius is degenerate, not inactive, so giving it a radius is
// valid; making an inactive (NaN) primitive active, or an active one (zero radius included) inactive, is not.
TEST_F(update_validation, swept_activity) {
    for (bool lss : {false, true}) {
        SCOPED_TRACE(lss ? "lss" : "spheres");
        SweptInput base;
        base.lss = lss;
        const size_t per = lss ? 2 : 1;
        for (int i = 0; i < 4; ++i)
            for (size_t e = 0; e < per; ++e) base.positions.push_back({float(i), float(e), 0}), base.radii.push_back(0.25f);
        for (size_t e = 0; e < per; ++e) base.radii[0 * per + e] = kNaN;  // primitive 0 inactive
        for (size_t e = 0; e < per; ++e) base.radii[1 * per + e] = 0.0f;  // primitive 1 degenerate
        wireSwept(base, 4, VK_GEOMETRY_OPAQUE_BIT_KHR);
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas({base.geometry}, {base.range}, opt);
        auto tryRadii = [&](std::vector<float> radii, const char* vuid) {
            auto d = withData(base, base.positions, std::move(radii));
            std::vector<VkAccelerationStructureGeometryKHR> gg{d->geometry};
            EXPECT_ONLY(tryUpdate(blas->handle, blas, blasInfo(gg, opt.flags), {d->range}), vuid);
        };
        {
            auto r = base.radii;
            for (size_t e = 0; e < per; ++e) r[0 * per + e] = 0.5f;
            tryRadii(r, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03664");
        }
        {
            auto r = base.radii;
            r[1 * per] = kNaN;
            tryRadii(r, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
        }
        {
            auto r = base.radii;
            r[2 * per] = kNaN;
            tryRadii(r, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
        }
        // The degenerate primitive given a radius: valid, and hit.
        auto r = base.radii;
        for (size_t e = 0; e < per; ++e) r[1 * per + e] = 0.25f;
        auto d = withData(base, base.positions, r);
        AccelStruct* out = updateBlas(blas, blas, {d->geometry}, {d->range}, opt);
        EXPECT_TRUE(takeValidationErrors().empty());
        oracle::Ray ray;
        ray.origin = {1, lss ? 0.5f : 0.0f, 2}, ray.direction = {0, 0, -1}, ray.tMax = 10;
        const Hit h = traceClosest(buildSingleInstanceTlas(out), ray);
        EXPECT_EQ(h.primitiveIndex, 1);
    }
}

TEST_F(update_validation, instance_activity) {
    auto g = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*g);
    std::vector<Instance> instances(4);
    for (auto& in : instances) in.blas = blas;
    instances[2].blas = nullptr;
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* tlas = buildTlas(instances, opt);
    {
        auto changed = instances;
        changed[1].blas = nullptr;
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
    }
    {
        auto changed = instances;
        changed[2].blas = blas;
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03664");
    }
    {
        auto changed = instances;
        changed.pop_back();
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769");
    }
    checkRays(tlas, randomRays(*tlas->scene, 50));
}

// Another element's destination overlapping an update's source (03701), and an update's source being another
// element's destination (03403).
TEST_F(update_validation, between_infos) {
    Fixture f = makeFixture();
    auto pb = prepareBlas({f.data.get()}, f.opt);  // a build into pb->as
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    VkAccelerationStructureBuildGeometryInfoKHR infos[2] = {blasInfo(g, f.opt.flags), pb->info};
    infos[0].mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    infos[0].srcAccelerationStructure = f.blas->handle;
    infos[0].dstAccelerationStructure = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {})->handle;
    infos[1].dstAccelerationStructure = f.blas->handle;
    const VkAccelerationStructureBuildRangeInfoKHR* r[2] = {&f.data->range, &f.data->range};
    EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 2, infos, r), VK_ERROR_VALIDATION_FAILED_EXT);
    const auto errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u) << (errors.empty() ? "" : errors[0]);
    EXPECT_NE(errors[0].find("VUID-vkBuildAccelerationStructuresKHR-pInfos-03403"), std::string::npos);
}

// ---- specialised triangle refit (issue 7) ---------------------------------------------------------------------------

namespace {

struct RefitFormat {
    VkFormat format;
    uint32_t size, componentSize, components;  // components stored (a 4th is ignored by the decode)
    int kind;                                  // 0 float32, 1 float16, 2 float64, 3 integer bits (SNORM / UNORM)
};
const RefitFormat kRefitFormats[] = {
    {VK_FORMAT_R32G32_SFLOAT, 8, 4, 2, 0},       {VK_FORMAT_R32G32B32_SFLOAT, 12, 4, 3, 0},
    {VK_FORMAT_R32G32B32A32_SFLOAT, 16, 4, 4, 0}, {VK_FORMAT_R16G16_SFLOAT, 4, 2, 2, 1},
    {VK_FORMAT_R16G16B16_SFLOAT, 6, 2, 3, 1},     {VK_FORMAT_R16G16B16A16_SFLOAT, 8, 2, 4, 1},
    {VK_FORMAT_R16G16_SNORM, 4, 2, 2, 3},         {VK_FORMAT_R16G16B16_SNORM, 6, 2, 3, 3},
    {VK_FORMAT_R16G16B16A16_SNORM, 8, 2, 4, 3},   {VK_FORMAT_R8G8_SNORM, 2, 1, 2, 3},
    {VK_FORMAT_R8G8B8_SNORM, 3, 1, 3, 3},         {VK_FORMAT_R8G8B8A8_SNORM, 4, 1, 4, 3},
    {VK_FORMAT_R64G64_SFLOAT, 16, 8, 2, 2},       {VK_FORMAT_R64G64B64_SFLOAT, 24, 8, 3, 2},
    {VK_FORMAT_R64G64B64A64_SFLOAT, 32, 8, 4, 2}, {VK_FORMAT_A2B10G10R10_UNORM_PACK32, 4, 4, 1, 3},
};

// One vertex component: a value in about [-2, 2] (or raw bits for integer formats), a NaN when `nan`, and now
// and then a signed zero, an infinity or a signalling NaN in Y / Z (kept by an active triangle, never in a box).
void writeComponent(Rng& rng, const RefitFormat& f, bool nan, bool special, uint8_t* out) {
    if (f.kind == 3) {
        for (uint32_t b = 0; b < f.componentSize; ++b) out[b] = uint8_t(rng.u32());
        return;
    }
    const double v = rng.coin(0.2) ? double(rng.range(-2, 2)) : rng.uniform(-2.0, 2.0);
    const uint32_t pick = rng.below(4);
    if (f.kind == 0) {
        float x = float(v);
        uint32_t bits;
        std::memcpy(&bits, &x, 4);
        if (nan) bits = rng.coin() ? 0x7FC0'0000u : 0xFF80'0003u;  // quiet or signalling
        else if (special) bits = pick == 0 ? 0x8000'0000u : pick == 1 ? 0x7F80'0000u : pick == 2 ? 0x7F80'0001u : 1u;
        std::memcpy(out, &bits, 4);
    } else if (f.kind == 1) {
        // half: sign, 5-bit exponent at most 16 (|v| < 4), 10-bit mantissa
        uint16_t bits = uint16_t((rng.u32() & 0x8000) | (rng.below(17) << 10) | (rng.u32() & 0x3FF));
        if (nan) bits = rng.coin() ? 0x7E00 : 0xFC01;
        else if (special) bits = pick == 0 ? 0x8000 : pick == 1 ? 0xFC00 : pick == 2 ? 0x7C01 : 0x0001;
        std::memcpy(out, &bits, 2);
    } else {
        uint64_t bits;
        std::memcpy(&bits, &v, 8);
        if (nan) bits = rng.coin() ? 0x7FF8'0000'0000'0000ull : 0x7FF0'0000'0000'0001ull;
        else if (special) bits = pick == 0 ? 0x8000'0000'0000'0000ull : pick == 1 ? 0x47EF'FFFF'F000'0000ull
                                 : pick == 2 ? 0x7FF0'0000'0000'0001ull : 0x3690'0000'0000'0000ull;  // huge, tiny
        std::memcpy(out, &bits, 8);
    }
}

struct RawTriangles {
    std::vector<uint8_t> vertices, indices, transform;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
};

// Random triangles in format f: `nanX[n]` says which vertices have a NaN X (they make their triangles inactive, in
// both versions of the inputs), some triangles repeat a vertex (degenerate), some components are special values.
std::unique_ptr<RawTriangles> randomRaw(Rng& rng, const RefitFormat& f, VkIndexType it, const std::vector<uint8_t>& nanX,
                                        const std::vector<uint32_t>& indices, bool specials, const VkTransformMatrixKHR* t,
                                        uint32_t firstVertex, uint32_t primitiveOffset) {
    auto g = std::make_unique<RawTriangles>();
    const bool indexed = it != VK_INDEX_TYPE_NONE_KHR;
    const size_t n = indexed ? nanX.size() : indices.size();
    const uint32_t stride = f.size + (f.kind == 3 ? 1 : 0) * f.componentSize;  // an odd stride for integer formats
    g->vertices.assign(1 + (indexed ? 0 : primitiveOffset) + size_t(stride) * (firstVertex + n), 0xAA);
    uint8_t* base = g->vertices.data() + 1;  // misaligned on purpose
    for (size_t k = 0; k < n; ++k) {
        const uint32_t vertex = indexed ? uint32_t(k) : indices[k];
        uint8_t* p = base + (indexed ? 0 : primitiveOffset) + size_t(stride) * (firstVertex + k);
        for (uint32_t c = 0; c < f.components; ++c)
            writeComponent(rng, f, c == 0 && nanX[vertex] && f.kind != 3, specials && c > 0 && rng.coin(0.03),
                           p + c * f.componentSize);
        if (!nanX[vertex] && f.kind != 3) {  // X must stay a number: the activity of a triangle may not change
            double d;
            uint8_t* x = p;
            if (f.kind == 0) {
                float v;
                std::memcpy(&v, x, 4);
                d = v;
            } else if (f.kind == 2) {
                std::memcpy(&d, x, 8);
            } else {
                uint16_t h;
                std::memcpy(&h, x, 2);
                d = (h & 0x7C00) == 0x7C00 ? NAN : 0.0;
            }
            if (std::isnan(d)) std::memset(x, 0, f.componentSize);
        }
    }
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = f.format;
    tri.vertexStride = stride;
    tri.vertexData.hostAddress = base;
    tri.maxVertex = uint32_t(n + 2);  // independent of firstVertex: an update must keep it (03764)
    tri.indexType = it;
    if (indexed) {
        const uint32_t size = it == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        g->indices.assign(1 + primitiveOffset + indices.size() * size, 0xAA);
        for (size_t k = 0; k < indices.size(); ++k)
            std::memcpy(g->indices.data() + 1 + primitiveOffset + k * size, &indices[k], size);
        tri.indexData.hostAddress = g->indices.data() + 1;
    }
    if (t) {
        g->transform.assign(16 + sizeof *t, 0xAA);
        std::memcpy(g->transform.data() + 16, t, sizeof *t);
        tri.transformData.hostAddress = g->transform.data();
    }
    g->range.primitiveCount = uint32_t(indices.size() / 3);
    g->range.primitiveOffset = indexed ? primitiveOffset : primitiveOffset;
    g->range.firstVertex = firstVertex;
    g->range.transformOffset = t ? 16 : 0;
    return g;
}

template <class T>
T load(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// Same float, or both zero (the sign of a zero box coordinate may differ: docs/FORMAT.md, "Update (refit)").
bool sameBoxCoordinate(float a, float b) { return std::memcmp(&a, &b, 4) == 0 || (a == 0.0f && b == 0.0f); }

// Checks a refitted bottom level of triangle records against its source, from the bytes alone (docs/FORMAT.md):
// everything but the bounds, the node boxes and the records' positions and degenerate bits unchanged; every node
// slot the exact min / max of the records below it (NaN coordinates ignored, inactive records -- none here --
// excluded); the header bounds the root's.
::testing::AssertionResult refitStructureIsExact(const std::vector<uint8_t>& src, const uint8_t* dst) {
    const uint64_t used = load<uint64_t>(src.data() + 16);
    const uint64_t nodeOffset = load<uint64_t>(src.data() + 80), recordOffset = load<uint64_t>(src.data() + 88);
    const uint32_t nodeCount = load<uint32_t>(src.data() + 68), recordCount = load<uint32_t>(src.data() + 64);
    if (std::memcmp(src.data(), dst, 32) || std::memcmp(src.data() + 56, dst + 56, nodeOffset - 56))
        return ::testing::AssertionFailure() << "header or geometry table changed";
    const uint64_t nodeEnd = nodeOffset + 256ull * nodeCount;
    if (std::memcmp(src.data() + nodeEnd, dst + nodeEnd, recordOffset - nodeEnd))
        return ::testing::AssertionFailure() << "gap changed";
    const std::vector<uint8_t> srcRecords = vt::triangleRecordsOf(src.data()), dstRecords = vt::triangleRecordsOf(dst);
    for (uint32_t j = 0; j < recordCount; ++j) {
        const uint64_t r = 48ull * j;
        if (std::memcmp(srcRecords.data() + r + 36, dstRecords.data() + r + 36, 8) ||
            (load<uint32_t>(srcRecords.data() + r + 44) & ~2u) != (load<uint32_t>(dstRecords.data() + r + 44) & ~2u))
            return ::testing::AssertionFailure() << "record " << j << " names another primitive or changed flags";
    }
    if (recordOffset + 44ull * recordCount + (recordCount ? 4 : 0) != used)
        return ::testing::AssertionFailure() << "usedSize";
    auto slotBox = [&](uint64_t ref, float lo[3], float hi[3]) -> bool {
        for (int c = 0; c < 3; ++c) lo[c] = INFINITY, hi[c] = -INFINITY;
        const uint64_t kind = ref >> 62;
        if (kind == 2) {
            const uint64_t first = ref & 0xFF'FFFF'FFFFull, count = (ref >> 40) & 0xFF;
            for (uint64_t j = first; j < first + count; ++j)
                for (int v = 0; v < 3; ++v)
                    for (int c = 0; c < 3; ++c) {
                        const float x = load<float>(dstRecords.data() + 48 * j + 12 * v + 4 * c);
                        if (x < lo[c]) lo[c] = x;  // NaN never compares
                        if (x > hi[c]) hi[c] = x;
                    }
        } else if (kind == 1) {
            const uint8_t* child = dst + nodeOffset + 256ull * uint32_t(ref);
            for (int i = 0; i < 8; ++i)
                for (int c = 0; c < 3; ++c) {
                    lo[c] = std::min(lo[c], load<float>(child + 64 * c + 4 * i));
                    hi[c] = std::max(hi[c], load<float>(child + 64 * c + 32 + 4 * i));
                }
        } else if (kind != 0) {
            return false;
        }
        return true;
    };
    for (uint32_t k = 0; k < nodeCount; ++k) {
        const uint8_t* n = dst + nodeOffset + 256ull * k;
        if (std::memcmp(src.data() + nodeOffset + 256ull * k + 192, n + 192, 64))
            return ::testing::AssertionFailure() << "node " << k << " children changed";
        for (int i = 0; i < 8; ++i) {
            float lo[3], hi[3];
            if (!slotBox(load<uint64_t>(n + 192 + 8 * i), lo, hi)) return ::testing::AssertionFailure() << "bad ref";
            for (int c = 0; c < 3; ++c)
                if (!sameBoxCoordinate(load<float>(n + 64 * c + 4 * i), lo[c]) ||
                    !sameBoxCoordinate(load<float>(n + 64 * c + 32 + 4 * i), hi[c]))
                    return ::testing::AssertionFailure() << "node " << k << " slot " << i << " axis " << c << ": box "
                                                         << load<float>(n + 64 * c + 4 * i) << ".."
                                                         << load<float>(n + 64 * c + 32 + 4 * i) << ", records "
                                                         << lo[c] << ".." << hi[c];
        }
    }
    float lo[3], hi[3];
    slotBox(load<uint64_t>(dst + 24), lo, hi);
    for (int c = 0; c < 3; ++c)
        if (!sameBoxCoordinate(load<float>(dst + 32 + 4 * c), lo[c]) || !sameBoxCoordinate(load<float>(dst + 44 + 4 * c), hi[c]))
            return ::testing::AssertionFailure() << "header bounds, axis " << c;
    return ::testing::AssertionSuccess();
}

}  // namespace

// The specialised refit (and the build fetch it shares) for every vertex format, index type NONE / UINT16 / UINT32,
// with and without a geometry transform, in place, into another structure and from a compacted copy, on random
// inputs with inactive (NaN X, quiet and signalling), degenerate (a repeated vertex) and special-valued triangles:
// (1) every refitted record is bit for bit the record a fresh ALLOW_UPDATE build of the new inputs stores for that
// primitive (positions, degenerate bit); (2) the refitted bytes keep the source's topology and every node box is
// the exact min / max of the records below it; (3) a second refit back to the first inputs gives the first build's
// bytes (up to the sign of a zero box coordinate); (4) float3 inputs without specials trace like the oracle.
TEST_F(update, specialised_refit_matches_build_for_every_format) {
    int combination = 0;
    uint64_t records = 0, degenerate = 0;
    for (const RefitFormat& f : kRefitFormats)
        for (VkIndexType it : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
            for (int transformed = 0; transformed < 2; ++transformed, ++combination) {
                const int mode = combination % 3;  // 0 in place, 1 into another structure, 2 from a compacted copy
                const bool specials = combination % 2 == 0;
                SCOPED_TRACE(testing::Message() << "format " << f.format << " index " << it << " transform "
                                                << transformed << " mode " << mode << " specials " << specials);
                const uint32_t vertexCount = 30 + rng.below(100), triangles = 40 + rng.below(200);
                std::vector<uint8_t> nanX(vertexCount);
                for (auto& x : nanX) x = rng.coin(0.03);
                std::vector<uint32_t> indices(3 * triangles);
                for (uint32_t k = 0; k < indices.size(); ++k)
                    indices[k] = k % 3 && rng.coin(0.05) ? indices[k - 1] : rng.below(vertexCount);  // repeats: degenerate
                const VkTransformMatrixKHR t0 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                const VkTransformMatrixKHR t1 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                const uint32_t firstVertex = rng.below(3), offset = 8 * rng.below(3);  // a multiple of every component and index size
                auto a = randomRaw(rng, f, it, nanX, indices, specials, transformed ? &t0 : nullptr, firstVertex, offset);
                auto b = randomRaw(rng, f, it, nanX, indices, specials, transformed ? &t1 : nullptr, rng.below(3), offset);
                BuildOptions opt;
                opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
                opt.usePointers = rng.coin();
                AccelStruct* built = buildBlas({a->geometry}, {a->range}, opt);
                const uint64_t used = load<uint64_t>(built->data() + 16);
                const std::vector<uint8_t> original(built->data(), built->data() + used);
                AccelStruct* src = mode == 2 ? compactCopy(built) : built;
                const std::vector<uint8_t> before(src->data(), src->data() + used);
                AccelStruct* out = updateBlas(src, mode == 0 ? src : nullptr, {b->geometry}, {b->range}, opt);
                // (1) the records of a fresh build of the new inputs
                AccelStruct* fresh = buildBlas({b->geometry}, {b->range}, opt);
                const uint32_t n = load<uint32_t>(out->data() + 64);
                ASSERT_EQ(load<uint32_t>(fresh->data() + 64), n);
                std::map<uint64_t, const uint8_t*> byPrimitive;
                const std::vector<uint8_t> freshCopy = vt::triangleRecordsOf(fresh->data());
                const uint8_t* freshRecords = freshCopy.data();
                for (uint32_t j = 0; j < n; ++j)
                    byPrimitive[load<uint64_t>(freshRecords + 48ull * j + 36)] = freshRecords + 48ull * j;
                const std::vector<uint8_t> outCopy = vt::triangleRecordsOf(out->data());
                const uint8_t* outRecords = outCopy.data();
                for (uint32_t j = 0; j < n; ++j) {
                    const uint8_t* r = outRecords + 48ull * j;
                    auto found = byPrimitive.find(load<uint64_t>(r + 36));
                    ASSERT_NE(found, byPrimitive.end()) << "record " << j;
                    ASSERT_EQ(std::memcmp(r, found->second, 48), 0)
                        << "record " << j << " (primitive " << load<uint32_t>(r + 40) << ") differs from the build's";
                    degenerate += (load<uint32_t>(r + 44) & 2) != 0;
                }
                records += n;
                // (2) topology kept, node boxes exact
                ASSERT_TRUE(refitStructureIsExact(before, out->data()));
                // (3) back to the first inputs (in place): the first build's bytes
                AccelStruct* back = updateBlas(out, out, {a->geometry}, {a->range}, opt);
                for (uint64_t i = 0; i < used; i += 4)
                    ASSERT_TRUE(sameBoxCoordinate(load<float>(original.data() + i), load<float>(back->data() + i)))
                        << "byte " << i;
                // (4) the oracle
                if (f.format == VK_FORMAT_R32G32B32_SFLOAT && !specials) {
                    AccelStruct* again = updateBlas(back, back, {b->geometry}, {b->range}, opt);
                    checkBlas(again, 60);
                }
                if (HasFailure()) return;
            }
    EXPECT_GT(degenerate, 0u);
    std::cout << records << " records compared, " << degenerate << " degenerate" << std::endl;
}

// Several geometries of different formats, index types and transforms in one structure (the refit switches
// readers between and within nodes), against a fresh build and the structure check, in place and not.
TEST_F(update, specialised_refit_mixed_geometries) {
    for (int round = 0; round < 6; ++round) {
        const int geometries = 2 + int(rng.below(4));
        std::vector<std::unique_ptr<RawTriangles>> a, b;
        std::vector<VkAccelerationStructureGeometryKHR> ga, gb;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> ra, rb;
        for (int g = 0; g < geometries; ++g) {
            const RefitFormat& f = kRefitFormats[rng.below(uint32_t(std::size(kRefitFormats)))];
            const VkIndexType it = std::array{VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32}[rng.below(3)];
            const uint32_t vertexCount = 20 + rng.below(50), triangles = 10 + rng.below(150);
            std::vector<uint8_t> nanX(vertexCount);
            for (auto& x : nanX) x = rng.coin(0.03);
            std::vector<uint32_t> indices(3 * triangles);
            for (uint32_t& i : indices) i = rng.below(vertexCount);
            const bool transformed = rng.coin();
            const VkTransformMatrixKHR t = randomTransform(rng, 0.5f, 2.0f, false, 2.0f);
            a.push_back(randomRaw(rng, f, it, nanX, indices, rng.coin(), transformed ? &t : nullptr, 0, 0));
            b.push_back(randomRaw(rng, f, it, nanX, indices, rng.coin(), transformed ? &t : nullptr, 1, 0));
            ga.push_back(a.back()->geometry), ra.push_back(a.back()->range);
            gb.push_back(b.back()->geometry), rb.push_back(b.back()->range);
        }
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* built = buildBlas(ga, ra, opt);
        const uint64_t used = load<uint64_t>(built->data() + 16);
        const std::vector<uint8_t> before(built->data(), built->data() + used);
        AccelStruct* out = updateBlas(built, round % 2 ? built : nullptr, gb, rb, opt);
        AccelStruct* fresh = buildBlas(gb, rb, opt);
        const uint32_t n = load<uint32_t>(out->data() + 64);
        ASSERT_EQ(load<uint32_t>(fresh->data() + 64), n);
        std::map<uint64_t, const uint8_t*> byPrimitive;
        const std::vector<uint8_t> freshCopy = vt::triangleRecordsOf(fresh->data());
        const uint8_t* fr = freshCopy.data();
        for (uint32_t j = 0; j < n; ++j) byPrimitive[load<uint64_t>(fr + 48ull * j + 36)] = fr + 48ull * j;
        const std::vector<uint8_t> outCopy = vt::triangleRecordsOf(out->data());
        const uint8_t* orec = outCopy.data();
        for (uint32_t j = 0; j < n; ++j) {
            auto found = byPrimitive.find(load<uint64_t>(orec + 48ull * j + 36));
            ASSERT_NE(found, byPrimitive.end());
            ASSERT_EQ(std::memcmp(orec + 48ull * j, found->second, 48), 0) << "record " << j;
        }
        ASSERT_TRUE(refitStructureIsExact(before, out->data()));
    }
}
