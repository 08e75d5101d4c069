// The ray / 8-wide node test in AVX2: lane by lane the same float operations as childEntryDistances
// (node_test_sse.hpp), in one 8-lane pass, so its results are identical (no FMA: the library is compiled with
// -ffp-contract=off and the function's target has no FMA, which keeps the rounding of every operation). Callable
// only where the CPU has AVX2 (__builtin_cpu_supports("avx2")); the batch kernel's AVX2 copy inlines it.
#pragma once

#include <cmath>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/node_test_sse.hpp"
#include "engine/trace/ray.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define VKAS_NODE_TEST_AVX2 1

namespace vkas {

__attribute__((target("avx2"))) inline uint32_t childEntryDistancesAvx2(const format::Node& node, const ShearedRay& r,
                                                                        float tMin, float tMax,
                                                                        float out[format::kNodeWidth]) {
    const NodePlanes p(node, r);
    const __m256 ox = _mm256_set1_ps(r.org[0]), oy = _mm256_set1_ps(r.org[1]), oz = _mm256_set1_ps(r.org[2]);
    const __m256 ix = _mm256_set1_ps(r.invDir[0]), iy = _mm256_set1_ps(r.invDir[1]),
                 iz = _mm256_set1_ps(r.invDir[2]);
    __m256 tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.nearX), ox), ix), _mm256_set1_ps(tMin));
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.nearY), oy), iy), tNear);
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.nearZ), oz), iz), tNear);
    __m256 tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.farX), ox), ix), _mm256_set1_ps(tMax));
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.farY), oy), iy), tFar);
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(p.farZ), oz), iz), tFar);
    const __m256 inf = _mm256_set1_ps(INFINITY);
    const __m256 hit = _mm256_cmp_ps(tNear, _mm256_mul_ps(tFar, _mm256_set1_ps(kFarSlack)), _CMP_LE_OS);
    _mm256_storeu_ps(out, _mm256_blendv_ps(inf, tNear, hit));
    return uint32_t(_mm256_movemask_ps(_mm256_and_ps(hit, _mm256_cmp_ps(tNear, inf, _CMP_NEQ_OQ))));
}

}  // namespace vkas
#endif
