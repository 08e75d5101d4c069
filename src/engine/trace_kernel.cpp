#include "engine/trace_kernel.hpp"

#include <vulkan/vulkan_core.h>

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "engine/hit_rules.hpp"
#include "engine/motion.hpp"
#include "engine/node_intersect.hpp"
#include "engine/triangle_intersect.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define VKAS_KERNEL_AVX2 1
#endif

namespace vkas {

namespace {

using format::ChildRef;

// The baseline kernel: the node test the ray query uses (SSE2, 4 lanes twice).
namespace baseline {
inline uint32_t childEntries(const format::Node& node, const ShearedRay& r, float tMin, float tMax,
                             float out[format::kNodeWidth]) {
    return childEntryDistances(node, r, tMin, tMax, out);
}
#include "engine/trace_kernel_body.inl"
}  // namespace baseline

#if VKAS_KERNEL_AVX2
// The AVX2 kernel: the same body compiled for AVX2 (no FMA: -ffp-contract=off and no FMA target keep the rounding
// of every operation), with an 8-lane node test doing lane by lane what childEntryDistances does.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
namespace avx2 {
inline uint32_t childEntries(const format::Node& node, const ShearedRay& r, float tMin, float tMax,
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
#include "engine/trace_kernel_body.inl"
}  // namespace avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

using KernelFn = bool (*)(const std::byte*, BlasResolver, const KernelRay&, KernelScratch&, QueryHit&);

// AVX2 where the CPU has it, unless VKAS_TRACE_KERNEL=sse2 asks for the baseline (tests run both).
KernelFn chooseKernel() {
#if VKAS_KERNEL_AVX2
    const char* forced = std::getenv("VKAS_TRACE_KERNEL");
    const bool baselineOnly = forced && std::strcmp(forced, "sse2") == 0;
    if (!baselineOnly && __builtin_cpu_supports("avx2")) return avx2::traceWith;
#endif
    return baseline::traceWith;
}

}  // namespace

bool traceKernel(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& scratch,
                 QueryHit& committed) {
    static const KernelFn kernel = chooseKernel();
    return kernel(topLevel, resolver, ray, scratch, committed);
}

}  // namespace vkas
