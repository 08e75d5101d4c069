#include "engine/trace/batch_kernel.hpp"

#include <vulkan/vulkan_core.h>

#include <cmath>

#include "engine/format/motion.hpp"
#include "engine/trace/hit_rules.hpp"
#include "engine/trace/instruction_set.hpp"
#include "engine/trace/node_intersector_avx2.hpp"
#include "engine/trace/node_intersector_avx512.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/packet_intersectors.hpp"
#include "engine/trace/ray.hpp"
#include "engine/trace/traversal_steps.hpp"
#include "engine/trace/triangle_leaf_intersector.hpp"
#include "engine/trace/triangle_intersector.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define VKAS_KERNEL_AVX2 (VKAS_NODE_INTERSECTOR_AVX2 && VKAS_PACKET_INTERSECTORS_AVX2)
#define VKAS_KERNEL_AVX512 (VKAS_KERNEL_AVX2 && VKAS_NODE_INTERSECTOR_AVX512)
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
// of every operation), with the 8-lane node test (node_intersector_avx2.hpp) and packet tests (packet_intersectors.hpp).
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

#if VKAS_KERNEL_AVX512
// The AVX-512 kernel: the same body compiled for AVX-512F/VL (no FMA, as above), with the node test whose
// comparisons land in mask registers (node_intersector_avx512.hpp); the packet tests and the instance transform are the
// AVX2 ones, which already fill a 256-bit register per step.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,avx512f,avx512vl"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,avx512f,avx512vl")
#endif
namespace avx512 {
using NodeRay = NodeRayAvx2;
using avx2::groupEntries;
using avx2::lanesEntering;
using avx2::prepareNodeRay;
using avx2::transformInstanceRay;
inline uint32_t childEntries(const format::Node& node, const NodeRay& r, float tMin, float tMax,
                             float out[format::kNodeWidth]) {
    return childEntryDistancesAvx512(node, r, tMin, tMax, out);
}
#include "engine/trace/batch_kernel_body.hpp"
#include "engine/trace/packet_kernel_body.hpp"
}  // namespace avx512
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

// The copy of the instruction set the registry names (instruction_set.hpp).
TraceKernels chooseKernels() {
#if VKAS_KERNEL_AVX512
    if (traceInstructionSet() == TraceInstructionSet::Avx512)
        return {avx512::traceWith, avx512::tracePacketWith, avx512::traceForQueryWith};
#endif
#if VKAS_KERNEL_AVX2
    if (traceInstructionSet() >= TraceInstructionSet::Avx2)
        return {avx2::traceWith, avx2::tracePacketWith, avx2::traceForQueryWith};
#endif
    return {baseline::traceWith, baseline::tracePacketWith, baseline::traceForQueryWith};
}

}  // namespace

const TraceKernels& traceKernels() {
    static const TraceKernels chosen = chooseKernels();
    return chosen;
}

bool traceKernel(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                 QueryHit& committed) {
    return traceKernels().single(topLevel, resolver, ray, scratch, committed);
}

bool traceKernelForQuery(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                         QueryHit& committed) {
    return traceKernels().forQuery(topLevel, resolver, ray, scratch, committed);
}

bool tracePacket(const std::byte* topLevel, BlasResolver resolver, const KernelRay* rays, uint32_t count,
                 PacketScratch& scratch, QueryHit* hits, uint32_t& tied) {
    return traceKernels().packet(topLevel, resolver, rays, count, scratch, hits, tied);
}

}  // namespace vkas
