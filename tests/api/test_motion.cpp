// [NV-motion] VK_NV_ray_tracing_motion_blur (the CTS has its motion cases under ray_tracing_pipeline.*motion*;
// this group covers the host side): motion top-level structures of VkAccelerationStructureMotionInstanceNV
// (static, matrix-motion and SRT-motion instances, in arrays with the 160-byte stride and as typed pointers),
// motion triangles (VkAccelerationStructureGeometryMotionTrianglesDataNV) in every vertex format, with and without
// indices, offsets and geometry transforms, inactive instances, masks and ray flags, vkasRayQueryInitializeMotion
// at time 0, 1 and random times with its time rule (06366), the interpolated transform and position getters, the
// bounds of rotating SRT instances, and the motion build rules (04927, 04928, 04929, 04954, 04955, 04930, the
// motion instance type and flags). Everything is checked against the brute-force oracle evaluated at the ray
// time; every test prints its seed.
#include <cmath>
#include <cstring>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {

constexpr VkBuildAccelerationStructureFlagsKHR kMotionBuild = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
constexpr VkAccelerationStructureCreateFlagsKHR kMotionCreate = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;

// ---- Vertex encoding ------------------------------------------------------------------------------------------
// Writes p in `format` (SNORM/UNORM inputs must lie in their range; 4th components get 1).
void encodeVertex(VkFormat format, const double p[3], uint8_t* out) {
    const oracle::FormatInfo& fi = oracle::formatInfo(format);
    if (fi.packed) {
        uint32_t w = 0;
        for (int c = 0; c < 3; ++c) w |= uint32_t(std::lround(std::clamp(p[c], 0.0, 1.0) * 1023.0)) << (10 * c);
        w |= 3u << 30;
        std::memcpy(out, &w, 4);
        return;
    }
    for (uint32_t c = 0; c < fi.components; ++c) {
        const double v = c < 3 ? p[c] : 1.0;
        uint8_t* q = out + c * fi.componentSize;
        switch (fi.componentSize) {
            case 8: std::memcpy(q, &v, 8); break;
            case 4: { const float f = float(v); std::memcpy(q, &f, 4); break; }
            case 2:
                if (fi.isFloat) {
                    const uint16_t h = oracle::floatToHalf(float(v));
                    std::memcpy(q, &h, 2);
                } else {
                    const int16_t s = int16_t(std::lround(std::clamp(v, -1.0, 1.0) * 32767.0));
                    std::memcpy(q, &s, 2);
                }
                break;
            default: { const int8_t s = int8_t(std::lround(std::clamp(v, -1.0, 1.0) * 127.0)); std::memcpy(q, &s, 1); }
        }
    }
}

// A triangle geometry with positions at time 0 and 1 in the same layout: any format, index type, stride,
// primitiveOffset, firstVertex and optional geometry transform. Not copyable (the structures point into it).
struct MotionGeometry {
    std::vector<uint8_t> v0, v1, indices, transform;
    VkAccelerationStructureGeometryMotionTrianglesDataNV motion{};
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    MotionGeometry() = default;
    MotionGeometry(const MotionGeometry&) = delete;
};

struct GeometryLayout {
    VkFormat format = VK_FORMAT_R32G32B32_SFLOAT;
    VkIndexType indexType = VK_INDEX_TYPE_UINT32;
    uint32_t extraStride = 0;  // multiple of the component size
    uint32_t primitiveOffset = 0;
    uint32_t firstVertex = 0;
    bool transform = false;
    bool withMotion = true;  // chain VkAccelerationStructureGeometryMotionTrianglesDataNV
    VkGeometryFlagsKHR flags = 0;
};

std::unique_ptr<MotionGeometry> makeMotionGeometry(const Mesh& mesh, const std::vector<Float3>& at1,
                                                   const GeometryLayout& L, Rng& rng) {
    auto g = std::make_unique<MotionGeometry>();
    const oracle::FormatInfo& fi = oracle::formatInfo(L.format);
    const uint64_t stride = fi.size + L.extraStride;
    const size_t tris = mesh.triangleCount();
    const bool indexed = L.indexType != VK_INDEX_TYPE_NONE_KHR;
    const size_t vertexCount = indexed ? mesh.positions.size() : 3 * tris;
    const uint64_t base = (indexed ? 0 : L.primitiveOffset) + stride * L.firstVertex;
    const size_t bytes = base + stride * vertexCount + 32;
    g->v0.assign(bytes, 0xAA);
    g->v1.assign(bytes, 0xAA);
    for (size_t k = 0; k < vertexCount; ++k) {
        const size_t src = indexed ? k : mesh.indices[k];
        double p0[3], p1[3];
        for (int c = 0; c < 3; ++c) p0[c] = mesh.positions[src][c], p1[c] = at1[src][c];
        encodeVertex(L.format, p0, g->v0.data() + base + stride * k);
        encodeVertex(L.format, p1, g->v1.data() + base + stride * k);
    }
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = L.flags;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = L.format;
    tri.vertexStride = stride;
    tri.indexType = L.indexType;
    tri.vertexData.hostAddress = g->v0.data();
    tri.maxVertex = uint32_t(L.firstVertex + (vertexCount ? vertexCount - 1 : 0));
    if (indexed) {
        const uint32_t isz = L.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        g->indices.assign(L.primitiveOffset + isz * mesh.indices.size() + 4, 0xAA);
        for (size_t i = 0; i < mesh.indices.size(); ++i) {
            const uint32_t v = mesh.indices[i];
            std::memcpy(g->indices.data() + L.primitiveOffset + isz * i, &v, isz);  // little-endian
        }
        tri.indexData.hostAddress = g->indices.data();
    }
    if (L.transform) {
        const VkTransformMatrixKHR m = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 1.0f);
        g->transform.assign(16 + sizeof m, 0);
        std::memcpy(g->transform.data() + 16, &m, sizeof m);
        tri.transformData.hostAddress = g->transform.data();
        g->range.transformOffset = 16;
    }
    g->motion.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV;
    g->motion.vertexData.hostAddress = g->v1.data();
    if (L.withMotion) tri.pNext = &g->motion;
    g->range.primitiveCount = uint32_t(tris);
    g->range.primitiveOffset = L.primitiveOffset;
    g->range.firstVertex = L.firstVertex;
    return g;
}

