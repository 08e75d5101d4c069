#include "reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace diff {

namespace {

constexpr uint32_t kRayOpaque = 0x1, kRayNoOpaque = 0x2, kRayCullOpaque = 0x40, kRayCullNoOpaque = 0x80,
                   kRaySkipAabbs = 0x200;
constexpr uint32_t kInstForceOpaque = 0x4, kInstForceNoOpaque = 0x8;
constexpr double kRel = 1e-5;  // the oracle's relative tolerance

}  // namespace

const Expected* ExpectedRay::find(uint32_t type, uint32_t instanceId, uint32_t geometryIndex,
                                  uint32_t primitiveIndex) const {
    for (const Expected& e : candidates)
        if (e.type == type && e.instanceId == instanceId && e.geometryIndex == geometryIndex &&
            e.primitiveIndex == primitiveIndex)
            return &e;
    return nullptr;
}

Reference::Reference(const Scene& scene) : scene_(scene) {
    for (const Blas& blas : scene.blases) {
        BlasView view;
        view.triangles = std::make_shared<oracle::Blas>();
        for (const Geometry& g : blas.geometries) {
            view.geometryFlags.push_back(g.flags);
            view.boxes.emplace_back();
            if (g.type == VK_GEOMETRY_TYPE_AABBS_KHR) {
                view.isAabb = true;
                view.triangles->geometries.emplace_back();
                for (uint32_t p = 0; p < g.range.primitiveCount; ++p) {
                    float f[6];
                    std::memcpy(f, scene.blob.data() + g.aabbs.dataOffset + g.range.primitiveOffset + p * g.aabbs.stride,
                                sizeof f);
                    Box b{{f[0], f[1], f[2]}, {f[3], f[4], f[5]}, !std::isnan(f[0])};
                    view.hasInactive |= !b.active;
                    view.boxes.back().push_back(b);
                }
                continue;
            }
            // The oracle fetches through host addresses into the scene's own blob.
            VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
            geom.geometryType = g.type;
            geom.flags = g.flags;
            auto& t = geom.geometry.triangles;
            t.vertexFormat = g.triangles.vertexFormat;
            t.vertexData.hostAddress = scene.blob.data() + g.triangles.vertexOffset;
            t.vertexStride = g.triangles.vertexStride;
            t.maxVertex = g.triangles.maxVertex;
            t.indexType = g.triangles.indexType;
            if (g.triangles.indexType != VK_INDEX_TYPE_NONE_KHR)
                t.indexData.hostAddress = scene.blob.data() + g.triangles.indexOffset;
            if (g.triangles.hasTransform) t.transformData.hostAddress = scene.blob.data() + g.triangles.transformOffset;
            view.triangles->geometries.push_back(oracle::fetchTriangles(geom, g.range));
            // lavapipe-notes 1: an inactive triangle can hide its BLAS neighbours from lavapipe. First seen with a
            // NaN in the third vertex only; seed 7930896381578007571 (inactive_primitives) shows it with NaN X in the
            // first or second vertex too, so any inactive triangle counts.
            for (const oracle::Triangle& tri : view.triangles->geometries.back().triangles)
                view.hasInactive |= !tri.active;
        }
        view.triangles->computeBounds();
        blases_.push_back(std::move(view));
    }
    for (const Instance& in : scene.instances) {
        oracle::Instance o;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) o.toWorld[r][c] = in.transform.matrix[r][c];
        oracle::invert34(o.toWorld, o.toObject);
        o.customIndex = in.customIndex & 0xFF'FFFFu;
        o.mask = in.mask & 0xFFu;
        o.sbtOffset = in.sbtOffset & 0xFF'FFFFu;
        o.flags = in.flags & 0xFFu;
        o.reference = in.blas < 0 ? 0 : uint64_t(in.blas) + 1;
        // AABB BLASes have no triangles: the oracle then finds nothing there, and expect() adds the boxes.
        if (in.blas >= 0 && !blases_[size_t(in.blas)].isAabb) o.blas = blases_[size_t(in.blas)].triangles;
        oracleScene_.instances.push_back(o);
    }
}

