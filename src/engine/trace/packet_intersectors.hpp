// The box tests of a ray packet (packet_kernel_body.hpp): up to kPacketWidth rays of one octant traced together.
//
// - The group test (packetChildEntries): one pass over a node's 8 children for the whole packet, with interval
//   arithmetic over the packet's origins and inverse directions (Boulos et al., "Geometric and arithmetic culling
//   methods for entire ray packets", 2006). It is conservative to the last bit: every bound is computed with the
//   float operations of the single-ray test (node_intersector_sse.hpp) on the extreme operands, and rounding to nearest is
//   monotone, so a child that any ray of the packet enters (as the single-ray test decides it, with that ray's
//   tMin and tMax) passes. A child that no ray enters may pass too; it only costs time.
// - The lane test (lanesEnteringChild): one child against every ray of the packet, one SIMD lane per ray, with
//   exactly the single-ray test's operations, so each lane decides as childEntryDistances would for that ray.
//
// Both need every ray of the packet in one octant with finite inverse directions (packetFrustum checks), so that
// the planes are chosen alike for all and no product is NaN.
#pragma once

#include <cmath>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/ray.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace vkas {

constexpr uint32_t kPacketWidth = 16;  // lanes of a packet (a multiple of 8); masks of lanes are uint32_t

// The rays of a packet in one space (world, or one instance's object space), one lane each.
struct PacketLanes {
    alignas(32) float org[3][kPacketWidth];
    alignas(32) float invDir[3][kPacketWidth];
};

// The packet as intervals: for each axis, the origin that gives the nearest near-plane distance and the one that
// gives the farthest far-plane distance, and the range of the inverse direction; the smallest tMin.
struct PacketFrustum {
    bool negative[3];  // the octant: the sign of every ray's direction on each axis
    float nearOrg[3], farOrg[3];
    float invLo[3], invHi[3];
    float tMin;
};

// The frustum of the lanes in `lanes` (a non-empty mask), or false when they do not share an octant or a
// direction component is zero, infinite or NaN somewhere (such rays are traced alone).
// rayOf(l) is lane l's ray (a const ShearedRay&).
template <typename RayOf>
inline bool packetFrustum(const RayOf& rayOf, uint32_t lanes, const float* tMin, PacketLanes& L, PacketFrustum& f) {
    const uint32_t first = uint32_t(__builtin_ctz(lanes));
    for (int a = 0; a < 3; ++a) f.negative[a] = rayOf(first).invDir[a] < 0.0f;
    float oLo[3] = {INFINITY, INFINITY, INFINITY}, oHi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int a = 0; a < 3; ++a) f.invLo[a] = INFINITY, f.invHi[a] = -INFINITY;
    f.tMin = INFINITY;
    for (uint32_t l = 0; l < kPacketWidth; ++l) {
        // Lanes outside `lanes` copy the first ray, so that they compute finite values that are then masked off.
        const ShearedRay& r = rayOf((lanes >> l) & 1u ? l : first);
        for (int a = 0; a < 3; ++a) {
            L.org[a][l] = r.org[a];
            L.invDir[a][l] = r.invDir[a];
        }
        if (!((lanes >> l) & 1u)) continue;
        for (int a = 0; a < 3; ++a) {
            const float inv = r.invDir[a], o = r.org[a];
            // finite and non-zero, and on the octant's side (a NaN fails every comparison)
            if (!(f.negative[a] ? (inv < 0.0f && inv > -INFINITY) : (inv > 0.0f && inv < INFINITY))) return false;
            oLo[a] = o < oLo[a] ? o : oLo[a], oHi[a] = o > oHi[a] ? o : oHi[a];
            f.invLo[a] = inv < f.invLo[a] ? inv : f.invLo[a], f.invHi[a] = inv > f.invHi[a] ? inv : f.invHi[a];
        }
        f.tMin = tMin[l] < f.tMin ? tMin[l] : f.tMin;
    }
    for (int a = 0; a < 3; ++a) {
        // near = (plane - o) * inv is smallest for the largest o when inv > 0, the smallest o when inv < 0; far the
        // other way round.
        f.nearOrg[a] = f.negative[a] ? oLo[a] : oHi[a];
        f.farOrg[a] = f.negative[a] ? oHi[a] : oLo[a];
    }
    return true;
}

