// [NV-LSS] Ray/sphere test for VK_GEOMETRY_TYPE_SPHERES_NV primitives, in double precision.
//
// A sphere is the closed ball |x - c| <= r. The ray reports only where it enters the ball: a ray whose
// [tMin, tMax] segment starts inside the ball (or meets it only behind tMin) gets no hit (spec digest 3.5), and
// t is inclusive at both ends as for every non-triangle primitive (tMin <= t <= tMax).
//
// The entry is computed from the point of the line closest to the centre (the chord's midpoint), which keeps the
// result accurate for far-away and small spheres where the textbook b^2 - 4ac form cancels.
#pragma once

#include <cmath>

namespace vkas {

namespace swept {
inline double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
}  // namespace swept

// Where the line o + t d first meets the closed ball (c, r) (t may be negative). False when it never does.
inline bool ballEntry(const double o[3], const double d[3], const double c[3], double r, double& tEnter) {
    const double a = swept::dot3(d, d);
    if (!(a > 0.0) || !(r >= 0.0)) return false;
    const double oc[3] = {o[0] - c[0], o[1] - c[1], o[2] - c[2]};
    const double tc = -swept::dot3(oc, d) / a;  // closest approach to the centre
    const double p[3] = {oc[0] + tc * d[0], oc[1] + tc * d[1], oc[2] + tc * d[2]};
    const double h = r * r - swept::dot3(p, p);  // squared half-chord, times 1
    if (!(h >= 0.0)) return false;
    tEnter = tc - std::sqrt(h / a);
    return true;
}

// Ray/sphere candidate: true when the ray enters the ball at a t within [tMin, tMax]; tOut receives that t.
inline bool intersectSphere(const float org[3], const float dir[3], const float center[3], float radius, float tMin,
                            float tMax, float& tOut) {
    const double o[3] = {org[0], org[1], org[2]}, d[3] = {dir[0], dir[1], dir[2]};
    const double c[3] = {center[0], center[1], center[2]};
    double t;
    if (!ballEntry(o, d, c, double(radius), t)) return false;
    if (!(t >= double(tMin) && t <= double(tMax))) return false;
    tOut = float(t);  // rounding is monotonic, so the float stays within [tMin, tMax]
    return true;
}

}  // namespace vkas
