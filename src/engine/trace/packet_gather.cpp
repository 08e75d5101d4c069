#include "engine/trace/packet_gather.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "engine/trace/hit_rules.hpp"
#include "engine/trace/ray.hpp"

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
    const uint32_t dominant = uint32_t(dominantAxis(ax, ay, az));  // the shear's kz: a packet's rays share it
    return octant * 3 + dominant;
}

// What the gather knows of each ray: its group, and for a ray that can join a packet its unit direction.
struct Gathered {
    uint32_t group[kMaxGather];
    float unit[kMaxGather][3];
};

void unitDirection(const KernelRay& r, float out[3]) {
    const float scale = 1.0f / std::sqrt(r.direction[0] * r.direction[0] + r.direction[1] * r.direction[1] +
                                         r.direction[2] * r.direction[2]);
    for (int a = 0; a < 3; ++a) out[a] = r.direction[a] * scale;
}

constexpr float kDirectionSpread = 0.05f;  // unit directions of one packet within this on every axis: ~3 degrees

// How many of rays order[0, n) from the first on are coherent enough for one packet: unit directions within
// kDirectionSpread of each other on every axis and origins within originTolerance. The run grows ray by ray (one
// look at each ray), so a gather costs the same whatever packets it forms; a window tested whole and moved on by
// one ray where it failed cost up to kPacketWidth looks a ray (issue 36: 445 instructions a gathered camera ray).
uint32_t coherentRun(const KernelRay* rays, const Gathered& g, const uint32_t* order, uint32_t n,
                     float originTolerance) {
    float dLo[3], dHi[3], oLo[3], oHi[3];
    for (int a = 0; a < 3; ++a) {
        dLo[a] = dHi[a] = g.unit[order[0]][a];
        oLo[a] = oHi[a] = rays[order[0]].origin[a];
    }
    for (uint32_t k = 1; k < n; ++k) {
        float nLo[3], nHi[3], mLo[3], mHi[3];
        bool fits = true;
        for (int a = 0; a < 3; ++a) {
            const float d = g.unit[order[k]][a], o = rays[order[k]].origin[a];
            nLo[a] = d < dLo[a] ? d : dLo[a], nHi[a] = d > dHi[a] ? d : dHi[a];
            mLo[a] = o < oLo[a] ? o : oLo[a], mHi[a] = o > oHi[a] ? o : oHi[a];
            fits = fits && nHi[a] - nLo[a] <= kDirectionSpread && mHi[a] - mLo[a] <= originTolerance;
        }
        if (!fits) return k;
        for (int a = 0; a < 3; ++a) dLo[a] = nLo[a], dHi[a] = nHi[a], oLo[a] = mLo[a], oHi[a] = mHi[a];
    }
    return n;
}

// Whether neighbours in the batch are mostly coherent (an image's rays) or mostly not (bounces, shadow rays to
// area lights): without enough coherent neighbours the batch is traced in its own order, ray by ray, and the sort
// is not paid for.
bool worthGathering(const KernelRay* rays, const Gathered& g, uint32_t count, float originTolerance) {
    uint32_t close = 0;
    for (uint32_t i = 1; i < count; ++i) {
        if (g.group[i] == kAlone || g.group[i] != g.group[i - 1]) continue;
        bool near = true;
        for (int a = 0; a < 3; ++a) {
            const float dd = g.unit[i][a] - g.unit[i - 1][a], od = rays[i].origin[a] - rays[i - 1].origin[a];
            near = near && dd <= kDirectionSpread && -dd <= kDirectionSpread && od <= originTolerance &&
                   -od <= originTolerance;
        }
        close += near ? 1u : 0u;
    }
    return 4 * close >= count;
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
    auto oneByOne = [&] {
        for (uint32_t i = 0; i < count; ++i) order[i] = i, groupSize[groups++] = 1;
        return groups;
    };
    if (policy == PacketPolicy::Off || count > kMaxGather) return oneByOne();
    Gathered g;
    for (uint32_t i = 0; i < count; ++i) {
        g.group[i] = groupOf(rays[i]);
        if (g.group[i] != kAlone) unitDirection(rays[i], g.unit[i]);
    }
    if (policy == PacketPolicy::Coherent && !worthGathering(rays, g, count, originTolerance)) return oneByOne();
    // A stable counting sort by group keeps each group's rays in batch order (neighbours in an image stay
    // neighbours); order[] holds group after group.
    uint32_t start[kGroups + 3] = {};  // keys 0 to kAlone, counted two places up
    for (uint32_t i = 0; i < count; ++i) ++start[g.group[i] + 2];
    for (uint32_t k = 3; k < kGroups + 3; ++k) start[k] += start[k - 1];
    for (uint32_t i = 0; i < count; ++i) order[start[g.group[i] + 1]++] = i;
    // start[k + 1] is now the end of group k, start[k] its beginning.
    for (uint32_t key = 0; key <= kGroups; ++key) {
        const uint32_t begin = start[key], end = start[key + 1];
        for (uint32_t k = begin; k < end;) {
            uint32_t n = end - k < kPacketWidth ? end - k : kPacketWidth;
            if (key == kAlone)
                n = 1;
            else if (policy == PacketPolicy::Coherent && n > 1)
                n = coherentRun(rays, g, order + k, n, originTolerance);  // 1: this ray goes alone
            groupSize[groups++] = n;
            k += n;
        }
    }
    return groups;
}

}  // namespace vkas
