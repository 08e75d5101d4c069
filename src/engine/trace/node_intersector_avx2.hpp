// The ray / 8-wide node test in AVX2: lane by lane the same float operations as childEntryDistances
// (node_intersector_sse.hpp), in one 8-lane pass, so its results are identical (no FMA: the library is compiled with
// -ffp-contract=off and the function's target has no FMA, which keeps the rounding of every operation). Callable
// only where the CPU has AVX2 (__builtin_cpu_supports("avx2")); the batch kernel's AVX2 copy inlines it.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/ray.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define VKAS_NODE_INTERSECTOR_AVX2 1

namespace vkas {

// The ray as the 8-lane node test reads it, prepared once per structure walked (not once per node): origin and
// reciprocals broadcast to all lanes, and the plane offsets of its octant. A walk keeps it in registers.
struct NodeRayAvx2 {
    __m256 ox, oy, oz, ix, iy, iz;
    size_t nearX, farX, nearY, farY, nearZ, farZ;  // (pointer-sized: added to a node address as they are)
};

__attribute__((target("avx2"))) inline NodeRayAvx2 nodeRayAvx2(const ShearedRay& r) {
    return {_mm256_set1_ps(r.org[0]),       _mm256_set1_ps(r.org[1]),       _mm256_set1_ps(r.org[2]),
            _mm256_set1_ps(r.invDir[0]),    _mm256_set1_ps(r.invDir[1]),    _mm256_set1_ps(r.invDir[2]),
            r.planes.nearPlane[0],          r.planes.farPlane[0],           r.planes.nearPlane[1],
            r.planes.farPlane[1],           r.planes.nearPlane[2],          r.planes.farPlane[2]};
}

__attribute__((target("avx2"))) inline uint32_t childEntryDistancesAvx2(const format::Node& node, const NodeRayAvx2& r,
                                                                        float tMin, float tMax,
                                                                        float out[format::kNodeWidth]) {
    const char* base = reinterpret_cast<const char*>(&node);
#define VKAS_PLANE(offset) _mm256_load_ps(reinterpret_cast<const float*>(base + (offset)))
    __m256 tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearX), r.ox), r.ix), _mm256_set1_ps(tMin));
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearY), r.oy), r.iy), tNear);
    tNear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.nearZ), r.oz), r.iz), tNear);
    __m256 tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farX), r.ox), r.ix), _mm256_set1_ps(tMax));
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farY), r.oy), r.iy), tFar);
    tFar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(VKAS_PLANE(r.farZ), r.oz), r.iz), tFar);
    const __m256 inf = _mm256_set1_ps(INFINITY);
    const __m256 hit = _mm256_cmp_ps(tNear, _mm256_mul_ps(tFar, _mm256_set1_ps(kFarSlack)), _CMP_LE_OS);
    _mm256_storeu_ps(out, _mm256_blendv_ps(inf, tNear, hit));
    return uint32_t(_mm256_movemask_ps(_mm256_and_ps(hit, _mm256_cmp_ps(tNear, inf, _CMP_NEQ_OQ))));
#undef VKAS_PLANE
}

__attribute__((target("avx2"))) inline uint32_t childEntryDistancesAvx2(const format::Node& node, const ShearedRay& r,
                                                                        float tMin, float tMax,
                                                                        float out[format::kNodeWidth]) {
    return childEntryDistancesAvx2(node, nodeRayAvx2(r), tMin, tMax, out);
}

}  // namespace vkas
#endif