namespace detail {
// The near and far planes of the packet's octant.
struct PacketPlanes {
    const float *nearX, *farX, *nearY, *farY, *nearZ, *farZ;
    PacketPlanes(const format::Node& node, const bool negative[3]) {
        nearX = negative[0] ? node.upperX : node.lowerX, farX = negative[0] ? node.lowerX : node.upperX;
        nearY = negative[1] ? node.upperY : node.lowerY, farY = negative[1] ? node.lowerY : node.upperY;
        nearZ = negative[2] ? node.upperZ : node.lowerZ, farZ = negative[2] ? node.lowerZ : node.upperZ;
    }
};
}  // namespace detail

// The group test, 4 children at a time: the children some ray of the packet may enter before tMax (the largest
// tMax of its rays), with a lower bound of their entry distances in entry[] (+inf for the others).
inline uint32_t packetChildEntries(const format::Node& node, const PacketFrustum& f, float tMax,
                                   float entry[format::kNodeWidth]) {
    const detail::PacketPlanes p(node, f.negative);
#if defined(__SSE2__)
    uint32_t mask = 0;
    const __m128 inf = _mm_set1_ps(INFINITY);
    for (uint32_t k = 0; k < format::kNodeWidth; k += 4) {
        __m128 tNear = _mm_set1_ps(f.tMin), tFar = _mm_set1_ps(tMax);
        const float* nearPlanes[3] = {p.nearX + k, p.nearY + k, p.nearZ + k};
        const float* farPlanes[3] = {p.farX + k, p.farY + k, p.farZ + k};
        for (int a = 0; a < 3; ++a) {
            const __m128 lo = _mm_set1_ps(f.invLo[a]), hi = _mm_set1_ps(f.invHi[a]);
            const __m128 xn = _mm_sub_ps(_mm_load_ps(nearPlanes[a]), _mm_set1_ps(f.nearOrg[a]));
            const __m128 xf = _mm_sub_ps(_mm_load_ps(farPlanes[a]), _mm_set1_ps(f.farOrg[a]));
            tNear = _mm_max_ps(_mm_min_ps(_mm_mul_ps(xn, lo), _mm_mul_ps(xn, hi)), tNear);
            tFar = _mm_min_ps(_mm_max_ps(_mm_mul_ps(xf, lo), _mm_mul_ps(xf, hi)), tFar);
        }
        const __m128 hit = _mm_cmple_ps(tNear, _mm_mul_ps(tFar, _mm_set1_ps(kFarSlack)));
        _mm_storeu_ps(entry + k, _mm_or_ps(_mm_and_ps(hit, tNear), _mm_andnot_ps(hit, inf)));
        mask |= uint32_t(_mm_movemask_ps(_mm_and_ps(hit, _mm_cmpneq_ps(tNear, inf)))) << k;
    }
    return mask;
#else
    uint32_t mask = 0;
    const float* nearPlanes[3] = {p.nearX, p.nearY, p.nearZ};
    const float* farPlanes[3] = {p.farX, p.farY, p.farZ};
    for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
        float tNear = f.tMin, tFar = tMax;
        for (int a = 0; a < 3; ++a) {
            const float xn = nearPlanes[a][i] - f.nearOrg[a], xf = farPlanes[a][i] - f.farOrg[a];
            tNear = std::fmax(tNear, std::fmin(xn * f.invLo[a], xn * f.invHi[a]));
            tFar = std::fmin(tFar, std::fmax(xf * f.invLo[a], xf * f.invHi[a]));
        }
        entry[i] = tNear <= tFar * kFarSlack ? tNear : INFINITY;
        if (entry[i] != INFINITY) mask |= 1u << i;
    }
    return mask;