// Positions moved by up to `amount` on each axis, kept in [lo, hi].
std::vector<Float3> displaced(const Mesh& m, Rng& rng, float amount, float lo = -1e30f, float hi = 1e30f) {
    std::vector<Float3> out = m.positions;
    for (auto& p : out)
        for (float& c : p) c = std::clamp(c + rng.uniformf(-amount, amount), lo, hi);
    return out;
}

// ---- Motion instances ---------------------------------------------------------------------------------------------
VkTransformMatrixKHR axisRotation(double ax, double ay, double az, double angle) {
    const double n = std::sqrt(ax * ax + ay * ay + az * az);
    ax /= n, ay /= n, az /= n;
    const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
    VkTransformMatrixKHR m{};
    const double R[3][3] = {{t * ax * ax + c, t * ax * ay - s * az, t * ax * az + s * ay},
                            {t * ax * ay + s * az, t * ay * ay + c, t * ay * az - s * ax},
                            {t * ax * az - s * ay, t * ay * az + s * ax, t * az * az + c}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m.matrix[i][j] = float(R[i][j]);
    return m;
}

struct MotionInstanceDesc {
    uint32_t type = 0;  // VkAccelerationStructureMotionInstanceTypeNV
    VkTransformMatrixKHR m0 = identityTransform(), m1 = identityTransform();
    VkSRTDataNV s0{}, s1{};
    uint32_t customIndex = 0, mask = 0xFF, sbtOffset = 0, flags = 0;
    const AccelStruct* blas = nullptr;  // null: inactive
};

VkSRTDataNV randomSrt(Rng& rng, float maxTranslation) {
    VkSRTDataNV s{};
    s.sx = rng.uniformf(0.5f, 2.0f), s.sy = rng.uniformf(0.5f, 2.0f), s.sz = rng.uniformf(0.5f, 2.0f);
    s.a = rng.uniformf(-0.3f, 0.3f), s.b = rng.uniformf(-0.3f, 0.3f), s.c = rng.uniformf(-0.3f, 0.3f);
    s.pvx = rng.uniformf(-1, 1), s.pvy = rng.uniformf(-1, 1), s.pvz = rng.uniformf(-1, 1);
    double q[4], n = 0;
    for (double& c : q) c = rng.uniform(-1, 1), n += c * c;
    n = std::sqrt(n);
    s.qx = float(q[0] / n), s.qy = float(q[1] / n), s.qz = float(q[2] / n), s.qw = float(q[3] / n);
    s.tx = rng.uniformf(-maxTranslation, maxTranslation);
    s.ty = rng.uniformf(-maxTranslation, maxTranslation);
    s.tz = rng.uniformf(-maxTranslation, maxTranslation);
    return s;
}

// A second SRT: scale, shear, pivot and translation moved a little, the rotation turned by up to maxAngle about a
// random axis (or kept bit-identical), sometimes a non-unit quaternion (the implementation normalizes).
VkSRTDataNV nextSrt(const VkSRTDataNV& s0, Rng& rng, double maxAngle) {
    VkSRTDataNV s = s0;
    s.sx *= rng.uniformf(0.8f, 1.25f), s.sy *= rng.uniformf(0.8f, 1.25f), s.sz *= rng.uniformf(0.8f, 1.25f);
    s.a += rng.uniformf(-0.1f, 0.1f), s.pvx += rng.uniformf(-0.5f, 0.5f), s.pvz += rng.uniformf(-0.5f, 0.5f);
    s.tx += rng.uniformf(-3, 3), s.ty += rng.uniformf(-3, 3), s.tz += rng.uniformf(-3, 3);
    if (rng.coin(0.2)) return s;  // same rotation
    const double angle = rng.uniform(-maxAngle, maxAngle);
    double ax[3], n = 0;
    for (double& c : ax) c = rng.uniform(-1, 1), n += c * c;
    n = std::sqrt(n);
    const double h = std::sin(angle / 2) / n;
    const double r[4] = {ax[0] * h, ax[1] * h, ax[2] * h, std::cos(angle / 2)};  // x y z w
    const double q[4] = {s0.qx, s0.qy, s0.qz, s0.qw};
    // r * q
    double o[4] = {r[3] * q[0] + r[0] * q[3] + r[1] * q[2] - r[2] * q[1],
                   r[3] * q[1] - r[0] * q[2] + r[1] * q[3] + r[2] * q[0],
                   r[3] * q[2] + r[0] * q[1] - r[1] * q[0] + r[2] * q[3],
                   r[3] * q[3] - r[0] * q[0] - r[1] * q[1] - r[2] * q[2]};
    const double k = rng.coin(0.25) ? rng.uniform(0.5, 3.0) : 1.0;
    s.qx = float(o[0] * k), s.qy = float(o[1] * k), s.qz = float(o[2] * k), s.qw = float(o[3] * k);
    return s;
}

MotionInstanceDesc randomMotionInstance(Rng& rng, const AccelStruct* blas, uint32_t type) {
    MotionInstanceDesc d;
    d.type = type;
    d.blas = blas;
    d.customIndex = rng.u32() & 0xFFFFFFu;
    d.sbtOffset = rng.u32() & 0xFFFFFFu;
    d.mask = rng.coin(0.7) ? 0xFF : (rng.u32() & 0xFF);
    d.flags = rng.coin(0.3) ? (rng.below(4) == 0 ? 0x2 : 0x1) : 0;
    if (type == 0) {
        d.m0 = d.m1 = randomTransform(rng, 0.5f, 2.0f, rng.coin(0.3), 6.0f);
    } else if (type == 1) {
        d.m0 = randomTransform(rng, 0.5f, 2.0f, rng.coin(0.3), 6.0f);
        // The end transform turns by at most 90 degrees and moves: every interpolated matrix stays invertible.
        VkTransformMatrixKHR turn = axisRotation(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1, 1),
                                                 rng.uniform(-M_PI / 2, M_PI / 2));
        d.m1 = compose(translation(rng.uniformf(-3, 3), rng.uniformf(-3, 3), rng.uniformf(-3, 3)), compose(turn, d.m0));
    } else {
        d.s0 = randomSrt(rng, 6.0f);
        d.s1 = nextSrt(d.s0, rng, 2.8);
    }
    return d;
}

