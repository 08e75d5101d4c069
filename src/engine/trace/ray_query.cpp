#include "engine/trace/ray_query.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "engine/format/motion.hpp"
#include "engine/trace/aabb_intersector.hpp"
#include "engine/trace/batch_kernel.hpp"
#include "engine/trace/hit_rules.hpp"
#include "engine/trace/instruction_set.hpp"
#include "engine/trace/lss_intersector.hpp"
#include "engine/trace/node_intersector_avx2.hpp"
#include "engine/trace/node_intersector_avx512.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/sphere_intersector.hpp"
#include "engine/trace/traversal_steps.hpp"
#include "engine/trace/triangle_leaf_intersector.hpp"
#include "engine/util/math.hpp"
#include "vkas/vkas_compat.h"

namespace vkas {

using namespace format;

namespace {

void resetHit(QueryHit& h, float tMax) {
    std::memset(&h, 0, sizeof h);
    h.type = kCommittedNone;
    h.t = tMax;
}

void push(RayQueryState& q, ChildRef ref, float dist) { pushChild(q.stackRef, q.stackDist, q.sp, ref, dist); }

using DescendFn = ChildRef (*)(RayQueryState&, const Node*, ChildRef, const ShearedRay&);

// The walk down from a popped node (ray_query_descent.hpp), once per instruction set as the batch kernel is built.
// Each defines the node ray (the ray as its node test reads it, prepared once per descent: a descent's pushes could
// alias the query's ray for the compiler, which would prepare it again at every node) and the node test.
namespace baseline {
using NodeRay = const ShearedRay&;
inline NodeRay prepareNodeRay(const ShearedRay& r) { return r; }
inline uint32_t nodeTest(const Node& n, NodeRay r, float tMin, float tMax, float* out) {
    return childEntryDistances(n, r, tMin, tMax, out);
}
#include "engine/trace/ray_query_descent.hpp"
}  // namespace baseline

#if VKAS_NODE_INTERSECTOR_AVX2
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
namespace avx2 {
using NodeRay = NodeRayAvx2;
inline NodeRay prepareNodeRay(const ShearedRay& r) { return nodeRayAvx2(r); }
inline uint32_t nodeTest(const Node& n, const NodeRay& r, float tMin, float tMax, float* out) {
    return childEntryDistancesAvx2(n, r, tMin, tMax, out);
}
#include "engine/trace/ray_query_descent.hpp"
}  // namespace avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

#if VKAS_NODE_INTERSECTOR_AVX512
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,avx512f,avx512vl"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,avx512f,avx512vl")
#endif
namespace avx512 {
using NodeRay = NodeRayAvx2;
using avx2::prepareNodeRay;
inline uint32_t nodeTest(const Node& n, const NodeRay& r, float tMin, float tMax, float* out) {
    return childEntryDistancesAvx512(n, r, tMin, tMax, out);
}
#include "engine/trace/ray_query_descent.hpp"
}  // namespace avx512
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

// The node test of the instruction set the registry names (instruction_set.hpp), as the batch kernel takes its.
DescendFn chooseDescend() {
#if VKAS_NODE_INTERSECTOR_AVX512
    if (traceInstructionSet() == TraceInstructionSet::Avx512) return avx512::descend;
#endif
#if VKAS_NODE_INTERSECTOR_AVX2
    if (traceInstructionSet() >= TraceInstructionSet::Avx2) return avx2::descend;
#endif
    return baseline::descend;
}

ChildRef descend(RayQueryState& q, const Node* nodes, ChildRef ref, const ShearedRay& r) {
    static const DescendFn fn = chooseDescend();
    return fn(q, nodes, ref, r);
}

// Enters `inst` with the world-to-object transform `worldToObject` (the record's own, or [NV-motion] the one
// interpolated at the ray time).
void enterInstanceWith(RayQueryState& q, const InstanceRecord& inst, const float (*worldToObject)[4]) {
    const std::byte* blas = q.resolver ? q.resolver(inst.reference) : nullptr;
    const Header* h = traversableStructure(blas, StructureType::BottomLevel);
    if (!h || skippedByRayFlags(*h, q.flags)) return;
    const bool aabbs = h->primitiveType == VK_GEOMETRY_TYPE_AABBS_KHR;
    float oo[3], od[3];
    transformRay(worldToObject, q.worldOrigin, q.worldDirection, oo, od);
    prepareShearedRay(q.objectRay, oo, od);
    q.instance = &inst;
    q.bottomLevel = blas;
    q.bottomLevelAabbs = aabbs;
    q.bottomLevelMotion =
        h->primitiveType == VK_GEOMETRY_TYPE_TRIANGLES_KHR && motion::isMotionBuild(h->buildFlags);
    q.bottomLevelSwept = (h->primitiveType == VK_GEOMETRY_TYPE_SPHERES_NV ||
                          h->primitiveType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV)
                             ? h->primitiveType
                             : 0u;
    q.inBottomLevel = true;
    q.topLevelStackBase = q.sp;
    q.bottomLeafNext = q.bottomLeafEnd = 0;
    q.leafLanes = 0;
    push(q, h->root, q.tMin);
}

void enterInstance(RayQueryState& q, const InstanceRecord& inst) {
    if (!instanceVisible(inst, q.cullMask)) return;
    enterInstanceWith(q, inst, inst.worldToObject);
}

// [NV-motion] An instance of a motion top level: static ones as usual, matrix and SRT motion ones with their
// transform at the ray time (computed only after the mask test).
void enterMotionInstance(RayQueryState& q, const MotionInstanceRecord& rec) {
    const InstanceRecord& inst = rec.base;
    if (!instanceVisible(inst, q.cullMask)) return;
    if (inst.motionType == motion::kStatic) {
        enterInstanceWith(q, inst, inst.worldToObject);
        return;
    }
    float objectToWorld[3][4], worldToObject[3][4];
    motion::instanceTransformsAt(inst, q.time, objectToWorld, worldToObject);
    enterInstanceWith(q, inst, worldToObject);
}

enum class TriangleOutcome { None, Committed, Candidate };

void commit(RayQueryState& q, const QueryHit& hit, uint32_t type) {
    q.committed = hit;
    q.committed.type = type;
    q.tMax = hit.t;
    if (q.flags & kRayTerminateOnFirstHit) q.done = true;
}

// Starts a candidate on the current instance (hit_rules.hpp, startHit).
inline QueryHit& startCandidate(RayQueryState& q, uint32_t type, float t) {
    startHit(q.candidate, type, t, q.instance, q.objectRay);
    return q.candidate;
}

// A triangle candidate `c` of primitive `primitive` of geometry `geometry` at positions `v`: opaque ones commit at
// once, non-opaque ones go back to the application.
TriangleOutcome takeTriangleCandidate(RayQueryState& q, const TriangleCandidate& c, uint32_t geometry,
                                      uint32_t primitive, const float (*v)[3]) {
    setTriangleHit(q.candidate, kCandidateTriangle, c, geometry, primitive, v, q.instance, q.objectRay);
    if (c.opaque) {
        commit(q, q.candidate, kCommittedTriangle);
        return TriangleOutcome::Committed;
    }
    q.candidatePending = true;
    return TriangleOutcome::Candidate;
}

// [NV-motion] The rest of the current leaf of a motion bottom level: positions interpolated at the ray time.
bool visitMotionTriangleLeaf(RayQueryState& q) {
    const MotionTriangleRecord* records = motionTriangles(q.bottomLevel);
    while (q.bottomLeafNext < q.bottomLeafEnd) {
        const MotionTriangleRecord& rec = records[q.bottomLeafNext++];
        float v[3][3];
        for (int j = 0; j < 3; ++j)
            for (int c = 0; c < 3; ++c) v[j][c] = motion::lerp(rec.base.v[j][c], rec.v1[j][c], q.time);
        // Degenerate at the ray time (a line or a point): never hit. The build keeps such triangles (they may be
        // degenerate at some times only), and a ray through the line can get a non-zero determinant from rounding.
        if (isDegenerateTriangle(v)) continue;
        TriangleCandidate c;
        if (!triangleCandidate(q.objectRay, q.tMin, q.tMax, q.flags, q.instance->sbtOffsetAndFlags >> 24,
                               rec.base.flags, {q.bottomLevel, rec.base.geometryIndex, rec.base.primitiveIndex}, v, c))
            continue;
        if (takeTriangleCandidate(q, c, rec.base.geometryIndex, rec.base.primitiveIndex, v) ==
            TriangleOutcome::Candidate)
            return true;
        if (q.done) return false;
    }
    return false;
}

// Tests the rest of the current triangle leaf, four lanes at a time as the batch kernel does (triangle_leaf_intersector.hpp;
// the lanes of the current four wait in q.leafEdges / q.leafLanes while the application decides a candidate).
// Returns true when a candidate needs the application.
bool visitTriangleLeaf(RayQueryState& q) {
    if (q.bottomLevelMotion) return visitMotionTriangleLeaf(q);  // once per leaf, not per triangle
    const ConstTriangleLeaf leaf = triangleLeaf(records(q.bottomLevel), q.bottomLeafFirst, q.bottomLeafCount);
    const uint32_t instanceFlags = q.instance->sbtOffsetAndFlags >> 24;
    for (;;) {
        if (q.leafLanes == 0) {
            if (q.bottomLeafNext >= q.bottomLeafEnd) return false;
            const uint32_t lane0 = uint32_t(q.bottomLeafNext - q.bottomLeafFirst);
            const uint32_t count = q.bottomLeafEnd - q.bottomLeafNext < 4 ? uint32_t(q.bottomLeafEnd - q.bottomLeafNext) : 4;
            edgesOfFour(leaf, lane0, count, q.objectRay, q.leafEdges);
            q.leafLane0 = lane0;
            q.leafLanes = q.leafEdges.covered | q.leafEdges.undecided;
            q.bottomLeafNext += count;
            continue;
        }
        const uint32_t lane = uint32_t(__builtin_ctz(q.leafLanes));
        q.leafLanes &= q.leafLanes - 1;
        const uint32_t at = q.leafLane0 + lane;
        TriangleCandidate c;
        if (!leafLaneCandidate(q.bottomLevel, leaf, q.leafLane0, lane, q.leafEdges, q.objectRay, q.tMin, q.tMax, q.flags, instanceFlags,
                               c))
            continue;
        float v[3][3];
        leaf.positions(at, v);
        if (takeTriangleCandidate(q, c, leaf.geometryIndex(at), leaf.primitiveIndex()[at], v) ==
            TriangleOutcome::Candidate)
            return true;
        if (q.done) return false;  // an opaque hit with TerminateOnFirstHit
    }
}

// Every AABB the ray meets goes back to the application, opaque or not: only it knows the shape inside.
bool testAabb(RayQueryState& q, const AabbRecord& box) {
    float tEnter;
    if (!intersectAabb(q.objectRay.org, q.objectRay.dir, box.lower, box.upper, q.tMin, q.tMax, tEnter)) return false;
    const uint32_t instanceFlags = q.instance->sbtOffsetAndFlags >> 24;
    const bool opaque = resolveOpacity((box.flags & kAabbOpaque) != 0, instanceFlags, q.flags);
    if (culledByOpacity(opaque, q.flags)) return false;

    QueryHit& c = startCandidate(q, kCandidateAabb, tEnter);
    c.aabbOpaque = opaque;
    c.aabb = &box;
    q.candidatePending = true;
    return true;
}

// Tests the rest of the current AABB leaf. Returns true at the first candidate.
bool visitAabbLeaf(RayQueryState& q) {
    const AabbRecord* records = aabbs(q.bottomLevel);
    while (q.bottomLeafNext < q.bottomLeafEnd)
        if (testAabb(q, records[q.bottomLeafNext++])) return true;
    return false;
}

// [NV-LSS] Spheres and linear swept spheres are built-in primitives: like triangles, opaque ones commit at once
// and non-opaque ones go back to the application as triangle-type candidates. Facing culls do not apply (they
// are for triangles); SkipTriangles (SkipBuiltinPrimitivesNV) skipped the whole instance (skippedByRayFlags).
TriangleOutcome testSwept(RayQueryState& q, const SphereRecord* sphere, const LssRecord* lss) {
    float t, u = 0.0f;
    // Degenerate (zero radii, kept for updates) or made invalid by an update: no candidate at all.
    if (((sphere ? sphere->flags : lss->flags) & kSweptDegenerate) != 0) return TriangleOutcome::None;
    uint32_t recordFlags;
    if (sphere) {
        if (!intersectSphere(q.objectRay.org, q.objectRay.dir, sphere->center, sphere->radius, q.tMin, q.tMax, t))
            return TriangleOutcome::None;
        recordFlags = sphere->flags;
    } else {
        uint32_t caps = ((lss->flags & kLssCap0) ? kLssCapBit0 : 0u) | ((lss->flags & kLssCap1) ? kLssCapBit1 : 0u);
        if (!intersectLss(q.objectRay.org, q.objectRay.dir, lss->p0, lss->r0, lss->p1, lss->r1, caps, q.tMin, q.tMax,
                          t, u))
            return TriangleOutcome::None;
        recordFlags = lss->flags;
    }
    const uint32_t instanceFlags = q.instance->sbtOffsetAndFlags >> 24;
    const bool opaque = resolveOpacity((recordFlags & kSweptOpaque) != 0, instanceFlags, q.flags);
    if (culledByOpacity(opaque, q.flags)) return TriangleOutcome::None;

    QueryHit& c = startCandidate(q, kCandidateTriangle, t);
    c.sphere = sphere;
    c.lss = lss;
    c.lssHitValue = u;
    if (opaque) {
        commit(q, c, kCommittedTriangle);
        return TriangleOutcome::Committed;
    }
    q.candidatePending = true;
    return TriangleOutcome::Candidate;
}

// Tests the rest of the current sphere or LSS leaf. Returns true when a candidate needs the application.
bool visitSweptLeaf(RayQueryState& q) {
    const bool isSphere = q.bottomLevelSwept == VK_GEOMETRY_TYPE_SPHERES_NV;
    while (q.bottomLeafNext < q.bottomLeafEnd) {
        const uint64_t i = q.bottomLeafNext++;
        const TriangleOutcome r = isSphere ? testSwept(q, &spheres(q.bottomLevel)[i], nullptr)
                                           : testSwept(q, nullptr, &lssRecords(q.bottomLevel)[i]);
        if (r == TriangleOutcome::Candidate) return true;
        if (q.done) return false;
    }
    return false;
}

// The whole ray in the batch kernel (batch_kernel.hpp), which gives the state machine's hits and ties, while no
// candidate needs the application: true, with the committed hit set and the query done. False where the ray meets
// one (a non-opaque triangle, AABBs) or a structure the kernel does not cover (motion, spheres, LSS): the state
// machine then traces the ray from the start, as if the kernel had not run (nothing of the query was changed).
// Not inlined: the kernel's stack (about 11 KiB) is on the C stack only during this call.
[[gnu::noinline]] bool traceInKernel(RayQueryState& q) {
    KernelScratch scratch;
    scratch.cachedReference = 0;
    scratch.cachedBlas = nullptr;
    const KernelRay ray{{q.worldOrigin[0], q.worldOrigin[1], q.worldOrigin[2]},
                        {q.worldDirection[0], q.worldDirection[1], q.worldDirection[2]},
                        q.tMin,
                        q.tMax,
                        q.flags,
                        q.cullMask};
    // The kernel commits straight into the query (a miss leaves it as queryInitialize did: type none, t = tMax); a
    // declined ray may have committed an opaque hit on its way, which the state machine, starting over, must not see.
    if (!traceKernelForQuery(q.topLevel, q.resolver, ray, scratch, q.committed)) {
        resetHit(q.committed, q.tMax);
        return false;
    }
    q.tMax = q.committed.t;
    q.done = true;
    return true;
}

// Where the kernel declines a ray of a top level (non-opaque geometry, AABBs, motion), the next rays of it likely
// meet the same, and each decline costs the kernel's walk up to that candidate before the state machine starts
// over (about 7% of a query whose every candidate is non-opaque, docs/PERFORMANCE.md). So after a decline this
// thread's next kSkipAfterDecline queries of that top level go straight to the state machine, then the kernel is
// tried again. Only the speed depends on it: both paths give the same hits.
constexpr uint32_t kSkipAfterDecline = 15;
struct KernelDeclines {
    const std::byte* topLevel = nullptr;
    uint32_t skip = 0;
};
thread_local KernelDeclines declines;

bool kernelMayTake(const RayQueryState& q) {
    if (q.topLevel != declines.topLevel || declines.skip == 0) return true;
    --declines.skip;
    return false;
}

// VKAS_RAY_QUERY_KERNEL=off: every query runs in the state machine from its first proceed (the tests hold the
// state machine to the batch kernel with it, tests/api/CMakeLists.txt). Read once.
bool kernelForQueries() {
    static const bool allowed = [] {
        const char* v = std::getenv("VKAS_RAY_QUERY_KERNEL");
        return !(v && std::strcmp(v, "off") == 0);
    }();
    return allowed;
}

}  // namespace

