#include "engine/trace/batch_kernel.hpp"

#include <vulkan/vulkan_core.h>

#include <cmath>

#include "engine/format/motion.hpp"
#include "engine/trace/hit_rules.hpp"
#include "engine/trace/instruction_set.hpp"
#include "engine/trace/node_test_avx2.hpp"
#include "engine/trace/node_test_sse.hpp"
#include "engine/trace/packet_tests.hpp"
#include "engine/trace/ray.hpp"
#include "engine/trace/traversal_steps.hpp"
#include "engine/trace/triangle_leaf_test.hpp"
#include "engine/trace/triangle_test.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define VKAS_KERNEL_AVX2 (VKAS_NODE_TEST_AVX2 && VKAS_PACKET_TESTS_AVX2)
#endif

namespace vkas {

namespace {

using format::ChildRef;

// The baseline kernel: the node test the ray query uses (SSE2, 4 lanes twice), and the packet tests in SSE2.
namespace baseline {
// The node test reads the prepared ray through this reference (prepareNodeRay: once per structure walked).
struct NodeRay {
    const ShearedRay* r;
};
inline NodeRay prepareNodeRay(const ShearedRay& r) { return {&r}; }
inline uint32_t childEntries(const format::Node& node, const NodeRay& r, float tMin, float tMax,
                             float out[format::kNodeWidth]) {
    return childEntryDistances(node, *r.r, tMin, tMax, out);
}
inline uint32_t groupEntries(const format::Node& node, const PacketFrustum& f, float tMax,
                             float entry[format::kNodeWidth]) {
    return packetChildEntries(node, f, tMax, entry);
}
inline uint32_t lanesEntering(const format::Node& node, uint32_t slot, const PacketFrustum& f, const PacketLanes& L,
                              const float* tMin, const float* tMax, uint32_t lanes) {
    return lanesEnteringChild(node, slot, f, L, tMin, tMax, lanes);
}
inline void transformInstanceRay(const float (*m)[4], const float o[3], const float d[3], float oo[3], float od[3]) {
    transformRay(m, o, d, oo, od);
}
#include "engine/trace/batch_kernel_body.hpp"
#include "engine/trace/packet_kernel_body.hpp"
}  // namespace baseline

#if VKAS_KERNEL_AVX2
// The AVX2 kernel: the same body compiled for AVX2 (no FMA: -ffp-contract=off and no FMA target keep the rounding
// of every operation), with the 8-lane node test (node_test_avx2.hpp) and packet tests (packet_tests.hpp).
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
namespace avx2 {
// The ray broadcast once per structure walked (prepareNodeRay), kept in registers by the walk.
using NodeRay = NodeRayAvx2;
inline NodeRay prepareNodeRay(const ShearedRay& r) { return nodeRayAvx2(r); }
inline uint32_t childEntries(const format::Node& node, const NodeRay& r, float tMin, float tMax,
                             float out[format::kNodeWidth]) {
    return childEntryDistancesAvx2(node, r, tMin, tMax, out);
}
inline uint32_t groupEntries(const format::Node& node, const PacketFrustum& f, float tMax,
                             float entry[format::kNodeWidth]) {
    return packetChildEntriesAvx2(node, f, tMax, entry);
}
inline uint32_t lanesEntering(const format::Node& node, uint32_t slot, const PacketFrustum& f, const PacketLanes& L,
                              const float* tMin, const float* tMax, uint32_t lanes) {
    return lanesEnteringChildAvx2(node, slot, f, L, tMin, tMax, lanes);
}
inline void transformInstanceRay(const float (*m)[4], const float o[3], const float d[3], float oo[3], float od[3]) {
    transformRayAvx2(m, o, d, oo, od);
}
#include "engine/trace/batch_kernel_body.hpp"
#include "engine/trace/packet_kernel_body.hpp"
}  // namespace avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

using KernelFn = bool (*)(const std::byte*, BlasResolver, const KernelRay&, KernelScratch&, QueryHit&);
using PacketFn = bool (*)(const std::byte*, BlasResolver, const KernelRay*, uint32_t, PacketScratch&, QueryHit*,
                          uint32_t&);
struct Kernels {
    KernelFn single;
    PacketFn packet;
    KernelFn query;
};

// The copy of the instruction set the registry names (instruction_set.hpp).
Kernels chooseKernels() {
#if VKAS_KERNEL_AVX2
    if (traceInstructionSet() == TraceInstructionSet::Avx2)
        return {avx2::traceWith, avx2::tracePacketWith, avx2::traceForQueryWith};
#endif
    return {baseline::traceWith, baseline::tracePacketWith, baseline::traceForQueryWith};
}

const Kernels& kernels() {
    static const Kernels chosen = chooseKernels();
    return chosen;
}

}  // namespace

bool traceKernel(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                 QueryHit& committed) {
    return kernels().single(topLevel, resolver, ray, scratch, committed);
}

bool traceKernelForQuery(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                         QueryHit& committed) {
    return kernels().query(topLevel, resolver, ray, scratch, committed);
}

bool tracePacket(const std::byte* topLevel, BlasResolver resolver, const KernelRay* rays, uint32_t count,
                 PacketScratch& scratch, QueryHit* hits, uint32_t& tied) {
    return kernels().packet(topLevel, resolver, rays, count, scratch, hits, tied);
}

}  // namespace vkas
