// Where a primitive falls among a range's object bins, the one rule the SAH builder (sah_builder.cpp) and the
// spatial-split builder (spatial_split_builder.cpp) share: lower + upper (twice the centroid) binned over the range's
// bounds doubled, so that no pass gathers centroid bounds; clamped in float first, so NaN lands in bin 0 and +inf in
// the last (invalid input still gets valid bins), then truncated.
#pragma once

#include <immintrin.h>

namespace vkas {

struct CentroidBins {
    __m128 origin, scale, lastBin;
    float axisScale[3];  // 0: the axis is not binned (no extent, or not asked for): everything is in its bin 0

    // binCount bins along each axis a with binned[a], over the box [lower, upper].
    CentroidBins(const float lower[3], const float upper[3], int binCount, const bool binned[3]) {
        float o[3];
        for (int a = 0; a < 3; ++a) {
            o[a] = lower[a] + lower[a];
            const float extent = (upper[a] + upper[a]) - o[a];
            axisScale[a] = binned[a] && extent > 0 ? (float(binCount) * 0.99999f) / extent : 0.0f;
        }
        origin = _mm_setr_ps(o[0], o[1], o[2], 0.0f);
        scale = _mm_setr_ps(axisScale[0], axisScale[1], axisScale[2], 0.0f);
        lastBin = _mm_set1_ps(float(binCount - 1));
    }
    // The primitive's unclamped bin coordinates along x, y, z (lane 3 unused): a bin <= b holds it on axis a
    // exactly when !(position[a] >= b + 1), for b + 1 <= the last bin.
    __m128 position(__m128 lo, __m128 up) const { return _mm_mul_ps(_mm_sub_ps(_mm_add_ps(lo, up), origin), scale); }
    // Its bins along x, y, z.
    __m128i of(__m128 lo, __m128 up) const {
        return _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(position(lo, up), _mm_setzero_ps()), lastBin));
    }
};

}  // namespace vkas