void queryInitialize(RayQueryState& q, const std::byte* topLevel, BlasResolver resolver, uint32_t rayFlags,
                     uint32_t cullMask, const float origin[3], float tMin, const float direction[3], float tMax,
                     float time) {
    std::memcpy(q.worldOrigin, origin, sizeof q.worldOrigin);
    q.time = time;
    q.topLevelMotion = false;
    q.bottomLevelMotion = false;
    std::memcpy(q.worldDirection, direction, sizeof q.worldDirection);
    q.tMin = tMin;
    q.tMax = tMax;
    q.flags = rayFlags;
    q.cullMask = cullMask;
    q.topLevel = topLevel;
    q.resolver = resolver;
    q.firstProceed = kernelForQueries() ? RayQueryState::FirstProceed::TryKernel  // (the world ray is prepared there)
                                        : RayQueryState::FirstProceed::Prepare;
    q.done = false;
    q.inBottomLevel = false;
    q.candidatePending = false;
    q.sp = 0;
    q.topLevelStackBase = 0;
    q.topLeafNext = q.topLeafEnd = 0;
    q.bottomLeafNext = q.bottomLeafEnd = q.bottomLeafFirst = 0;
    q.bottomLeafCount = 0;
    q.leafLanes = 0;
    q.instance = nullptr;
    q.bottomLevel = nullptr;
    q.bottomLevelAabbs = false;
    q.bottomLevelSwept = 0;
    resetHit(q.candidate, tMax);
    resetHit(q.committed, tMax);
    const Header* h = traversableStructure(topLevel, StructureType::TopLevel);
    if (!h) {
        q.done = true;  // a null acceleration structure: every ray misses
        return;
    }
    q.topLevelMotion = motion::isMotionBuild(h->buildFlags);
    push(q, h->root, tMin);
}