ExpectedRay Reference::expect(const Ray& ray) const {
    ExpectedRay out;
    oracle::Ray oray;
    for (int c = 0; c < 3; ++c) oray.origin[c] = ray.origin[c], oray.direction[c] = ray.direction[c];
    oray.tMin = ray.tMin;
    oray.tMax = ray.tMax;
    const oracle::Result tri = oracle::trace(oracleScene_, oray, ray.flags, ray.cullMask);
    for (const oracle::Candidate& c : tri.candidates) {
        Expected e;
        e.type = 0;
        e.instanceId = uint32_t(c.instanceId);
        e.geometryIndex = uint32_t(c.geometryIndex);
        e.primitiveIndex = uint32_t(c.primitiveIndex);
        e.optional = c.optional;
        e.accepted = c.opaque || confirmRule(e.instanceId, e.geometryIndex, e.primitiveIndex);
        e.noDuplicates = blases_[size_t(scene_.instances[e.instanceId].blas)].geometryFlags[e.geometryIndex] &
                         VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
        e.t = c.t;
        e.tTolerance = c.tTolerance;
        e.triangle = c;
        out.candidates.push_back(e);
    }
    if (ray.flags & kRaySkipAabbs) return out;

    // AABBs: the ray's overlap with each active box, in double, in object space.
    for (uint32_t id = 0; id < scene_.instances.size(); ++id) {
        const Instance& in = scene_.instances[id];
        if (in.blas < 0 || ((in.mask & ray.cullMask) & 0xFFu) == 0) continue;
        const BlasView& view = blases_[size_t(in.blas)];
        if (!view.isAabb) continue;
        const auto& M = oracleScene_.instances[id].toObject;
        double o[3], d[3];
        for (int r = 0; r < 3; ++r) {
            o[r] = M[r][0] * ray.origin[0] + M[r][1] * ray.origin[1] + M[r][2] * ray.origin[2] + M[r][3];
            d[r] = M[r][0] * ray.direction[0] + M[r][1] * ray.direction[1] + M[r][2] * ray.direction[2];
        }
        for (uint32_t g = 0; g < view.boxes.size(); ++g) {
            bool opaque = view.geometryFlags[g] & VK_GEOMETRY_OPAQUE_BIT_KHR;
            if (in.flags & kInstForceOpaque) opaque = true;
            if (in.flags & kInstForceNoOpaque) opaque = false;
            if (ray.flags & kRayOpaque) opaque = true;
            if (ray.flags & kRayNoOpaque) opaque = false;
            if ((ray.flags & kRayCullOpaque) && opaque) continue;
            if ((ray.flags & kRayCullNoOpaque) && !opaque) continue;
            for (uint32_t p = 0; p < view.boxes[g].size(); ++p) {
                const Box& b = view.boxes[g][p];
                if (!b.active) continue;
                double tNear = -INFINITY, tFar = INFINITY, scale = 0;
                for (int c = 0; c < 3; ++c) {
                    const double t0 = (b.lo[c] - o[c]) / d[c], t1 = (b.hi[c] - o[c]) / d[c];
                    tNear = std::max(tNear, std::min(t0, t1));
                    tFar = std::min(tFar, std::max(t0, t1));
                    scale = std::max({scale, std::fabs(b.lo[c]), std::fabs(b.hi[c]), std::fabs(o[c])});
                }
                const double dmin = std::min({std::fabs(d[0]), std::fabs(d[1]), std::fabs(d[2])});
                // Rounding of the object ray and of the slab divisions, in units of t.
                const double tol = kRel * (scale / std::max(dmin, 1e-30) + std::max(std::fabs(tNear), std::fabs(tFar)));
                const double lo = std::max(tNear, double(ray.tMin)), hi = std::min(tFar, double(ray.tMax));
                if (!(lo <= hi + tol)) continue;  // misses the box, even with rounding
                Expected e;
                e.type = 1;
                e.instanceId = id;
                e.geometryIndex = g;
                e.primitiveIndex = p;
                e.optional = !(lo < hi - tol);
                e.noDuplicates = view.geometryFlags[g] & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
                e.t = std::max(tNear, double(ray.tMin));
                e.tTolerance = tol;
                // The procedural step generates at tHit when tHit <= tFar and tHit <= the limit (ray.tMax at most).
                e.accepted = generateRule(id, g, p) && e.t <= tFar && e.t <= ray.tMax;
                e.acceptOptional = generateRule(id, g, p) && (std::fabs(e.t - tFar) <= tol ||
                                                              std::fabs(e.t - double(ray.tMax)) <= tol);
                out.candidates.push_back(e);
            }
        }
    }
    return out;
}

