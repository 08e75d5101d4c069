// The rules that decide whether a primitive the ray meets becomes a hit, written once for the ray query's state
// machine (ray_query.cpp) and the batch kernel (batch_kernel_body.hpp): ray and instance flag bits, the instance
// mask, opacity in the spec's order, the whole triangle decision, and the hit record both paths fill.
#pragma once

#include <cstdint>

#include "engine/format/fragment_section.hpp"
#include "engine/format/layout.hpp"
#include "engine/trace/fragment_hit_point.hpp"
#include "engine/trace/opacity_micromap.hpp"
#include "engine/trace/ray.hpp"
#include "engine/trace/triangle_leaf_intersector.hpp"
#include "engine/trace/triangle_intersector.hpp"

namespace vkas {

constexpr uint32_t kRayOpaque = 0x1, kRayNoOpaque = 0x2, kRayTerminateOnFirstHit = 0x4;
constexpr uint32_t kRayCullBack = 0x10, kRayCullFront = 0x20, kRayCullOpaque = 0x40, kRayCullNoOpaque = 0x80;
constexpr uint32_t kRaySkipTriangles = 0x100, kRaySkipAabbs = 0x200;
constexpr uint32_t kRayForceOpacityMicromap2State = 0x400;  // [EXT-OMM] SPV_EXT_opacity_micromap
constexpr uint32_t kInstanceCullDisable = 0x1, kInstanceFlipFacing = 0x2, kInstanceForceOpaque = 0x4,
                   kInstanceForceNoOpaque = 0x8;
constexpr uint32_t kInstanceForceOpacityMicromap2State = 0x10, kInstanceDisableOpacityMicromaps = 0x20;  // [EXT-OMM]

// Opacity in the spec's order: the geometry's OPAQUE flag, overridden by the instance's FORCE_* flags,
// overridden by the ray's Opaque / NoOpaque flags.
inline bool resolveOpacity(bool geometryOpaque, uint32_t instanceFlags, uint32_t rayFlags) {
    bool opaque = geometryOpaque;
    if (instanceFlags & kInstanceForceOpaque)
        opaque = true;
    else if (instanceFlags & kInstanceForceNoOpaque)
        opaque = false;
    if (rayFlags & kRayOpaque)
        opaque = true;
    else if (rayFlags & kRayNoOpaque)
        opaque = false;
    return opaque;
}

inline bool culledByOpacity(bool opaque, uint32_t rayFlags) {
    return opaque ? (rayFlags & kRayCullOpaque) != 0 : (rayFlags & kRayCullNoOpaque) != 0;
}

// The instance mask test: "the instance is visible to the ray when (cullMask & instance mask) != 0".
inline bool instanceVisible(const format::InstanceRecord& inst, uint32_t cullMask) {
    return ((inst.customIndexAndMask >> 24) & cullMask & 0xFFu) != 0;
}

constexpr uint32_t kCommittedNone = 0, kCommittedTriangle = 1, kCommittedGenerated = 2;
constexpr uint32_t kCandidateTriangle = 0, kCandidateAabb = 1;

struct QueryHit {
    uint32_t type;
    float t;  // AABB candidates: where the ray enters the box (not less than tMin); the spec leaves it undefined
    float barycentrics[2];
    bool frontFace;
    bool aabbOpaque;
    const format::InstanceRecord* instance;  // null for no hit
    // Triangle candidates and hits: their indices and positions (format 2 leaves are structure-of-arrays, so the hit
    // keeps its own copy; [NV-motion] the positions at the ray time), which position fetch returns.
    bool isTriangle;
    uint32_t triangleGeometryIndex, trianglePrimitiveIndex;
    float trianglePositions[3][3];
    const format::AabbRecord* aabb;          // AABB candidates and generated hits
    // [NV-LSS] Sphere and LSS candidates and hits. They report the triangle intersection types (as SPIR-V does)
    // and are told apart by these pointers (OpRayQueryIsSphereHitNV / OpRayQueryIsLSSHitNV).
    const format::SphereRecord* sphere;
    const format::LssRecord* lss;
    float lssHitValue;  // u along the LSS (0 or 1 on an end cap); 0 for everything else
    float objectOrigin[3];
    float objectDirection[3];
};

// Geometry and primitive index of a hit, -1 without one.
inline int32_t hitGeometryIndex(const QueryHit& h) {
    return h.isTriangle ? int32_t(h.triangleGeometryIndex)
           : h.aabb   ? int32_t(h.aabb->geometryIndex)
           : h.sphere ? int32_t(h.sphere->geometryIndex)
           : h.lss    ? int32_t(h.lss->geometryIndex)
                      : -1;
}
inline int32_t hitPrimitiveIndex(const QueryHit& h) {
    return h.isTriangle ? int32_t(h.trianglePrimitiveIndex)
           : h.aabb   ? int32_t(h.aabb->primitiveIndex)
           : h.sphere ? int32_t(h.sphere->primitiveIndex)
           : h.lss    ? int32_t(h.lss->primitiveIndex)
                      : -1;
}

// What a triangle test decides before the hit is recorded: the intersection (t, barycentrics), the facing after the
// instance's FLIP_FACING, and the resolved opacity.
struct TriangleCandidate {
    TriangleHit hit;
    bool frontFace;
    bool opaque;
};

// Which triangle of which bottom level a candidate is: what an opacity micromap is looked up with.
struct TriangleId {
    const std::byte* blas;
    uint32_t geometryIndex, primitiveIndex;
    // A format-2 leaf's triangle: its leaf and lane, where a fragment's record and positions are read.
    format::ConstTriangleLeaf leaf{nullptr, 0};
    uint32_t lane = 0;
};

// A fragment of a triangle that spatial splits cut into several records (format/fragment_section.hpp) reports a hit
// only where the point where the ray meets the triangle lies in its region, so that the triangle is shown to a ray
// once (the point is computed accurately enough that the fragment holding it is one the ray visits). The spec:
// "VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR specifies that the implementation must only call the any-hit
// shader a single time for each primitive in this geometry"; vkas keeps that for every geometry.
inline bool fragmentReports(const TriangleId& id, const ShearedRay& r, const TriangleHit& hit) {
    if (!id.leaf.base) return true;  // not a format-2 leaf ([NV-motion] records): never cut (format/check.cpp)
    const uint64_t record = uint64_t(id.leaf.base - format::records(id.blas)) / format::kTriangleBytes + id.lane;
    const format::FragmentEntry* fragment = format::findFragment(id.blas, uint32_t(record));
    float v[3][3];
    id.leaf.positions(id.lane, v);
    if (!fragment) return true;
    double p[3];
    fragmentHitPoint(r, v, hit.b, hit.c, p);
    return format::fragmentHolds(*fragment, p);
}

// The geometry's opacity before the instance and ray overrides: its OPAQUE flag or, "If the intersection candidate is
// with a geometry with an associated opacity micromap and VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_BIT_KHR is
// not set in its instance", the micromap's verdict, which "is used to determine geometry opacity instead of the
// VK_GEOMETRY_OPAQUE_BIT_KHR flag in the geometry". Returns false for Ignored: "If the result of the opacity micromap
// operation is ignored, the candidate is considered neither opaque or non-opaque and execution instead proceeds with
// enumerating the next candidate."
inline bool geometryOpacity(uint32_t recordFlags, uint32_t instanceFlags, uint32_t rayFlags, const TriangleId& id,
                            const TriangleHit& hit, bool& opaque) {
    opaque = (recordFlags & format::kTriangleOpaque) != 0;
    if (!(recordFlags & format::kTriangleMicromap) || (instanceFlags & kInstanceDisableOpacityMicromaps)) return true;
    const bool force2State =
        (instanceFlags & kInstanceForceOpacityMicromap2State) || (rayFlags & kRayForceOpacityMicromap2State);
    const MicromapOpacity m = micromapOpacity(id.blas, id.geometryIndex, id.primitiveIndex, hit.b, hit.c, force2State);
    if (m == MicromapOpacity::Ignored) return false;
    opaque = m == MicromapOpacity::Opaque;
    return true;
}

// The t interval of a triangle candidate: exclusive at both ends. The batch kernel asks it before acceptTriangleHit
// too, so that a candidate past the committed hit costs no call.
inline bool insideTriangleInterval(float t, float tMin, float tMax) { return t > tMin && t < tMax; }

// What follows the intersection: the t interval (exclusive for triangles), the facing culls (unless the instance
// disables culling) and opacity, for a triangle with record flags `recordFlags` that the ray covers at `out.hit`.
inline bool acceptTriangleHit(const ShearedRay& r, float tMin, float tMax, uint32_t rayFlags, uint32_t instanceFlags,
                              uint32_t recordFlags, const TriangleId& id, TriangleCandidate& out) {
    if (!insideTriangleInterval(out.hit.t, tMin, tMax)) return false;
    bool front = out.hit.frontFace;
    if (instanceFlags & kInstanceFlipFacing) front = !front;
    if (!(instanceFlags & kInstanceCullDisable)) {
        if ((rayFlags & kRayCullBack) && !front) return false;
        if ((rayFlags & kRayCullFront) && front) return false;
    }
    out.frontFace = front;
    bool opaque;
    if (!geometryOpacity(recordFlags, instanceFlags, rayFlags, id, out.hit, opaque)) return false;
    out.opaque = resolveOpacity(opaque, instanceFlags, rayFlags);
    if (culledByOpacity(out.opaque, rayFlags)) return false;
    // An opaque hit needs no region: it is never shown to the application, and every fragment of a triangle meets
    // the ray at the same t, which the strict interval drops once one of them is committed.
    return out.opaque || !(recordFlags & format::kTriangleFragment) || fragmentReports(id, r, out.hit);
}

// Whether the ray, in [tMin, tMax] (exclusive for triangles), meets the triangle with record flags `recordFlags` at
// positions `v` (its own, or [NV-motion] the ones interpolated at the ray time) as a candidate: not degenerate,
// covered (watertight test), not culled by facing nor by opacity. The batch kernel's four-lane leaf test
// (triangle_leaf_intersector.hpp) makes the same decision with the intersection's edge functions computed four at a time.
inline bool triangleCandidate(const ShearedRay& r, float tMin, float tMax, uint32_t rayFlags, uint32_t instanceFlags,
                              uint32_t recordFlags, const TriangleId& id, const float (*v)[3], TriangleCandidate& out) {
    if (recordFlags & format::kTriangleDegenerate) return false;
    if (!intersectTriangle(r, v[0], v[1], v[2], out.hit)) return false;
    return acceptTriangleHit(r, tMin, tMax, rayFlags, instanceFlags, recordFlags, id, out);
}

// The same decision for lane `lane` of the four from `lane0` of a format-2 leaf that edgesOfFour left (its edge
// functions already computed): the ray query and both batch kernels take the lanes of a leaf through it, in order.
// Its first half, the intersection (unless the triangle is degenerate), is leafLaneHit: a packet of rays
// (packet_kernel_body.hpp) looks at t before the interval test, to find ties.
inline bool leafLaneHit(const format::ConstTriangleLeaf& leaf, uint32_t lane0, uint32_t lane, const FourLaneEdges& e,
                        const ShearedRay& r, TriangleHit& hit) {
    if (leaf.flags(lane0 + lane) & format::kTriangleDegenerate) return false;
    return laneIntersection(leaf, lane0, lane, e, r, hit);
}
inline TriangleId leafTriangleId(const std::byte* blas, const format::ConstTriangleLeaf& leaf, uint32_t at) {
    return {blas, leaf.geometryIndex(at), leaf.primitiveIndex()[at], leaf, at};
}
inline bool leafLaneCandidate(const std::byte* blas, const format::ConstTriangleLeaf& leaf, uint32_t lane0,
                              uint32_t lane, const FourLaneEdges& e, const ShearedRay& r, float tMin, float tMax,
                              uint32_t rayFlags, uint32_t instanceFlags, TriangleCandidate& out) {
    return leafLaneHit(leaf, lane0, lane, e, r, out.hit) &&
           acceptTriangleHit(r, tMin, tMax, rayFlags, instanceFlags, leaf.flags(lane0 + lane),
                             leafTriangleId(blas, leaf, lane0 + lane), out);
}

// Starts hit record `h` of `type` at t on `instance`, seen along the object-space ray `r`: no primitive yet, no
// barycentrics or facing. Callers then name the primitive and fill what its kind defines.
inline void startHit(QueryHit& h, uint32_t type, float t, const format::InstanceRecord* instance, const ShearedRay& r) {
    h.type = type;
    h.t = t;
    h.barycentrics[0] = h.barycentrics[1] = 0.0f;
    h.frontFace = false;
    h.aabbOpaque = false;
    h.instance = instance;
    h.isTriangle = false;
    h.aabb = nullptr;
    h.sphere = nullptr;
    h.lss = nullptr;
    h.lssHitValue = 0.0f;
    for (int i = 0; i < 3; ++i) h.objectOrigin[i] = r.org[i], h.objectDirection[i] = r.dir[i];
}

// The triangle's part of hit record `h` (started by startHit or setReportedTriangleHit) for candidate `c`:
// barycentrics, facing and the triangle's indices.
inline void setTriangleFields(QueryHit& h, const TriangleCandidate& c, uint32_t geometryIndex, uint32_t primitiveIndex) {
    h.barycentrics[0] = c.hit.b;
    h.barycentrics[1] = c.hit.c;
    h.frontFace = c.frontFace;
    h.isTriangle = true;
    h.triangleGeometryIndex = geometryIndex;
    h.trianglePrimitiveIndex = primitiveIndex;
}

// Hit record `h` of `type` for the triangle candidate `c`: primitive `primitiveIndex` of geometry `geometryIndex`,
// at positions `v`.
inline void setTriangleHit(QueryHit& h, uint32_t type, const TriangleCandidate& c, uint32_t geometryIndex,
                           uint32_t primitiveIndex, const float (*v)[3], const format::InstanceRecord* instance,
                           const ShearedRay& r) {
    startHit(h, type, c.hit.t, instance, r);
    setTriangleFields(h, c, geometryIndex, primitiveIndex);
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) h.trianglePositions[k][a] = v[k][a];
}

// The part of a triangle hit record that a batch reports (VkasHit, written by api/batch_trace.cpp's writeHit): t,
// barycentrics, facing, the instance and the triangle's indices. The batch kernel fills only these for a ray of
// vkasTraceRays; the ray query fills the whole record (setTriangleHit), whose positions (position fetch) and
// object-space ray only its getters read.
inline void setReportedTriangleHit(QueryHit& h, const TriangleCandidate& c, uint32_t geometryIndex,
                                   uint32_t primitiveIndex, const format::InstanceRecord* instance) {
    h.type = kCommittedTriangle;
    h.t = c.hit.t;
    h.instance = instance;
    setTriangleFields(h, c, geometryIndex, primitiveIndex);
}

}  // namespace vkas