// ---- Results --------------------------------------------------------------------------------------------------
struct MotionCheck {
    size_t rays = 0, hits = 0, failures = 0;
};

class MotionTest : public VkasTest {
protected:
    // A motion bottom level (or a plain one with motion = false) of the geometries; the oracle knows both times.
    AccelStruct* buildMotionBlas(const std::vector<const MotionGeometry*>& geoms, bool motion = true,
                                 VkBuildAccelerationStructureFlagsKHR extraFlags = 0) {
        std::vector<VkAccelerationStructureGeometryKHR> g;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
        for (const auto* m : geoms) g.push_back(m->geometry), r.push_back(m->range);
        BuildOptions opt;
        // ALLOW_DATA_ACCESS: the checks fetch hit positions (VUID-RuntimeSpirv-flags-08761).
        opt.flags = extraFlags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR | (motion ? kMotionBuild : 0);
        opt.createFlags = motion ? kMotionCreate : 0;
        opt.usePointers = rng.coin();
        auto pb = prepareBlas(g, r, opt);
        if (motion) {
            auto later = std::make_shared<oracle::Blas>();
            for (size_t i = 0; i < g.size(); ++i) later->geometries.push_back(oracle::fetchTrianglesAtTime1(g[i], r[i]));
            later->computeBounds();
            pb->blas->atTime1 = later;
        }
        submit({pb.get()});
        return pb->as;
    }

