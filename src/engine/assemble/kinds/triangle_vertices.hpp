// What the gather and the update of triangles (triangles.cpp, triangles_update.cpp) share: a float vertex loaded
// into a register, and the degenerate-triangle rule on vertices in registers, so that both decide as the build does.
#pragma once

#include <immintrin.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "engine/input/triangles.hpp"
#include "engine/util/byte_io.hpp"

namespace vkas {

// One float vertex in lanes 0-2 (z = 0 for two components), lane 3 zero. Reads exactly the vertex's bytes.
template <TriangleVertexKind V>
inline __m128 loadFloatVertex(const std::byte* p) {
    uint64_t xy;
    std::memcpy(&xy, p, 8);
    const __m128 lo = _mm_castsi128_ps(_mm_cvtsi64_si128(int64_t(xy)));
    if constexpr (V == TriangleVertexKind::Float3) return _mm_movelh_ps(lo, _mm_set_ss(loadUnaligned<float>(p + 8)));
    return lo;
}

// isDegenerateTriangle on vertices in registers: the same double differences and products, two lanes at a time
// (the middle component comes out negated, which keeps whether it is zero), so the decision is the build's.
inline bool isDegenerateTriangleSse(__m128 v0, __m128 v1, __m128 v2) {
    const __m128d a = _mm_cvtps_pd(v0), az = _mm_cvtps_pd(_mm_movehl_ps(v0, v0));
    const __m128d e1 = _mm_sub_pd(_mm_cvtps_pd(v1), a), e1z = _mm_sub_pd(_mm_cvtps_pd(_mm_movehl_ps(v1, v1)), az);
    const __m128d e2 = _mm_sub_pd(_mm_cvtps_pd(v2), a), e2z = _mm_sub_pd(_mm_cvtps_pd(_mm_movehl_ps(v2, v2)), az);
    const __m128d e2s = _mm_shuffle_pd(e2, e2, 1);  // (e2y, e2x)
    const __m128d t = _mm_mul_pd(e1, e2s);           // (e1x e2y, e1y e2x)
    const __m128d n2 = _mm_sub_sd(t, _mm_unpackhi_pd(t, t));
    // (e1y e2z - e1z e2y, e1x e2z - e1z e2x) = (n0, -n1)
    const __m128d n01 = _mm_sub_pd(_mm_mul_pd(_mm_shuffle_pd(e1, e1, 1), _mm_unpacklo_pd(e2z, e2z)),
                                   _mm_mul_pd(_mm_unpacklo_pd(e1z, e1z), e2s));
    const __m128d zero = _mm_setzero_pd();
    return _mm_movemask_pd(_mm_cmpeq_pd(n01, zero)) == 3 && (_mm_movemask_pd(_mm_cmpeq_sd(n2, zero)) & 1);
}

}  // namespace vkas
