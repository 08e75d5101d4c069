#include "engine/trace/packet_gather.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "engine/trace/hit_rules.hpp"

namespace vkas {

namespace {

constexpr uint32_t kGroups = 8 * 3;  // octant x dominant axis
constexpr uint32_t kAlone = kGroups;

// The group of a ray: its octant and dominant axis, or kAlone when a packet cannot hold it (terminate-on-first-hit
// keeps the first hit met, which the order decides; a zero or non-finite direction component has no octant).
uint32_t groupOf(const KernelRay& r) {
    if (r.flags & kRayTerminateOnFirstHit) return kAlone;
    const float x = r.direction[0], y = r.direction[1], z = r.direction[2];
    const float ax = x < 0.0f ? -x : x, ay = y < 0.0f ? -y : y, az = z < 0.0f ? -z : z;
    // 1 / d is finite and non-zero for |d| in [2^-126, 2^126]: no zero, denormal, huge, infinite or NaN component.
    constexpr float kLo = 0x1p-126f, kHi = 0x1p126f;
    if (!(ax >= kLo && ax <= kHi && ay >= kLo && ay <= kHi && az >= kLo && az <= kHi)) return kAlone;
    const uint32_t octant = (x < 0.0f ? 1u : 0u) | (y < 0.0f ? 2u : 0u) | (z < 0.0f ? 4u : 0u);
    const uint32_t dominant = ax > ay ? (ax > az ? 0u : 2u) : (ay > az ? 1u : 2u);
    return octant * 3 + dominant;
}

// Whether rays order[0, n) are coherent enough for one packet: unit directions within kDirectionSpread of each
// other on every axis (about 3 degrees) and origins within originTolerance.
bool coherent(const KernelRay* rays, const uint32_t* order, uint32_t n, float originTolerance) {
    constexpr float kDirectionSpread = 0.05f;
    float dLo[3], dHi[3], oLo[3], oHi[3];
    for (uint32_t k = 0; k < n; ++k) {
        const KernelRay& r = rays[order[k]];
        const float scale = 1.0f / std::sqrt(r.direction[0] * r.direction[0] + r.direction[1] * r.direction[1] +
                                             r.direction[2] * r.direction[2]);
        for (int a = 0; a < 3; ++a) {
            const float d = r.direction[a] * scale, o = r.origin[a];
            if (k == 0) {
                dLo[a] = dHi[a] = d, oLo[a] = oHi[a] = o;
                continue;
            }
            dLo[a] = d < dLo[a] ? d : dLo[a], dHi[a] = d > dHi[a] ? d : dHi[a];
            oLo[a] = o < oLo[a] ? o : oLo[a], oHi[a] = o > oHi[a] ? o : oHi[a];
        }
        // Most incoherent runs (diffuse bounces) fail on their first rays.
        if (k >= 1 && !(dHi[0] - dLo[0] <= kDirectionSpread && dHi[1] - dLo[1] <= kDirectionSpread &&
                        dHi[2] - dLo[2] <= kDirectionSpread))
            return false;
    }
    for (int a = 0; a < 3; ++a)
        if (!(oHi[a] - oLo[a] <= originTolerance)) return false;
    return true;
}

}  // namespace

PacketPolicy packetPolicy() {
    static const PacketPolicy policy = [] {
        const char* v = std::getenv("VKAS_TRACE_PACKETS");
        if (v && std::strcmp(v, "off") == 0) return PacketPolicy::Off;
        if (v && std::strcmp(v, "always") == 0) return PacketPolicy::Always;
        return PacketPolicy::Coherent;
    }();
    return policy;
}

float packetOriginTolerance(const float bounds[6]) {
    float extent = 0.0f;
    for (int a = 0; a < 3; ++a) {
        const float e = bounds[a + 3] - bounds[a];
        if (std::isfinite(e) && e > extent) extent = e;
    }
    return 1e-3f * extent;
}

uint32_t gatherPackets(const KernelRay* rays, uint32_t count, PacketPolicy policy, float originTolerance,
                       uint32_t* order, uint32_t* groupSize) {
    uint32_t groups = 0;
    if (policy == PacketPolicy::Off) {
        for (uint32_t i = 0; i < count; ++i) order[i] = i, groupSize[groups++] = 1;
        return groups;
    }
    // A stable counting sort by group keeps each group's rays in batch order (neighbours in an image stay
    // neighbours); order[] holds group after group.
    uint32_t start[kGroups + 3] = {};  // keys 0 to kAlone, counted two places up
    for (uint32_t i = 0; i < count; ++i) {
        groupSize[i] = groupOf(rays[i]);  // (groupSize[] holds each ray's group until the groups are cut)
        ++start[groupSize[i] + 2];
    }
    for (uint32_t g = 3; g < kGroups + 3; ++g) start[g] += start[g - 1];
    for (uint32_t i = 0; i < count; ++i) order[start[groupSize[i] + 1]++] = i;
    // start[g + 1] is now the end of group g, start[g] its beginning.
    for (uint32_t g = 0; g <= kGroups; ++g) {
        const uint32_t begin = start[g], end = start[g + 1];
        for (uint32_t k = begin; k < end;) {
            uint32_t n = end - k < kPacketWidth ? end - k : kPacketWidth;
            if (g == kAlone || n < 2 ||
                (policy == PacketPolicy::Coherent && !coherent(rays, order + k, n, originTolerance)))
                n = 1;
            groupSize[groups++] = n;
            k += n;
        }
    }
    return groups;
}

}  // namespace vkas
