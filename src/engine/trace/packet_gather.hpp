// Which rays of a batch are traced together as packets (batch_kernel.hpp, tracePacket): closest-hit rays are
// gathered by octant and dominant axis of their directions, in their order within the batch, and each run of up
// to kPacketWidth rays of one group becomes a packet when the rays are coherent (nearly parallel, from nearly one
// origin: a camera's rays, not diffuse bounces, whose packet would admit almost every child). The rest are traced
// one by one, and a batch whose neighbouring rays are mostly not coherent is not gathered at all.
#pragma once

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

}  // namespace vkas
