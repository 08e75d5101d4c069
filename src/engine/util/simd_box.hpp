// Axis-aligned boxes in two SSE registers (x, y, z in lanes 0-2; lane 3 is kept at a harmless value), for the
// inner loops of the builders and the refit: extending a box is two instructions instead of six.
//
// The two kinds differ only in what a NaN coordinate does, which the name says:
//   SimdBoxNanSpreads: a NaN in what is added makes that coordinate of the box NaN (_mm_min_ps(box, new) returns
//                      `new` when either is NaN). For inputs known to hold no NaN: the builders' PrimRef boxes.
//   SimdBoxNanIgnored: a NaN in what is added leaves the box as it was, exactly as Aabb::extend (std::min and
//                      std::max keep their first argument unless the second compares smaller / larger). For the
//                      refit, which re-reads application data.
#pragma once

#include <immintrin.h>

#include <limits>

#include "engine/util/math.hpp"

namespace vkas {

struct SimdBoxNanSpreads {
    __m128 lower = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 upper = _mm_set1_ps(-std::numeric_limits<float>::infinity());

    void extend(__m128 lo, __m128 up) {
        lower = _mm_min_ps(lower, lo);
        upper = _mm_max_ps(upper, up);
    }
    void extend(const SimdBoxNanSpreads& b) { extend(b.lower, b.upper); }

    // Half the surface area (only ratios matter to the SAH); 0 for an empty box, as Aabb::halfArea.
    // In registers: (dx dy + dy dz) + dz dx, rounded exactly as the scalar expression.
    float halfArea() const {
        if ((_mm_movemask_ps(_mm_cmple_ps(lower, upper)) & 7) != 7) return 0.0f;
        const __m128 d = _mm_sub_ps(upper, lower);
        const __m128 p = _mm_mul_ps(d, _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1)));  // dx dy, dy dz, dz dx
        const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 1)));
        return _mm_cvtss_f32(_mm_add_ss(s, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 2, 1, 2))));
    }

    Aabb aabb() const {
        alignas(16) float lo[4], up[4];
        _mm_store_ps(lo, lower);
        _mm_store_ps(up, upper);
        Aabb b;
        b.lower = {lo[0], lo[1], lo[2]};
        b.upper = {up[0], up[1], up[2]};
        return b;
    }
};

struct SimdBoxNanIgnored {
    __m128 lower = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 upper = _mm_set1_ps(-std::numeric_limits<float>::infinity());

    // The new point comes first: _mm_min_ps(p, box) returns `box` when p is NaN (ties too keep the box).
    void extend(__m128 p) {
        lower = _mm_min_ps(p, lower);
        upper = _mm_max_ps(p, upper);
    }
    void extend(const Aabb& b) {
        lower = _mm_min_ps(_mm_setr_ps(b.lower.x, b.lower.y, b.lower.z, 0.0f), lower);
        upper = _mm_max_ps(_mm_setr_ps(b.upper.x, b.upper.y, b.upper.z, 0.0f), upper);
    }
};

// Lanes 0-2 of v, lane 3 zeroed: a PrimRef's fourth word is an index, whose bits would be a denormal float.
inline __m128 xyz(__m128 v) { return _mm_and_ps(v, _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1))); }

}  // namespace vkas
