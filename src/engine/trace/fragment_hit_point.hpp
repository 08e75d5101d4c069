// Where a ray meets a triangle, for the region test of a fragment (format/fragment_section.hpp): the point that decides
// which one of a cut triangle's records reports a non-opaque candidate.
//
// The rule that exactly one fragment reports needs only that every fragment computes the same point: the regions
// partition space. That the reporting fragment is one the ray visits needs more: the point must lie within the
// builder's padding (builders/spatial_split_builder.cpp, 2^-17 of the triangle's largest coordinate) of where the ray
// really crosses the triangle, because only there does the ray pass through the fragment's box. The hit's float
// barycentrics are no such point: on a thin triangle (or a ray nearly along its plane) the watertight test's edge
// functions are differences of nearly equal products, and b and c can be wrong by a third of the triangle (issue 35:
// a sliver of a height field whose float barycentrics put the point 0.02 away from the ray, in a fragment the ray
// never visits, so no fragment reported the candidate).
//
// So the point is the barycentric combination of the exact weights w_i = d . (v_j - o) x (v_k - o), the scalar triple
// products whose float values the watertight test approximates, computed in double with a rigorous error bound, and
// again in binary128 where double cannot guarantee the point to 2^-20 of the triangle's size. Only where even
// binary128 cannot (the ray all but parallel to the triangle's plane, the weights' sum within rounding of zero) does
// the point fall back to the hit's barycentrics; it is still the same point for every fragment.
#pragma once

#include <cmath>

#include "engine/trace/ray.hpp"

namespace vkas {

namespace detail {

// The weights' sum S and the point v0 + (w1 (v1 - v0) + w2 (v2 - v0)) / S in precision Real with unit roundoff u;
// false when the error bound of S is not below 2^-20 |S| (then the point is not trusted).
template <typename Real>
bool hitPointIn(const float o[3], const float d[3], const float (*v)[3], Real u, double p[3]) {
    Real rel[3][3];  // v_i - o
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) rel[i][a] = Real(v[i][a]) - Real(o[a]);
    Real w[3];
    Real bound = 0;  // sum over the weights of |d| . (|a| x+ |b|), the size of each term
    for (int i = 0; i < 3; ++i) {
        const Real* a = rel[(i + 1) % 3];
        const Real* b = rel[(i + 2) % 3];
        const Real cx = a[1] * b[2] - a[2] * b[1];
        const Real cy = a[2] * b[0] - a[0] * b[2];
        const Real cz = a[0] * b[1] - a[1] * b[0];
        w[i] = Real(d[0]) * cx + Real(d[1]) * cy + Real(d[2]) * cz;
        auto mag = [](Real x) { return x < 0 ? -x : x; };
        bound += mag(Real(d[0])) * (mag(a[1] * b[2]) + mag(a[2] * b[1])) +
                 mag(Real(d[1])) * (mag(a[2] * b[0]) + mag(a[0] * b[2])) +
                 mag(Real(d[2])) * (mag(a[0] * b[1]) + mag(a[1] * b[0]));
    }
    const Real sum = w[0] + w[1] + w[2];
    // Each weight is 11 roundings deep (the differences, the products, the cross product's and the dot's sums, and
    // the total): |error of sum| <= gamma_12 * bound, gamma_n = n u / (1 - n u).
    const Real gamma = Real(12) * u / (Real(1) - Real(12) * u);
    const Real absSum = sum < 0 ? -sum : sum;
    if (!(gamma * bound * Real(1 << 20) < absSum)) return false;
    for (int a = 0; a < 3; ++a) {
        const Real e1 = Real(v[1][a]) - Real(v[0][a]), e2 = Real(v[2][a]) - Real(v[0][a]);
        p[a] = double(Real(v[0][a]) + (w[1] * e1 + w[2] * e2) / sum);
    }
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

}  // namespace detail

// The point of triangle v where the object-space ray r meets it, for the region test; (b, c) are the hit's
// barycentrics, the fallback. The same for every record of the triangle, whatever kernel computes it.
inline void fragmentHitPoint(const ShearedRay& r, const float (*v)[3], float b, float c, double p[3]) {
    if (detail::hitPointIn<double>(r.org, r.dir, v, std::ldexp(1.0, -53), p)) return;
#if defined(__SIZEOF_FLOAT128__)
    if (detail::hitPointIn<__float128>(r.org, r.dir, v, __float128(std::ldexp(1.0, -113)), p)) return;
#endif
    for (int a = 0; a < 3; ++a)
        p[a] = double(v[0][a]) + double(b) * (double(v[1][a]) - double(v[0][a])) +
               double(c) * (double(v[2][a]) - double(v[0][a]));
}

}  // namespace vkas
