// The ray / 8-wide node test, SSE2 version (4 lanes twice; a scalar fallback without SSE2): the one the ray query
// uses, and the batch kernel's baseline. node_intersector_avx2.hpp does the same float operations in 8 lanes, so both
// visit exactly the same children in the same order (and so report the same hit, ties included).
//
// Box tests accept intervals that overlap within a small relative slack, so rounding in the slab computation never
// rejects a box that the exact ray touches (Ize, "Robust BVH Ray Traversal", 2013, with extra margin for the
// shear of the triangle test). Empty slots (lower +inf, upper -inf) and NaN products (a zero direction component
// on a box plane) fall out of the comparisons: NaN is never taken as a bound, so such a slab does not constrain the
// interval. The SSE and AVX2 versions do the same float operations lane by lane: their results are identical.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/ray.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace vkas {

constexpr float kFarSlack = 1.0f + 1.0f / 1048576.0f;

namespace detail {
inline float maxNoNan(float a, float b) { return b > a ? b : a; }  // a NaN b leaves a
inline float minNoNan(float a, float b) { return b < a ? b : a; }
}  // namespace detail

// The ray's slab planes for one node: near and far planes per axis, chosen by the sign of the direction (the
// offsets ShearedRay resolved once per ray).
struct NodePlanes {
    const float *nearX, *farX, *nearY, *farY, *nearZ, *farZ;
    NodePlanes(const format::Node& node, const ShearedRay& r) {
        const char* base = reinterpret_cast<const char*>(&node);
        nearX = reinterpret_cast<const float*>(base + r.planes.nearPlane[0]), farX = reinterpret_cast<const float*>(base + r.planes.farPlane[0]);
        nearY = reinterpret_cast<const float*>(base + r.planes.nearPlane[1]), farY = reinterpret_cast<const float*>(base + r.planes.farPlane[1]);
        nearZ = reinterpret_cast<const float*>(base + r.planes.nearPlane[2]), farZ = reinterpret_cast<const float*>(base + r.planes.farPlane[2]);
    }
};
static_assert(offsetof(format::Node, upperX) == 32 && offsetof(format::Node, lowerY) == 64 &&
              offsetof(format::Node, upperY) == 96 && offsetof(format::Node, lowerZ) == 128 &&
              offsetof(format::Node, upperZ) == 160, "ShearedRay's plane offsets (ray.hpp) follow format::Node");

// Distances at which the ray enters each child box of `node` (+inf where it misses), 4 lanes at a time. Returns the
// mask of the children hit at a finite distance (bit i: child i).
inline uint32_t childEntryDistances(const format::Node& node, const ShearedRay& r, float tMin, float tMax,
                                    float out[format::kNodeWidth]) {
    const NodePlanes p(node, r);
#if defined(__SSE2__)
    const __m128 ox = _mm_set1_ps(r.org[0]), oy = _mm_set1_ps(r.org[1]), oz = _mm_set1_ps(r.org[2]);
    const __m128 ix = _mm_set1_ps(r.invDir[0]), iy = _mm_set1_ps(r.invDir[1]), iz = _mm_set1_ps(r.invDir[2]);
    const __m128 lo = _mm_set1_ps(tMin), hi = _mm_set1_ps(tMax), slack = _mm_set1_ps(kFarSlack);
    const __m128 inf = _mm_set1_ps(INFINITY);
    uint32_t mask = 0;
    for (uint32_t k = 0; k < format::kNodeWidth; k += 4) {
        // _mm_max_ps(v, acc) returns acc when v is NaN: the NaN-ignoring max the scalar code spells out.
        __m128 tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.nearX + k), ox), ix), lo);
        tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.nearY + k), oy), iy), tNear);
        tNear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.nearZ + k), oz), iz), tNear);
        __m128 tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.farX + k), ox), ix), hi);
        tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.farY + k), oy), iy), tFar);
        tFar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(p.farZ + k), oz), iz), tFar);
        __m128 hit = _mm_cmple_ps(tNear, _mm_mul_ps(tFar, slack));
        _mm_storeu_ps(out + k, _mm_or_ps(_mm_and_ps(hit, tNear), _mm_andnot_ps(hit, inf)));
        mask |= uint32_t(_mm_movemask_ps(_mm_and_ps(hit, _mm_cmpneq_ps(tNear, inf)))) << k;
    }
    return mask;
#else
    using detail::maxNoNan, detail::minNoNan;
    uint32_t mask = 0;
    for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
        float tNear = maxNoNan(tMin, (p.nearX[i] - r.org[0]) * r.invDir[0]);
        tNear = maxNoNan(tNear, (p.nearY[i] - r.org[1]) * r.invDir[1]);
        tNear = maxNoNan(tNear, (p.nearZ[i] - r.org[2]) * r.invDir[2]);
        float tFar = minNoNan(tMax, (p.farX[i] - r.org[0]) * r.invDir[0]);
        tFar = minNoNan(tFar, (p.farY[i] - r.org[1]) * r.invDir[1]);
        tFar = minNoNan(tFar, (p.farZ[i] - r.org[2]) * r.invDir[2]);
        out[i] = tNear <= tFar * kFarSlack ? tNear : INFINITY;
        if (out[i] != INFINITY) mask |= 1u << i;
    }
    return mask;
#endif
}

// Starts loading all four cache lines of a 256-byte node (boxes in the first three, child references in the last,
// which a traversal reads only after the box test): node loads are a traversal's cache misses.
inline void prefetchNode(const format::Node* node) {
#if defined(__SSE2__)
    const char* p = reinterpret_cast<const char*>(node);
    for (int line = 0; line < 4; ++line) _mm_prefetch(p + 64 * line, _MM_HINT_T0);
#else
    (void)node;
#endif
}

}  // namespace vkas
