// Which rays of a batch are traced together as packets (batch_kernel.hpp, tracePacket): closest-hit rays are
// gathered by octant and dominant axis of their directions, in their order within the batch, and within a group
// each longest run of coherent rays (nearly parallel, from nearly one origin: a camera's rays, not diffuse bounces,
// whose packet would admit almost every child), up to kPacketWidth, becomes a packet. The rest are traced
// one by one, and a batch whose neighbouring rays are mostly not coherent is not gathered at all.
#pragma once

#include <atomic>
#include <cstdint>

#include "engine/trace/batch_kernel.hpp"

namespace vkas {

enum class PacketPolicy {
    Off,       // every ray alone
    Coherent,  // packets of coherent rays (the default)
    Always,    // packets of every run of rays that share an octant (tests: the packet kernel on any rays)
};

// VKAS_TRACE_PACKETS=off or =always, otherwise Coherent; read once.
PacketPolicy packetPolicy();

// How far apart the origins of one packet may be: a thousandth of the extent of the scene (`bounds`: lower xyz,
// upper xyz of the top level), so that a packet's group test stays as tight as one ray's.
float packetOriginTolerance(const float bounds[6]);

// The most rays one gather takes (vkasTraceRays's share of a batch for one task); more are traced one by one.
constexpr uint32_t kMaxGather = 256;

// Orders rays[0, count) into groups: order[] gets a permutation of [0, count), and groupSize[] the sizes of its
// consecutive groups (1 for a ray traced alone, 2 to kPacketWidth for a packet). Returns the number of groups.
uint32_t gatherPackets(const KernelRay* rays, uint32_t count, PacketPolicy policy, float originTolerance,
                       uint32_t* order, uint32_t* groupSize);

// Between packets and rays alone, by their measured time per ray in one call: a packet saves node tests where its
// rays are dense against the geometry and costs more where they are not (a sparse scene, or a cheap one whose rays
// alone already stop after a few nodes, where even gathering them costs more than packets save). The call's first
// coherent groups alternate, a packet then the same number of rays alone, timed, until each way has kSamples groups;
// the way that took less time per ray then traces the rest of the call, and "alone" skips the gather. Only the path
// changes, never a hit: each ray gets the same hit either way. Shared by the tasks of one call (atomics).
class PacketChooser {
  public:
    enum class Choice { Sample, Packets, Alone };

    explicit PacketChooser(PacketPolicy policy)
        : fixed_(policy == PacketPolicy::Off ? Choice::Alone : policy == PacketPolicy::Always ? Choice::Packets
                                                                                              : Choice::Sample) {}
    Choice choice() const {
        if (fixed_ != Choice::Sample) return fixed_;
        return Choice(decided_.load(std::memory_order_relaxed));
    }
    // While sampling: whether the next coherent group goes as a packet (then alone, then as a packet ...).
    bool nextSampleIsPacket() { return turn_.fetch_add(1, std::memory_order_relaxed) % 2 == 0; }
    // While sampling: a task's gather formed `packets` packets. A call whose first kIncoherentTasks gathers formed
    // none (diffuse bounces, shadow rays to scattered points) stops gathering: its other tasks trace alone at once,
    // paying nothing for packets (issue 36: the gather was 4.5% of a diffuse ray's instructions). A later coherent
    // stretch of such a batch then goes alone too: slower perhaps, never another hit.
    void recordGather(uint32_t packets) {
        if (packets != 0) {
            packetsSeen_.store(true, std::memory_order_relaxed);
            return;
        }
        if (!packetsSeen_.load(std::memory_order_relaxed) &&
            emptyGathers_.fetch_add(1, std::memory_order_relaxed) + 1 >= kIncoherentTasks)
            decided_.store(uint32_t(Choice::Alone), std::memory_order_relaxed);
    }
    // While sampling: how long a group of `rays` took, as a packet or alone.
    void record(bool packet, uint64_t nanoseconds, uint32_t rays) {
        Way& w = packet ? packet_ : alone_;
        w.nanos.fetch_add(nanoseconds, std::memory_order_relaxed);
        w.rays.fetch_add(rays, std::memory_order_relaxed);
        w.groups.fetch_add(1, std::memory_order_relaxed);
        if (packet_.groups.load() >= kSamples && alone_.groups.load() >= kSamples) {
            const bool packets = packet_.nanos.load() * alone_.rays.load() <= alone_.nanos.load() * packet_.rays.load();
            decided_.store(uint32_t(packets ? Choice::Packets : Choice::Alone), std::memory_order_relaxed);
        }
    }

  private:
    static constexpr uint64_t kSamples = 8;
    static constexpr uint32_t kIncoherentTasks = 4;
    struct Way {
        std::atomic<uint64_t> nanos{0}, rays{0}, groups{0};
    };
    Choice fixed_;
    std::atomic<uint32_t> decided_{uint32_t(Choice::Sample)};
    std::atomic<uint32_t> turn_{0};
    std::atomic<uint32_t> emptyGathers_{0};
    std::atomic<bool> packetsSeen_{false};
    Way packet_, alone_;
};

}  // namespace vkas