bool Reference::isDegenerate(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) const {
    const oracle::Triangle* t = triangle(instanceId, geometryIndex, primitiveIndex);
    if (!t) return false;
    double e1[3], e2[3], scale = 0;
    for (int c = 0; c < 3; ++c) {
        e1[c] = t->v[1][c] - t->v[0][c];
        e2[c] = t->v[2][c] - t->v[0][c];
        scale = std::max({scale, std::fabs(e1[c]), std::fabs(e2[c])});
    }
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    return len <= 1e-12 * scale * scale;
}

bool Reference::blasHasInactivePrimitives(uint32_t instanceId) const {
    if (instanceId >= scene_.instances.size() || scene_.instances[instanceId].blas < 0) return false;
    return blases_[size_t(scene_.instances[instanceId].blas)].hasInactive;
}

bool Reference::findTriangle(uint32_t instanceId, const float positions[3][4], uint32_t* geometryIndex,
                             uint32_t* primitiveIndex) const {
    if (instanceId >= scene_.instances.size() || scene_.instances[instanceId].blas < 0) return false;
    const BlasView& view = blases_[size_t(scene_.instances[instanceId].blas)];
    for (uint32_t g = 0; g < view.triangles->geometries.size(); ++g) {
        const auto& tris = view.triangles->geometries[g].triangles;
        for (uint32_t p = 0; p < tris.size(); ++p) {
            bool same = true;
            for (int i = 0; i < 3 && same; ++i)
                for (int k = 0; k < 3 && same; ++k)
                    same = std::fabs(positions[i][k] - tris[p].v[size_t(i)][size_t(k)]) <=
                           1e-6 * std::max(1.0, std::fabs(tris[p].v[size_t(i)][size_t(k)]));
            if (same) {
                *geometryIndex = g;
                *primitiveIndex = p;
                return true;
            }
        }
    }
    return false;
}

const oracle::Triangle* Reference::triangleByBlasIndex(uint32_t instanceId, uint32_t index, uint32_t* geometryIndex,
                                                       uint32_t* primitiveIndex) const {
    if (instanceId >= scene_.instances.size() || scene_.instances[instanceId].blas < 0) return nullptr;
    const BlasView& view = blases_[size_t(scene_.instances[instanceId].blas)];
    for (uint32_t g = 0; g < view.triangles->geometries.size(); ++g) {
        const auto& tris = view.triangles->geometries[g].triangles;
        if (index < tris.size()) {
            *geometryIndex = g;
            *primitiveIndex = index;
            return &tris[index];
        }
        index -= uint32_t(tris.size());
    }
    return nullptr;
}

const oracle::Triangle* Reference::triangle(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) const {
    if (instanceId >= scene_.instances.size() || scene_.instances[instanceId].blas < 0) return nullptr;
    const BlasView& view = blases_[size_t(scene_.instances[instanceId].blas)];
    if (geometryIndex >= view.triangles->geometries.size()) return nullptr;
    const auto& tris = view.triangles->geometries[geometryIndex].triangles;
    return primitiveIndex < tris.size() ? &tris[primitiveIndex] : nullptr;
}

}  // namespace diff