    // Writes the instances as VkAccelerationStructureMotionInstanceNV (160-byte stride) or typed pointers, builds
    // a motion top level and decodes the application's bytes into `scene` for the oracle.
    AccelStruct* buildMotionTlas(const std::vector<MotionInstanceDesc>& instances, bool pointers,
                                 oracle::MotionScene& scene, uint32_t primitiveOffset = 0,
                                 VkBuildAccelerationStructureFlagsKHR extraFlags = 0) {
        auto pb = std::make_unique<PreparedBuild>();
        const size_t n = instances.size();
        const size_t stride = 160;
        // Pointer mode: each payload 16-byte aligned in instanceBytes (vector storage is 16-byte aligned).
        pb->instanceBytes.assign(primitiveOffset + stride * n + 16, 0xAA);
        std::vector<uint64_t> addresses(n);
        for (size_t i = 0; i < n; ++i) {
            const MotionInstanceDesc& d = instances[i];
            VkAccelerationStructureMotionInstanceNV mi;
            std::memset(&mi, 0, sizeof mi);
            mi.type = VkAccelerationStructureMotionInstanceTypeNV(d.type);
            const uint64_t ref = d.blas ? d.blas->reference() : 0;
            if (d.type == 0) {
                auto& s = mi.data.staticInstance;
                s.transform = d.m0;
                s.instanceCustomIndex = d.customIndex, s.mask = d.mask;
                s.instanceShaderBindingTableRecordOffset = d.sbtOffset, s.flags = d.flags;
                s.accelerationStructureReference = ref;
            } else if (d.type == 1) {
                auto& s = mi.data.matrixMotionInstance;
                s.transformT0 = d.m0, s.transformT1 = d.m1;
                s.instanceCustomIndex = d.customIndex, s.mask = d.mask;
                s.instanceShaderBindingTableRecordOffset = d.sbtOffset, s.flags = d.flags;
                s.accelerationStructureReference = ref;
            } else {
                auto& s = mi.data.srtMotionInstance;
                s.transformT0 = d.s0, s.transformT1 = d.s1;
                s.instanceCustomIndex = d.customIndex, s.mask = d.mask;
                s.instanceShaderBindingTableRecordOffset = d.sbtOffset, s.flags = d.flags;
                s.accelerationStructureReference = ref;
            }
            if (pointers) {
                // Payloads in reverse order; the pointer carries the type in its low 4 bits.
                uint8_t* dst = pb->instanceBytes.data() + stride * (n - 1 - i);
                std::memcpy(dst, &mi.data, sizeof mi.data);
                addresses[i] = uint64_t(reinterpret_cast<uintptr_t>(dst)) | d.type;
            } else {
                std::memcpy(pb->instanceBytes.data() + primitiveOffset + stride * i, &mi, sizeof mi);
            }
        }
        if (pointers) {
            pb->instancePointerBytes.assign(primitiveOffset + 8 * n + 8, 0xAA);
            for (size_t i = 0; i < n; ++i) std::memcpy(pb->instancePointerBytes.data() + primitiveOffset + 8 * i, &addresses[i], 8);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.arrayOfPointers = pointers ? VK_TRUE : VK_FALSE;
        g.geometry.instances.data.hostAddress = pointers ? pb->instancePointerBytes.data() : pb->instanceBytes.data();
        pb->geometries.push_back(g);
        VkAccelerationStructureBuildRangeInfoKHR range{};
        range.primitiveCount = uint32_t(n);
        range.primitiveOffset = primitiveOffset;
        pb->ranges.push_back(range);
        auto& info = pb->info;
        info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        info.flags = kMotionBuild | extraFlags;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.geometryCount = 1;
        info.pGeometries = pb->geometries.data();
        const uint32_t maxCount = uint32_t(n);
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                   &maxCount, &sizes);
        BuildOptions opt;
        opt.createFlags = kMotionCreate;
        opt.motionMaxInstances = uint32_t(n);
        pb->as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, opt);
        info.dstAccelerationStructure = pb->as->handle;
        pb->scratch.assign(sizes.buildScratchSize, 0xAA);
        info.scratchData.hostAddress = pb->scratch.empty() ? nullptr : pb->scratch.data();
        // The oracle decodes the application's bytes.
        auto lookup = [this](uint64_t ref) -> std::shared_ptr<const oracle::Blas> {
            auto it = blasRegistry.find(ref);
            return it == blasRegistry.end() ? nullptr : it->second;
        };
        scene.instances.clear();
        for (size_t i = 0; i < n; ++i) {
            if (pointers) {
                uint64_t p;
                std::memcpy(&p, pb->instancePointerBytes.data() + primitiveOffset + 8 * i, 8);
                scene.instances.push_back(oracle::decodeMotionInstance(uint32_t(p & 0xF),
                                                                       reinterpret_cast<const void*>(p & ~uint64_t(0xF)), lookup));
            } else {
                const uint8_t* p = pb->instanceBytes.data() + primitiveOffset + stride * i;
                uint32_t type;
                std::memcpy(&type, p, 4);
                scene.instances.push_back(oracle::decodeMotionInstance(type, p + 8, lookup));
            }
        }
        submit({pb.get()});
        return pb->as;
    }

    // One ray query at `time` (every triangle candidate confirmed), checked against the oracle's scene at that
    // time, including the candidates and the getters of the committed hit.
    void checkRay(VkAccelerationStructureKHR tlas, const oracle::Scene& at, const oracle::Ray& ray, uint32_t flags,
                  uint32_t mask, float time, MotionCheck& stats, bool plainInitialize = false) {
        ++stats.rays;
        const oracle::Result ex = oracle::trace(at, ray, flags, mask);
        VkasRayQuery q;
        if (plainInitialize)
            vkasRayQueryInitialize(&q, tlas, flags, mask, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
        else
            vkasRayQueryInitializeMotion(&q, tlas, flags, mask, ray.origin.data(), ray.tMin, ray.direction.data(),
                                         ray.tMax, time);
        std::string problems;
        while (vkasRayQueryProceed(&q)) {
            const Hit c = readHit(q, false);
            const oracle::Candidate* oc = ex.find(c.instanceId, c.geometryIndex, c.primitiveIndex);
            if (c.type != VKAS_CANDIDATE_INTERSECTION_TRIANGLE || !oc || oc->aabb)
                problems += "candidate " + c.str() + " is not an oracle triangle candidate; ";
            else if (oc->opaque)
                problems += "Proceed returned an opaque candidate " + c.str() + "; ";
            vkasRayQueryConfirmIntersection(&q);
        }
        const Hit got = readHit(q, true);
        auto res = (flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT) ? matchesAnyHit(ex, ray, got) : matchesClosest(ex, ray, got);
        if (got.type == VKAS_COMMITTED_INTERSECTION_TRIANGLE) {
            ++stats.hits;
            const oracle::Candidate* oc = ex.find(got.instanceId, got.geometryIndex, got.primitiveIndex);
            const oracle::Instance& inst = at.instances[size_t(got.instanceId)];
            float o2w[3][4], w2o[3][4], oo[3], od[3], pos[3][3];
            vkasRayQueryGetIntersectionObjectToWorld(&q, VK_TRUE, o2w);
            vkasRayQueryGetIntersectionWorldToObject(&q, VK_TRUE, w2o);
            vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_TRUE, oo);
            vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_TRUE, od);
            vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_TRUE, pos);
            double worst = 0, scale = 1;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 4; ++c) {
                    scale = std::max({scale, std::fabs(inst.toWorld[r][c]), std::fabs(inst.toObject[r][c])});
                    worst = std::max({worst, std::fabs(o2w[r][c] - inst.toWorld[r][c]),
                                      std::fabs(w2o[r][c] - inst.toObject[r][c])});
                }
            if (!(worst <= 1e-4 * scale)) problems += "ObjectToWorld/WorldToObject differ from the transform at the ray time; ";
            if (oc) {
                double d = 0, s = 1;
                for (int k = 0; k < 3; ++k) {
                    s = std::max({s, std::fabs(oc->objectOrigin[k]), std::fabs(oc->objectDirection[k])});
                    d = std::max({d, std::fabs(oo[k] - oc->objectOrigin[k]), std::fabs(od[k] - oc->objectDirection[k])});
                }
                if (!(d <= 1e-4 * s)) problems += "the object ray differs from the oracle's at the ray time; ";
                const auto& tri = inst.blas->geometries[size_t(got.geometryIndex)].triangles[size_t(got.primitiveIndex)];
                double pd = 0, ps = 1;
                for (int j = 0; j < 3; ++j)
                    for (int k = 0; k < 3; ++k)
                        ps = std::max(ps, std::fabs(tri.v[j][k])), pd = std::max(pd, std::fabs(pos[j][k] - tri.v[j][k]));
                if (!(pd <= 1e-5 * ps)) problems += "vertex positions differ from the positions at the ray time; ";
            }
        }
        if ((!res || !problems.empty()) && ++stats.failures <= 10)
            ADD_FAILURE() << "time " << time << " flags 0x" << std::hex << flags << " mask 0x" << mask << std::dec
                          << ": " << res.message() << "\n  " << problems << "\n  seed " << seed;
    }

    // Random and targeted rays at each time, generated from the oracle's scene at that time.
    MotionCheck checkTimes(const AccelStruct* tlas, const oracle::MotionScene& scene, const std::vector<float>& times,
                           size_t raysPerTime, uint32_t flags = 0, uint32_t mask = 0xFF) {
        MotionCheck stats;
        for (float time : times) {
            const oracle::Scene at = scene.at(time);
            auto rays = randomRays(at, raysPerTime / 2);
            auto targeted = targetedRays(at, raysPerTime - rays.size());
            rays.insert(rays.end(), targeted.begin(), targeted.end());
            for (const auto& ray : rays) checkRay(tlas->handle, at, ray, flags, mask, time, stats);
        }
        if (stats.failures > 10) ADD_FAILURE() << stats.failures << " failures in total, seed " << seed;
        return stats;
    }

    std::vector<float> someTimes(int randomCount) {
        std::vector<float> t = {0.0f, 1.0f};
        for (int i = 0; i < randomCount; ++i) t.push_back(rng.uniformf(0.0f, 1.0f));
        return t;
    }

    // A few bottom levels: plain triangle meshes, motion soups and a motion BLAS whose second geometry is static.
    std::vector<AccelStruct*> someBlases() {
        std::vector<AccelStruct*> out;
        keep.push_back(makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32));
        BuildOptions dataAccess;  // the checks fetch hit positions
        dataAccess.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
        out.push_back(buildBlas(*keep.back(), dataAccess));  // a non-motion structure under motion instances
        for (int k = 0; k < 2; ++k) {
            Mesh m = triangleSoup(int(rng.range(10, 60)), rng, 0.4f);
            GeometryLayout L;
            L.indexType = rng.coin() ? VK_INDEX_TYPE_UINT32 : VK_INDEX_TYPE_NONE_KHR;
            L.flags = rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0;
            motionKeep.push_back(makeMotionGeometry(m, displaced(m, rng, 0.5f), L, rng));
            std::vector<const MotionGeometry*> gs = {motionKeep.back().get()};
            if (k == 1) {  // a second geometry without motion data: it does not move
                Mesh m2 = triangleSoup(int(rng.range(5, 20)), rng, 0.3f);
                GeometryLayout L2;
                L2.withMotion = false;
                motionKeep.push_back(makeMotionGeometry(m2, m2.positions, L2, rng));
                gs.push_back(motionKeep.back().get());
            }
            out.push_back(buildMotionBlas(gs));
        }
        return out;
    }

    std::vector<std::unique_ptr<GeometryData>> keep;
    std::vector<std::unique_ptr<MotionGeometry>> motionKeep;
};