#endif
}

// The lane test, 4 lanes at a time: the lanes (rays) of `lanes` that enter child `slot` of `node`, each decided
// with childEntryDistances's operations for that ray with its tMin[] and tMax[].
inline uint32_t lanesEnteringChild(const format::Node& node, uint32_t slot, const PacketFrustum& f,
                                   const PacketLanes& L, const float* tMin, const float* tMax, uint32_t lanes) {
    const detail::PacketPlanes p(node, f.negative);
#if defined(__SSE2__)
    const __m128 nx = _mm_set1_ps(p.nearX[slot]), ny = _mm_set1_ps(p.nearY[slot]), nz = _mm_set1_ps(p.nearZ[slot]);
    const __m128 fx = _mm_set1_ps(p.farX[slot]), fy = _mm_set1_ps(p.farY[slot]), fz = _mm_set1_ps(p.farZ[slot]);
    const __m128 slack = _mm_set1_ps(kFarSlack), inf = _mm_set1_ps(INFINITY);
    uint32_t mask = 0;
    for (uint32_t k = 0; k < kPacketWidth; k += 4) {
        if (((lanes >> k) & 0xFu) == 0) continue;
        const __m128 ox = _mm_load_ps(L.org[0] + k), oy = _mm_load_ps(L.org[1] + k), oz = _mm_load_ps(L.org[2] + k);
        const __m128 ix = _mm_load_ps(L.invDir[0] + k), iy = _mm_load_ps(L.invDir[1] + k),
                     iz = _mm_load_ps(L.invDir[2] + k);
        __m128 tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(nx, ox), ix), _mm_loadu_ps(tMin + k));
        tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(ny, oy), iy), tNear);
        tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(nz, oz), iz), tNear);
        __m128 tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fx, ox), ix), _mm_loadu_ps(tMax + k));
        tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fy, oy), iy), tFar);
        tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fz, oz), iz), tFar);
        const __m128 hit = _mm_and_ps(_mm_cmple_ps(tNear, _mm_mul_ps(tFar, slack)), _mm_cmpneq_ps(tNear, inf));
        mask |= uint32_t(_mm_movemask_ps(hit)) << k;
    }
    return mask & lanes;
#else
    uint32_t mask = 0;
    for (uint32_t l = 0; l < kPacketWidth; ++l) {
        if (!((lanes >> l) & 1u)) continue;
        float tNear = detail::maxNoNan(tMin[l], (p.nearX[slot] - L.org[0][l]) * L.invDir[0][l]);
        tNear = detail::maxNoNan(tNear, (p.nearY[slot] - L.org[1][l]) * L.invDir[1][l]);
        tNear = detail::maxNoNan(tNear, (p.nearZ[slot] - L.org[2][l]) * L.invDir[2][l]);
        float tFar = detail::minNoNan(tMax[l], (p.farX[slot] - L.org[0][l]) * L.invDir[0][l]);
        tFar = detail::minNoNan(tFar, (p.farY[slot] - L.org[1][l]) * L.invDir[1][l]);
        tFar = detail::minNoNan(tFar, (p.farZ[slot] - L.org[2][l]) * L.invDir[2][l]);
        if (tNear <= tFar * kFarSlack && tNear != INFINITY) mask |= 1u << l;
    }
    return mask;
#endif
}

