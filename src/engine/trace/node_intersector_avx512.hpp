// The ray / 8-wide node test in AVX-512 (F and VL, on 256-bit registers): the same float operations lane by lane
// as childEntryDistancesAvx2 (node_intersector_avx2.hpp), on the same prepared ray (NodeRayAvx2), with the comparisons
// written into mask registers: the hit lanes come out as a mask, with no move from a vector to a general register
// and no AND of two vector masks. No FMA (the library is compiled with -ffp-contract=off), so each lane keeps the
// rounding of every operation and the results equal the SSE2 and AVX2 tests bit for bit (tests/engine/test_node_test.cpp).
// Callable only where the CPU has AVX-512F and AVX-512VL (instruction_set.hpp); the AVX-512 kernel inlines it.
#pragma once

#include <cmath>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/node_intersector_avx2.hpp"
#include "engine/trace/ray.hpp"

#if VKAS_NODE_INTERSECTOR_AVX2
#include <immintrin.h>
#define VKAS_NODE_INTERSECTOR_AVX512 1

namespace vkas {

#define VKAS_AVX512_TARGET __attribute__((target("avx2,avx512f,avx512vl")))

VKAS_AVX512_TARGET inline uint32_t childEntryDistancesAvx512(const format::Node& node, const NodeRayAvx2& r, float tMin,
                                                              float tMax, float out[format::kNodeWidth]) {
    const char* base = reinterpret_cast<const char*>(&node);
#define VKAS_PLANE(offset) _mm256_load_ps(reinterpret_cast<const float*>(base + (offset)))
    __m256 tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearX), r.ox), r.ix), _mm256_set1_ps(tMin));
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearY), r.oy), r.iy), tNear);
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearZ), r.oz), r.iz), tNear);
    __m256 tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farX), r.ox), r.ix), _mm256_set1_ps(tMax));
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farY), r.oy), r.iy), tFar);
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farZ), r.oz), r.iz), tFar);
#undef VKAS_PLANE
    const __m256 inf = _mm256_set1_ps(INFINITY);
    // Entered: tNear <= tFar * kFarSlack, and tNear finite on the high side (an empty slot's +inf never enters).
    const __mmask8 entered = _mm256_mask_cmp_ps_mask(
        _mm256_cmp_ps_mask(tNear, _mm256_mul_ps(tFar, _mm256_set1_ps(kFarSlack)), _CMP_LE_OS), tNear, inf,
        _CMP_NEQ_OQ);
    // Lanes not entered read +inf, as in the other tests (a lane entered with tNear = +inf cannot be: it is masked).
    _mm256_storeu_ps(out, _mm256_mask_blend_ps(entered, inf, tNear));
    return uint32_t(entered);
}

VKAS_AVX512_TARGET inline uint32_t childEntryDistancesAvx512(const format::Node& node, const ShearedRay& r, float tMin,
                                                              float tMax, float out[format::kNodeWidth]) {
    return childEntryDistancesAvx512(node, nodeRayAvx2(r), tMin, tMax, out);
}

#undef VKAS_AVX512_TARGET

}  // namespace vkas
#endif