// ---- Tests ----------------------------------------------------------------------------------------------------------

// Static, matrix and SRT motion instances mixed with inactive ones, in an array (160-byte stride, with a
// primitiveOffset) and as typed pointers, over plain and motion bottom levels, at times 0, 1 and random.
TEST_F(MotionTest, MixedInstancesArraysAndPointers) {
    const auto blases = someBlases();
    for (bool pointers : {false, true}) {
        std::vector<MotionInstanceDesc> descs;
        const int n = int(rng.range(6, 24));
        for (int i = 0; i < n; ++i) {
            if (rng.coin(0.15)) {  // inactive: still counts in instance ids
                MotionInstanceDesc d = randomMotionInstance(rng, nullptr, rng.below(3));
                descs.push_back(d);
                continue;
            }
            descs.push_back(randomMotionInstance(rng, blases[rng.below(uint32_t(blases.size()))], rng.below(3)));
        }
        oracle::MotionScene scene;
        const AccelStruct* tlas = buildMotionTlas(descs, pointers, scene, 16 * rng.below(4));
        const MotionCheck st = checkTimes(tlas, scene, someTimes(6), 400);
        EXPECT_GT(st.hits, st.rays / 10) << "too few hits to mean anything (pointers " << pointers << ")";
    }
}

// Every vertex format, with and without indices (16 and 32 bit), strides, primitiveOffset, firstVertex and a
// geometry transform, moving between two times. Under a static motion instance and under a plain top level.
TEST_F(MotionTest, MotionTrianglesFormatsAndIndexing) {
    for (const oracle::FormatInfo& fi : oracle::vertexFormats()) {
        SCOPED_TRACE(fi.name);
        for (VkIndexType it : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32}) {
            const bool unorm = fi.packed, snorm = !fi.isFloat && !fi.packed;
            Mesh m = triangleSoup(int(rng.range(4, 24)), rng, 0.4f);
            if (unorm)
                for (auto& p : m.positions)
                    for (float& c : p) c = 0.5f + 0.45f * c;
            const float lo = unorm ? 0.0f : snorm ? -1.0f : -1e30f, hi = (unorm || snorm) ? 1.0f : 1e30f;
            GeometryLayout L;
            L.format = fi.format;
            L.indexType = it;
            L.extraStride = fi.componentSize * rng.below(3);
            const uint32_t unit = it == VK_INDEX_TYPE_UINT16 ? 2 : it == VK_INDEX_TYPE_UINT32 ? 4 : fi.packed ? fi.size : fi.componentSize;
            L.primitiveOffset = unit * rng.below(5);
            L.firstVertex = rng.below(4);
            L.transform = rng.coin();
            auto g = makeMotionGeometry(m, displaced(m, rng, 0.3f, lo, hi), L, rng);
            const AccelStruct* blas = buildMotionBlas({g.get()});
            // Under a static instance of a motion top level...
            MotionInstanceDesc d = randomMotionInstance(rng, blas, 0);
            oracle::MotionScene scene;
            const AccelStruct* tlas = buildMotionTlas({d}, rng.coin(), scene);
            checkTimes(tlas, scene, someTimes(2), 24);
            // ...and under a plain top level: traced at the query's time all the same.
            Instance plain;
            plain.blas = blas;
            plain.transform = d.m0;
            const AccelStruct* staticTlas = buildTlas({plain});
            oracle::MotionScene plainScene;
            oracle::MotionInstance mi;
            mi.type = 0;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 4; ++c) mi.transform0[r][c] = mi.transform1[r][c] = d.m0.matrix[r][c];
            mi.base = staticTlas->scene->instances[0];
            plainScene.instances.push_back(mi);
            checkTimes(staticTlas, plainScene, someTimes(1), 12);
        }
    }
}

