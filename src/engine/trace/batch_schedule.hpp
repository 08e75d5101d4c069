// The schedule of a batch (vkasTraceRays, issue 36: the trace side's one plan): which rays of a task go together as
// packets and which alone, and the timing that chooses between the two (PacketChooser), over the kernels of
// batch_kernel.hpp. The API (api/batch_trace.cpp) validates the call, turns its rays into KernelRays, spreads the
// tasks over the device's worker threads and writes the hits; each ray that no kernel covers goes back to it
// (onDeclined), and it traces that ray with the ray query. Every way gives each ray the same hit.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/batch_kernel.hpp"
#include "engine/trace/packet_gather.hpp"

namespace vkas {

// The rays of one task: one gather's worth.
constexpr uint32_t kRaysPerTask = kMaxGather;

// One call's plan, shared by its tasks (the chooser's atomics).
struct BatchSchedule {
    const std::byte* topLevel;  // a valid top-level block, or null: every ray misses
    BlasResolver resolver;
    const TraceKernels kernels;  // the registry's copy, asked once per call
    PacketPolicy packets;
    float originTolerance;  // packetOriginTolerance of the top level's bounds
    PacketChooser chooser;

    BatchSchedule(const std::byte* topLevel_, BlasResolver resolver_, PacketPolicy packets_)
        : topLevel(topLevel_),
          resolver(resolver_),
          kernels(traceKernels()),
          packets(packets_),
          originTolerance(topLevel_ ? packetOriginTolerance(format::header(topLevel_)->bounds) : 0.0f),
          chooser(packets_) {}
};

// Traces rays[0, n) of one task (n at most kRaysPerTask): onHit(k, hit) with each ray's hit where a kernel traced it,
// onDeclined(k) for each ray none covers (motion, spheres, LSS); each ray exactly once. A packet whose rays met two
// triangles at one t (its order chose between them) has those rays traced again alone, as traceKernel would.
template <typename OnHit, typename OnDeclined>
void traceBatchTask(BatchSchedule& s, const KernelRay* rays, uint32_t n, PacketScratch& scratch, const OnHit& onHit,
                    const OnDeclined& onDeclined) {
    auto traceAlone = [&](uint32_t k) {
        QueryHit hit;
        if (s.kernels.single(s.topLevel, s.resolver, rays[k], scratch.single, hit))
            onHit(k, hit);
        else
            onDeclined(k);
    };
    const PacketChooser::Choice choice = s.chooser.choice();
    if (choice == PacketChooser::Choice::Alone) {
        for (uint32_t k = 0; k < n; ++k) traceAlone(k);
        return;
    }
    uint32_t order[kRaysPerTask], groupSize[kRaysPerTask];
    const uint32_t groups = gatherPackets(rays, n, s.packets, s.originTolerance, order, groupSize);
    if (choice == PacketChooser::Choice::Sample) s.chooser.recordGather(n - groups);  // > 0: a packet formed
    bool packetsPay = true;  // until a packet gives up: then this task's other rays go alone
    for (uint32_t g = 0, k = 0; g < groups; k += groupSize[g++]) {
        const bool coherent = groupSize[g] > 1 && packetsPay;
        const bool timed = coherent && choice == PacketChooser::Choice::Sample;
        const bool packet = coherent && (!timed || s.chooser.nextSampleIsPacket());
        const auto start = timed ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
        if (packet) {
            KernelRay packetRays[kPacketWidth];
            QueryHit hits[kPacketWidth];
            for (uint32_t l = 0; l < groupSize[g]; ++l) packetRays[l] = rays[order[k + l]];
            uint32_t tied = 0;
            packetsPay = s.kernels.packet(s.topLevel, s.resolver, packetRays, groupSize[g], scratch, hits, tied);
            for (uint32_t l = 0; l < groupSize[g]; ++l) {
                if (packetsPay && !((tied >> l) & 1u))
                    onHit(order[k + l], hits[l]);
                else
                    traceAlone(order[k + l]);  // a tie the packet's order decided, or rays it cannot take
            }
        } else {
            for (uint32_t l = 0; l < groupSize[g]; ++l) traceAlone(order[k + l]);
        }
        if (timed && packetsPay) {
            const auto nanos =
                std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start);
            s.chooser.record(packet, uint64_t(nanos.count()), groupSize[g]);
        }
    }
}

}  // namespace vkas
