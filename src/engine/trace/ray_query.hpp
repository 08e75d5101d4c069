// Ray traversal with the semantics of SPV_KHR_ray_query, as a resumable state machine: Proceed runs until it
// meets a candidate the caller must decide on (a non-opaque triangle or any AABB), or until traversal ends. The whole
// state, stacks included, lives in the caller's VkasRayQuery, so a query never allocates.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/hit_rules.hpp"
#include "engine/trace/ray.hpp"
#include "engine/trace/traversal_steps.hpp"
#include "engine/trace/triangle_leaf_intersector.hpp"

namespace vkas {

struct RayQueryState {
    // The ray, as given.
    float worldOrigin[3], worldDirection[3];
    float tMin, tMax;  // tMax shrinks to the committed t
    uint32_t flags, cullMask;
    const std::byte* topLevel;
    BlasResolver resolver;

    // Where traversal stands.
    enum class FirstProceed : uint8_t {
        Done,       // traversal has started
        TryKernel,  // the first proceed runs the ray in the batch kernel while no candidate needs the application
        Prepare,    // the first proceed only prepares the world ray (queryWithoutKernel)
    };
    FirstProceed firstProceed;
    bool done;
    bool inBottomLevel;
    bool candidatePending;
    uint32_t sp;
    uint32_t topLevelStackBase;  // stack depth at which the current bottom-level traversal started
    uint64_t topLeafNext, topLeafEnd;
    uint64_t bottomLeafNext, bottomLeafEnd;
    // The current triangle leaf (format 2, layout.hpp TriangleLeaf): where it starts, its triangles, and the four
    // lanes tested last (triangle_leaf_intersector.hpp) with those of them still to be taken, lowest first.
    uint64_t bottomLeafFirst;
    uint32_t bottomLeafCount;
    uint32_t leafLane0, leafLanes;
    FourLaneEdges leafEdges;
    ShearedRay worldRay, objectRay;  // worldRay: the box part only (prepareBoxRay)
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
// After queryInitialize: the state machine traces the whole ray (for a caller that knows the kernel declines it, or
// that must see AABB candidates).
inline void queryWithoutKernel(RayQueryState& q) {
    if (q.firstProceed == RayQueryState::FirstProceed::TryKernel) q.firstProceed = RayQueryState::FirstProceed::Prepare;
}
void queryConfirm(RayQueryState& q);
// Commits the pending AABB candidate at tHit. Does nothing without one, or when tHit is outside
// [tMin, committed t] (VUID 06353: the API layer reports it).
void queryGenerate(RayQueryState& q, float tHit);
void queryTerminate(RayQueryState& q);

// Runs a query to completion, confirming every non-opaque triangle candidate (no any-hit shader). AABB
// candidates are dropped (no intersection shader).
void queryRunToCompletion(RayQueryState& q);

}  // namespace vkas