// Masks, culling and opacity flags on a motion scene: the same semantics at every time.
TEST_F(MotionTest, MasksAndRayFlags) {
    const auto blases = someBlases();
    std::vector<MotionInstanceDesc> descs;
    for (int i = 0; i < 16; ++i) descs.push_back(randomMotionInstance(rng, blases[rng.below(uint32_t(blases.size()))], rng.below(3)));
    oracle::MotionScene scene;
    const AccelStruct* tlas = buildMotionTlas(descs, rng.coin(), scene);
    const uint32_t flagSets[] = {VKAS_RAY_FLAG_OPAQUE, VKAS_RAY_FLAG_NO_OPAQUE, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES,
                                 VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, VKAS_RAY_FLAG_CULL_OPAQUE,
                                 VKAS_RAY_FLAG_CULL_NO_OPAQUE, VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT};
    for (uint32_t flags : flagSets) checkTimes(tlas, scene, someTimes(1), 30, flags, rng.coin() ? 0xFF : rng.u32() & 0xFF);
}

// An SRT instance whose rotation turns 180 degrees about a pivot far from the object: at time 0.5 the object is
// far from where it is at both ends, so bounds made of the two end boxes would lose it.
TEST_F(MotionTest, RotatingSrtBoundsCoverTheWholePath) {
    Mesh m = icosphere(1);
    GeometryLayout L;
    L.withMotion = false;
    auto g = makeMotionGeometry(m, m.positions, L, rng);
    const AccelStruct* blas = buildMotionBlas({g.get()}, false);
    MotionInstanceDesc d;
    d.type = 2;
    d.blas = blas;
    d.s0 = VkSRTDataNV{};
    d.s0.sx = d.s0.sy = d.s0.sz = 1.0f;
    d.s0.pvx = 10.0f;  // the sphere sits at (10, 0, 0) before the rotation
    d.s0.qw = 1.0f;
    d.s1 = d.s0;
    d.s1.qw = 0.0f, d.s1.qz = 1.0f;  // 180 degrees about z: (-10, 0, 0) at time 1
    // Other instances around, so that the top level has nodes whose boxes are tested.
    std::vector<MotionInstanceDesc> descs = {d};
    for (int i = 0; i < 12; ++i) {
        MotionInstanceDesc o;
        o.blas = blas;
        o.m0 = o.m1 = translation(rng.uniformf(-30, 30), rng.uniformf(-30, 30), -40.0f);
        descs.push_back(o);
    }
    oracle::MotionScene scene;
    const AccelStruct* tlas = buildMotionTlas(descs, false, scene);
    MotionCheck st;
    for (float time : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f, rng.uniformf(0, 1)}) {
        const oracle::Scene at = scene.at(time);
        // Aim at the sphere's centre at this time, from above.
        const auto& w = at.instances[0].toWorld;
        oracle::Ray ray;
        ray.origin = {float(w[0][3]), float(w[1][3]), 50.0f};
        ray.direction = {0, 0, -1};
        ray.tMax = 1000.0f;
        const size_t before = st.hits;
        checkRay(tlas->handle, at, ray, 0, 0xFF, time, st);
        EXPECT_EQ(st.hits, before + 1) << "the rotating instance was missed at time " << time;
    }
    // And the general check at many times.
    checkTimes(tlas, scene, someTimes(6), 40);
}

