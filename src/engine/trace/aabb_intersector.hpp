// Ray/box test for AABB primitives (VK_GEOMETRY_TYPE_AABBS_KHR).
//
// An AABB is a candidate when the closed segment of the ray inside the box overlaps [tMin, tMax]: the bounds are
// inclusive for every primitive but triangles, and a ray that starts inside a box hits it. The slabs are
// computed in double from the float ray and box: differences of floats are exact there and each quotient is
// rounded once, so the interval is within a few double ulps of the exact one. A relative slack far above that
// error, and far below float precision, keeps rays that touch an edge, a corner or a flat box in.
#pragma once

#include <algorithm>
#include <cmath>

namespace vkas {

constexpr double kAabbSlack = 1.0 / (1ull << 40);

// Returns true when the ray org + t * dir, t in [tMin, tMax], meets the box [lower, upper] (min <= max on every
// axis; the builder drops other boxes). tEnter receives the first such t.
inline bool intersectAabb(const float org[3], const float dir[3], const float lower[3], const float upper[3],
                          float tMin, float tMax, float& tEnter) {
    double t0 = tMin, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        const double o = org[a], d = dir[a], lo = lower[a], hi = upper[a];
        if (d == 0.0) {  // parallel to the slab: inside it (boundary included) or never
            if (o < lo || o > hi) return false;
            continue;
        }
        double tNear = (lo - o) / d, tFar = (hi - o) / d;
        if (d < 0.0) std::swap(tNear, tFar);
        t0 = std::max(t0, tNear);
        t1 = std::min(t1, tFar);
    }
    if (!(t0 - t1 <= kAabbSlack * (std::abs(t0) + std::abs(t1)))) return false;
    tEnter = float(t0);
    return true;
}

}  // namespace vkas
