// The batch traversal kernel: one ray traced to completion in a tight loop, for vkasTraceRays.
//
// It gives exactly what the ray query's state machine (ray_query.hpp) gives for queryRunToCompletion: every
// non-opaque triangle confirmed, AABB candidates dropped, the same children visited in the same order (the node test
// of node_intersector_sse.hpp / node_intersector_avx2.hpp, the child order of traversal_steps.hpp) and the same triangle decision
// (hit_rules.hpp), so the same hit, ties included. What it saves is the resumable machinery: the ray and the stack stay in registers and on the kernel's own stack, a hit child is entered
// without a push and pop, a leaf's triangles are screened four at a time with SIMD before the exact scalar test, and
// the last bottom-level lookup is cached. It covers top levels without motion over bottom levels of triangles without
// motion (AABB bottom levels contribute nothing here); anything else is reported as unsupported and the caller
// runs the ray query instead.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/trace/packet_intersectors.hpp"
#include "engine/trace/ray_query.hpp"

namespace vkas {

struct KernelRay {
    float origin[3];
    float direction[3];
    float tMin, tMax;
    uint32_t flags;  // SPIR-V ray flags
    uint32_t cullMask;
};

// Per-thread working memory, reused from ray to ray: the stack and the last bottom-level lookup (valid for the whole
// batch: the application may not destroy a structure while a command uses it).
struct KernelScratch {
    uint64_t cachedReference = 0;
    const std::byte* cachedBlas = nullptr;
    format::ChildRef stackRef[kStackCapacity];
    float stackDist[kStackCapacity];
};

// Traces `ray` through `topLevel` (a valid top-level block, or null: every ray misses) into `committed` (a
// QueryHit as queryRunToCompletion leaves RayQueryState::committed, in the fields a batch reports: hit_rules.hpp,
// setReportedTriangleHit; without a hit only type and t are written). Returns false, with `committed` unspecified,
// when the ray meets something the kernel does not handle (a motion top level, motion triangles, spheres, LSS).
bool traceKernel(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                 QueryHit& committed);

// The ray query's first proceed (ray_query.cpp): traceKernel, except that it also returns false (committed
// unspecified) where the ray meets a candidate the application must see: a non-opaque triangle (after the facing and
// opacity rules and, for a fragment, its region) or an instance of AABBs the ray does not skip. Where it returns true,
// `committed` is what the query's state machine would commit with the application seeing nothing, every field
// (positions and object-space ray included): the query is done.
bool traceKernelForQuery(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                         QueryHit& committed);

// Working memory of the packet kernel: its own stack (each entry with the rays it holds) and a single-ray scratch
// for the rays that go on alone.
struct PacketScratch {
    KernelScratch single;
    struct Stack {
        format::ChildRef ref[kStackCapacity];
        float dist[kStackCapacity];
        uint32_t lanes[kStackCapacity];
    } stack;
};

// Traces rays[0, count) (count 1 to kPacketWidth: closest-hit rays with the same flags and cull mask whose
// directions share one octant, no component zero) together as a packet (packet_kernel_body.hpp) into hits[], each
// the hit traceKernel gives that ray, except for the rays whose bit `tied` has: they met two triangles at the same t
// and the packet's order chose between them, so the caller traces them again with traceKernel. Returns false, with
// hits unspecified, where traceKernel would, where the rays do not form a packet, or where the packet gave up (its
// rays spread wider than the structure's boxes, so that it cost more than the rays alone): the caller traces them
// one by one.
bool tracePacket(const std::byte* topLevel, BlasResolver resolver, const KernelRay* rays, uint32_t count,
                 PacketScratch& scratch, QueryHit* hits, uint32_t& tied);

// The three kernels above in the copy of the instruction set the registry names (instruction_set.hpp), for a caller
// that traces many rays: taken once per call (batch_schedule.hpp), they are called directly, without the registry's
// check and a forwarding call for each ray.
struct TraceKernels {
    bool (*single)(const std::byte*, BlasResolver, const KernelRay&, KernelScratch&, QueryHit&);
    bool (*packet)(const std::byte*, BlasResolver, const KernelRay*, uint32_t, PacketScratch&, QueryHit*, uint32_t&);
    bool (*forQuery)(const std::byte*, BlasResolver, const KernelRay&, KernelScratch&, QueryHit&);
};
const TraceKernels& traceKernels();

}  // namespace vkas