// vkasRayQueryInitialize and vkasTraceRays trace motion structures at time 0; InitializeMotion at time 0 gives the
// same results bit for bit.
TEST_F(MotionTest, PlainInitializeAndBatchUseTimeZero) {
    const auto blases = someBlases();
    std::vector<MotionInstanceDesc> descs;
    for (int i = 0; i < 10; ++i) descs.push_back(randomMotionInstance(rng, blases[rng.below(uint32_t(blases.size()))], rng.below(3)));
    oracle::MotionScene scene;
    const AccelStruct* tlas = buildMotionTlas(descs, rng.coin(), scene);
    const oracle::Scene at0 = scene.at(0.0);
    auto rays = targetedRays(at0, 60);
    auto more = randomRays(at0, 40);
    rays.insert(rays.end(), more.begin(), more.end());
    MotionCheck st;
    std::vector<VkasRay> batch(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        checkRay(tlas->handle, at0, rays[i], 0, 0xFF, 0.0f, st, /*plainInitialize=*/true);
        VkasRayQuery a, b;
        const auto& r = rays[i];
        vkasRayQueryInitialize(&a, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
        vkasRayQueryInitializeMotion(&b, tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax, 0.0f);
        while (vkasRayQueryProceed(&a)) vkasRayQueryConfirmIntersection(&a);
        while (vkasRayQueryProceed(&b)) vkasRayQueryConfirmIntersection(&b);
        EXPECT_TRUE(identical(readHit(a, true), readHit(b, true))) << describe(r);
        for (int k = 0; k < 3; ++k) batch[i].origin[k] = r.origin[k], batch[i].direction[k] = r.direction[k];
        batch[i].tMin = r.tMin, batch[i].tMax = r.tMax;
    }
    std::vector<VkasHit> hits(rays.size());
    ASSERT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                            batch.data(), hits.data()),
              VK_SUCCESS);
    for (size_t i = 0; i < rays.size(); ++i)
        EXPECT_TRUE(matchesClosest(oracle::trace(at0, rays[i], 0, 0xFF), rays[i], fromBatch(hits[i])));
    EXPECT_GT(st.hits, 10u);
}

// VUID-RuntimeSpirv-OpTraceRayMotionNV-06366: the time lies in [0, 1]. A query that breaks it is reported and
// misses; the ends are valid.
TEST_F(MotionTest, TimeOutsideZeroOneIsReported) {
    const auto blases = someBlases();
    MotionInstanceDesc d = randomMotionInstance(rng, blases[0], 0);
    d.m0 = d.m1 = identityTransform();
    oracle::MotionScene scene;
    const AccelStruct* tlas = buildMotionTlas({d}, false, scene);
    const float o[3] = {0, 0, 10}, dir[3] = {0, 0, -1};
    for (float t : {-0.25f, 1.0001f, 2.0f, std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::infinity()}) {
        VkasRayQuery q;
        vkasRayQueryInitializeMotion(&q, tlas->handle, 0, 0xFF, o, 0.0f, dir, 100.0f, t);
        EXPECT_FALSE(vkasRayQueryProceed(&q));
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
        const auto errors = takeValidationErrors();
        ASSERT_EQ(errors.size(), 1u) << "time " << t;
        EXPECT_NE(errors[0].find("VUID-RuntimeSpirv-OpTraceRayMotionNV-06366"), std::string::npos) << errors[0];
    }
    for (float t : {0.0f, 1.0f, 0.5f}) {
        VkasRayQuery q;
        vkasRayQueryInitializeMotion(&q, tlas->handle, 0, 0xFF, o, 0.0f, dir, 100.0f, t);
        while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_TRIANGLE) << "time " << t;
        EXPECT_TRUE(takeValidationErrors().empty());
    }
}

