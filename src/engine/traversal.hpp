// Ray traversal with the semantics of SPV_KHR_ray_query, as a resumable state machine: Proceed runs until it
// meets a candidate the caller must decide on (a non-opaque triangle or any AABB), or until traversal ends. The whole
// state, stacks included, lives in the caller's VkasRayQuery, so a query never allocates.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/as_build.hpp"
#include "engine/format.hpp"
#include "engine/triangle_intersect.hpp"

namespace vkas {

constexpr uint32_t kCommittedNone = 0, kCommittedTriangle = 1, kCommittedGenerated = 2;
constexpr uint32_t kCandidateTriangle = 0, kCandidateAabb = 1;

struct QueryHit {
    uint32_t type;
    float t;  // AABB candidates: where the ray enters the box (not less than tMin); the spec leaves it undefined
    float barycentrics[2];
    bool frontFace;
    bool aabbOpaque;
    const format::InstanceRecord* instance;  // null for no hit
    const format::TriangleRecord* triangle;  // triangle candidates and hits
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
    return h.triangle ? int32_t(h.triangle->geometryIndex)
           : h.aabb   ? int32_t(h.aabb->geometryIndex)
           : h.sphere ? int32_t(h.sphere->geometryIndex)
           : h.lss    ? int32_t(h.lss->geometryIndex)
                      : -1;
}
inline int32_t hitPrimitiveIndex(const QueryHit& h) {
    return h.triangle ? int32_t(h.triangle->primitiveIndex)
           : h.aabb   ? int32_t(h.aabb->primitiveIndex)
           : h.sphere ? int32_t(h.sphere->primitiveIndex)
           : h.lss    ? int32_t(h.lss->primitiveIndex)
                      : -1;
}

// Each wide level pushes at most 7 siblings; two levels (top and bottom) share the stack.
constexpr uint32_t kStackCapacity = 2 * ((format::kNodeWidth - 1) * format::kMaxTreeDepth + 1);

struct RayQueryState {
    // The ray, as given.
    float worldOrigin[3], worldDirection[3];
    float tMin, tMax;  // tMax shrinks to the committed t
    uint32_t flags, cullMask;
    const std::byte* topLevel;
    BlasResolver resolver;

    // Where traversal stands.
    bool done;
    bool inBottomLevel;
    bool candidatePending;
    uint32_t sp;
    uint32_t topLevelStackBase;  // stack depth at which the current bottom-level traversal started
    uint64_t topLeafNext, topLeafEnd;
    uint64_t bottomLeafNext, bottomLeafEnd;
    ShearedRay worldRay, objectRay;
    const format::InstanceRecord* instance;
    const std::byte* bottomLevel;
    bool bottomLevelAabbs;  // the current bottom-level structure holds AABBs, not triangles
    // [NV-motion] The ray time in [0, 1] (0 without one), and whether the top level / the current bottom level
    // store motion records (format::MotionInstanceRecord / format::MotionTriangleRecord).
    float time;
    bool topLevelMotion;
    bool bottomLevelMotion;
    uint32_t bottomLevelSwept;  // [NV-LSS] 0, or SPHERES_NV / LINEAR_SWEPT_SPHERES_NV for such a structure

    QueryHit candidate, committed;

    format::ChildRef stackRef[kStackCapacity];
    float stackDist[kStackCapacity];
};

void queryInitialize(RayQueryState& q, const std::byte* topLevel, BlasResolver resolver, uint32_t rayFlags,
                     uint32_t cullMask, const float origin[3], float tMin, const float direction[3], float tMax,
                     float time = 0.0f);
bool queryProceed(RayQueryState& q);
void queryConfirm(RayQueryState& q);
// Commits the pending AABB candidate at tHit. Does nothing without one, or when tHit is outside
// [tMin, committed t] (VUID 06353: the API layer reports it).
void queryGenerate(RayQueryState& q, float tHit);
void queryTerminate(RayQueryState& q);

// Runs a query to completion, confirming every non-opaque triangle candidate (no any-hit shader). AABB
// candidates are dropped (no intersection shader).
void queryRunToCompletion(RayQueryState& q);

}  // namespace vkas