bool queryProceed(RayQueryState& q) {
    q.candidatePending = false;  // an unconfirmed candidate is dropped
    // While every candidate is opaque the query runs as the batch does (issue 36): the state machine below only for
    // a ray that meets one the application must see.
    if (q.firstProceed != RayQueryState::FirstProceed::Done) {
        const bool tryKernel = q.firstProceed == RayQueryState::FirstProceed::TryKernel;
        q.firstProceed = RayQueryState::FirstProceed::Done;
        if (tryKernel && !q.done && kernelMayTake(q)) {
            if (traceInKernel(q)) return false;
            declines = {q.topLevel, kSkipAfterDecline};
        }
        prepareBoxRay(q.worldRay, q.worldOrigin, q.worldDirection);  // the top level's leaves are instances
    }
    while (!q.done) {
        if (q.inBottomLevel) {
            if (q.bottomLeafNext < q.bottomLeafEnd || q.leafLanes != 0) {
                if (q.bottomLevelAabbs    ? visitAabbLeaf(q)
                    : q.bottomLevelSwept ? visitSweptLeaf(q)
                                         : visitTriangleLeaf(q))
                    return true;
                continue;
            }
            if (q.sp == q.topLevelStackBase) {
                q.inBottomLevel = false;
                continue;
            }
        } else {
            if (q.topLeafNext < q.topLeafEnd) {
                if (q.topLevelMotion)  // [NV-motion]: once per instance
                    enterMotionInstance(q, motionInstances(q.topLevel)[q.topLeafNext++]);
                else
                    enterInstance(q, instances(q.topLevel)[q.topLeafNext++]);
                continue;
            }
            if (q.sp == 0) {
                q.done = true;
                break;
            }
        }
        --q.sp;
        ChildRef ref = q.stackRef[q.sp];
        if (q.stackDist[q.sp] > q.tMax * kFarSlack) continue;  // behind the committed hit
        if (isInternal(ref)) {
            const std::byte* base = q.inBottomLevel ? q.bottomLevel : q.topLevel;
            ref = descend(q, nodes(base), ref, q.inBottomLevel ? q.objectRay : q.worldRay);
        }
        if (isLeaf(ref)) {
            if (q.inBottomLevel) {
                q.bottomLeafFirst = q.bottomLeafNext = leafFirst(ref);
                q.bottomLeafEnd = leafFirst(ref) + leafCount(ref);
                q.bottomLeafCount = leafCount(ref);
                q.leafLanes = 0;
            } else {
                q.topLeafNext = leafFirst(ref);
                q.topLeafEnd = leafFirst(ref) + leafCount(ref);
            }
        }
    }
    return false;
}

void queryConfirm(RayQueryState& q) {
    if (!q.candidatePending || q.candidate.type != kCandidateTriangle) return;
    q.candidatePending = false;
    commit(q, q.candidate, kCommittedTriangle);
}

void queryGenerate(RayQueryState& q, float tHit) {
    if (!q.candidatePending || q.candidate.type != kCandidateAabb) return;
    if (!(tHit >= q.tMin && tHit <= q.tMax)) return;
    q.candidatePending = false;
    QueryHit h = q.candidate;
    h.t = tHit;
    commit(q, h, kCommittedGenerated);
}

void queryTerminate(RayQueryState& q) {
    q.done = true;
    q.candidatePending = false;
}

void queryRunToCompletion(RayQueryState& q) {
    while (queryProceed(q)) queryConfirm(q);
}

}  // namespace vkas