// The motion build rules.
TEST_F(MotionTest, BuildValidation) {
    Mesh m = triangleSoup(8, rng, 0.4f);
    GeometryLayout L;
    auto g = makeMotionGeometry(m, displaced(m, rng, 0.2f), L, rng);
    const AccelStruct* blas = buildMotionBlas({g.get()});
    auto expectOne = [&](const char* vuid) {
        const auto errors = takeValidationErrors();
        bool found = false;
        for (const auto& e : errors) found |= e.find(vuid) != std::string::npos;
        EXPECT_TRUE(found) << vuid << " not reported (" << errors.size() << " errors)";
    };
    auto tryBuild = [&](VkBuildAccelerationStructureFlagsKHR flags, VkAccelerationStructureCreateFlagsKHR createFlags,
                        VkAccelerationStructureTypeKHR type, const VkAccelerationStructureGeometryKHR& geom,
                        const VkAccelerationStructureBuildRangeInfoKHR& range) {
        BuildOptions opt;
        opt.createFlags = createFlags;
        opt.motionMaxInstances = 4;
        AccelStruct* as = createAccelStruct(type, 1 << 16, opt);
        std::vector<uint8_t> scratch(1 << 16);
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = type;
        info.flags = flags;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.dstAccelerationStructure = as->handle;
        info.geometryCount = 1;
        info.pGeometries = &geom;
        info.scratchData.hostAddress = scratch.data();
        const VkAccelerationStructureBuildRangeInfoKHR* ranges[] = {&range};
        return vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, ranges);
    };
    // 04927: created with CREATE_MOTION, built without MOTION.
    EXPECT_EQ(tryBuild(0, kMotionCreate, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g->geometry, g->range),
              VK_ERROR_VALIDATION_FAILED_EXT);
    expectOne("VUID-VkAccelerationStructureBuildGeometryInfoKHR-dstAccelerationStructure-04927");
    // 04928 (and 04955: motion triangles): built with MOTION into a structure created without CREATE_MOTION.
    EXPECT_EQ(tryBuild(kMotionBuild, 0, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g->geometry, g->range),
              VK_ERROR_VALIDATION_FAILED_EXT);
    {
        const auto errors = takeValidationErrors();
        bool a = false, b = false;
        for (const auto& e : errors) {
            a |= e.find("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04928") != std::string::npos;
            b |= e.find("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04955") != std::string::npos;
        }
        EXPECT_TRUE(a && b);
    }
    // 04929: MOTION with type GENERIC (a size query sees the info alone).
    {
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;
        info.flags = kMotionBuild;
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, nullptr, &sizes);
        expectOne("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04929");
    }
    // 04954: a motion top level needs VkAccelerationStructureMotionInfoNV.
    {
        HostBuffer* b = createBuffer(1 << 16);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = b->buffer;
        ci.size = 1 << 16;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        ci.createFlags = kMotionCreate;
        VkAccelerationStructureKHR h = VK_NULL_HANDLE;
        EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &h), VK_ERROR_VALIDATION_FAILED_EXT);
        expectOne("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04954");
    }
    // Motion instances: an invalid type, non-zero flags, a reference that is no structure (04930).
    auto instanceBuild = [&](uint32_t type, uint32_t flags, uint64_t ref, const char* vuid) {
        std::vector<uint8_t> bytes(160 * 2, 0);
        VkAccelerationStructureMotionInstanceNV mi;
        std::memset(&mi, 0, sizeof mi);
        mi.type = VkAccelerationStructureMotionInstanceTypeNV(type);
        mi.flags = flags;
        mi.data.staticInstance.transform = identityTransform();
        mi.data.staticInstance.mask = 0xFF;
        mi.data.staticInstance.accelerationStructureReference = ref;
        std::memcpy(bytes.data() + 160, &mi, sizeof mi);  // instance 1; instance 0 is inactive
        VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        geom.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        geom.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        geom.geometry.instances.data.hostAddress = bytes.data();
        VkAccelerationStructureBuildRangeInfoKHR range{};
        range.primitiveCount = 2;
        EXPECT_EQ(tryBuild(kMotionBuild, kMotionCreate, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, geom, range),
                  VK_ERROR_VALIDATION_FAILED_EXT)
            << vuid;
        expectOne(vuid);
    };
    instanceBuild(3, 0, blas->reference(), "VUID-VkAccelerationStructureMotionInstanceNV-type-parameter");
    instanceBuild(0, 1, blas->reference(), "VUID-VkAccelerationStructureMotionInstanceNV-flags-zerobitmask");
    instanceBuild(0, 0, 0x1230, "VUID-vkBuildAccelerationStructuresKHR-pInfos-04930");
}

}  // namespace

// A motion triangle that is a line at the ray time is never hit, even by a ray through that line: rounding can
// give the flat triangle a non-zero determinant. The build keeps it (it could be a triangle at other times), so
// traversal checks at the ray time. Found with VKAS_TEST_SEED=2613435041640896241 of MotionTrianglesFormatsAndIndexing.
TEST_F(MotionTest, DegenerateAtTheRayTimeIsNeverHit) {
    Mesh line;  // three collinear vertices (y = 1, z = 0), at both times
    line.positions = {{-0.172108615f, 1.0f, 0.0f}, {-0.0731271428f, 1.0f, 0.0f}, {0.127118342f, 1.0f, 0.0f}};
    line.indices = {0, 1, 2};
    Mesh moving = line;  // collinear only at time 0.5: vertex 1 moves from y = 1.5 to y = 0.5
    moving.positions[1] = {-0.0731271428f, 1.5f, 0.0f};
    std::vector<Float3> movingAt1 = moving.positions;
    movingAt1[1] = {-0.0731271428f, 0.5f, 0.0f};
    GeometryLayout L;
    L.format = VK_FORMAT_R32G32B32_SFLOAT;
    auto flat = makeMotionGeometry(line, line.positions, L, rng);
    auto crossing = makeMotionGeometry(moving, movingAt1, L, rng);
    for (const MotionGeometry* g : {flat.get(), crossing.get()}) {
        const AccelStruct* blas = buildMotionBlas({g});
        MotionInstanceDesc d;
        d.blas = blas;
        oracle::MotionScene scene;
        const AccelStruct* tlas = buildMotionTlas({d}, false, scene);
        // Rays through random points of the line, from random directions: rounding gives some of them a non-zero
        // determinant, which used to make a hit.
        for (int k = 0; k < 2000; ++k) {
            const float time = g == crossing.get() ? 0.5f : rng.uniformf(0, 1);
            const float u = rng.uniformf(0.05f, 0.95f);
            const float at[3] = {line.positions[0][0] + u * (line.positions[2][0] - line.positions[0][0]), 1.0f, 0.0f};
            float direction[3];
            for (float& c : direction) c = rng.uniformf(-1, 1);
            const float origin[3] = {at[0] - 2 * direction[0], at[1] - 2 * direction[1], at[2] - 2 * direction[2]};
            VkasRayQuery q;
            vkasRayQueryInitializeMotion(&q, tlas->handle, 0, 0xFF, origin, 0.0f, direction, INFINITY, time);
            while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
            ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), uint32_t(VKAS_COMMITTED_INTERSECTION_NONE))
                << (g == flat.get() ? "the line" : "the triangle that is a line at time 0.5") << " at time " << time
                << ", ray " << k;
        }
    }
}