#if defined(__x86_64__)
#define VKAS_PACKET_INTERSECTORS_AVX2 1
// The same two tests in 8 lanes (AVX2, no FMA: the operations and so the results are those above).
__attribute__((target("avx2"))) inline uint32_t packetChildEntriesAvx2(const format::Node& node,
                                                                       const PacketFrustum& f, float tMax,
                                                                       float entry[format::kNodeWidth]) {
    const detail::PacketPlanes p(node, f.negative);
    const float* nearPlanes[3] = {p.nearX, p.nearY, p.nearZ};
    const float* farPlanes[3] = {p.farX, p.farY, p.farZ};
    __m256 tNear = _mm256_set1_ps(f.tMin), tFar = _mm256_set1_ps(tMax);
    for (int a = 0; a < 3; ++a) {
        const __m256 lo = _mm256_set1_ps(f.invLo[a]), hi = _mm256_set1_ps(f.invHi[a]);
        const __m256 xn = _mm256_sub_ps(_mm256_load_ps(nearPlanes[a]), _mm256_set1_ps(f.nearOrg[a]));
        const __m256 xf = _mm256_sub_ps(_mm256_load_ps(farPlanes[a]), _mm256_set1_ps(f.farOrg[a]));
        tNear = _mm256_max_ps(_mm256_min_ps(_mm256_mul_ps(xn, lo), _mm256_mul_ps(xn, hi)), tNear);
        tFar = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(xf, lo), _mm256_mul_ps(xf, hi)), tFar);
    }
    const __m256 inf = _mm256_set1_ps(INFINITY);
    const __m256 hit = _mm256_cmp_ps(tNear, _mm256_mul_ps(tFar, _mm256_set1_ps(kFarSlack)), _CMP_LE_OS);
    _mm256_storeu_ps(entry, _mm256_blendv_ps(inf, tNear, hit));
    return uint32_t(_mm256_movemask_ps(_mm256_and_ps(hit, _mm256_cmp_ps(tNear, inf, _CMP_NEQ_OQ))));
}

__attribute__((target("avx2"))) inline uint32_t lanesEnteringChildAvx2(const format::Node& node, uint32_t slot,
                                                                       const PacketFrustum& f, const PacketLanes& L,
                                                                       const float* tMin, const float* tMax,
                                                                       uint32_t lanes) {
    const detail::PacketPlanes p(node, f.negative);
    const __m256 nx = _mm256_set1_ps(p.nearX[slot]), ny = _mm256_set1_ps(p.nearY[slot]), nz = _mm256_set1_ps(p.nearZ[slot]);
    const __m256 fx = _mm256_set1_ps(p.farX[slot]), fy = _mm256_set1_ps(p.farY[slot]), fz = _mm256_set1_ps(p.farZ[slot]);
    const __m256 inf = _mm256_set1_ps(INFINITY), slack = _mm256_set1_ps(kFarSlack);
    uint32_t mask = 0;
    for (uint32_t k = 0; k < kPacketWidth; k += 8) {
        if (((lanes >> k) & 0xFFu) == 0) continue;
        const __m256 ox = _mm256_load_ps(L.org[0] + k), oy = _mm256_load_ps(L.org[1] + k), oz = _mm256_load_ps(L.org[2] + k);
        const __m256 ix = _mm256_load_ps(L.invDir[0] + k), iy = _mm256_load_ps(L.invDir[1] + k),
                     iz = _mm256_load_ps(L.invDir[2] + k);
        __m256 tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nx, ox), ix), _mm256_loadu_ps(tMin + k));
        tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(ny, oy), iy), tNear);
        tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nz, oz), iz), tNear);
        __m256 tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fx, ox), ix), _mm256_loadu_ps(tMax + k));
        tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fy, oy), iy), tFar);
        tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fz, oz), iz), tFar);
        const __m256 hit = _mm256_and_ps(_mm256_cmp_ps(tNear, _mm256_mul_ps(tFar, slack), _CMP_LE_OS),
                                         _mm256_cmp_ps(tNear, inf, _CMP_NEQ_OQ));
        mask |= uint32_t(_mm256_movemask_ps(hit)) << k;
    }
    return mask & lanes;
}
#endif

}  // namespace vkas
