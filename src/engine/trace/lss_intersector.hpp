// [NV-LSS] Ray/linear-swept-sphere test for VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV primitives, in double.
//
// An LSS with endpoints p0, p1 and radii r0, r1 is the union of the balls B(s) with centre p0 + s (p1 - p0) and
// radius r0 + s (r1 - r0), s in [0, 1]: the convex hull of its two end balls. Its surface consists of the
// midsection (the cone tangent to the spheres, where the touching sphere has 0 < s < 1) and two end caps (the
// parts of the end spheres outside the cone). The hit value u is the s of the sphere the hit point lies on:
// 0 or 1 on an end cap, in between on the midsection.
//
// Only the entry point counts: a ray whose [tMin, tMax] segment starts inside the shape, or that enters it
// through an end cap the end-caps mode turned off, gets no hit (spec digest 3.5). For a self-enclosing LSS (one
// end ball contains the other), only the outer cap is tested: the shape is that ball. t is inclusive at both
// ends, as for every non-triangle primitive.
//
// Method. With w = o - p0, e = p1 - p0, dr = r1 - r0, the point o + t d is in B(s) when
//   g(t, s) = A t^2 + B s^2 + 2 C t s + 2 D t + 2 E s + F <= 0,
//   A = d.d, B = e.e - dr^2, C = -d.e, D = w.d, E = -w.e - r0 dr, F = w.w - r0^2.
// When B > 0, g is convex in s with its minimum at s*(t) = -(C t + E) / B, so the shape's boundary along the
// line is where g(t, clamp(s*(t), 0, 1)) = 0: roots of the end spheres with s* <= 0 or s* >= 1, and roots of
// the cone equation (A B - C^2) t^2 + 2 (D B - C E) t + (F B - E^2) = 0 with s* in [0, 1]. The smallest such
// root is the entry. The ray origin is first moved along the ray to the point nearest the segment's midpoint so
// that all quantities are of the size of the primitive.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

#include "engine/trace/sphere_intersector.hpp"

namespace vkas {

constexpr uint32_t kLssCapBit0 = 0x1, kLssCapBit1 = 0x2;

namespace swept {

// Both roots of a t^2 + 2 b t + c = 0 (a != 0), ordered; false when they are complex.
inline bool quadraticRoots(double a, double b, double c, double& t0, double& t1) {
    const double disc = b * b - a * c;
    if (!(disc >= 0.0)) return false;
    const double q = -(b + std::copysign(std::sqrt(disc), b));  // no cancellation
    if (q == 0.0) {  // b = 0 and disc = 0: a double root at 0
        t0 = t1 = 0.0;
        return true;
    }
    t0 = q / a;
    t1 = c / q;
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

}  // namespace swept

// Entry t (line parameter, may be negative) and hit value u of the line o + t d with the LSS, ignoring caps and
// the t range. False when the line misses the shape.
inline bool lssEntry(const double o[3], const double d[3], const double p0[3], double r0, const double p1[3],
                     double r1, double& tEnter, double& u) {
    using swept::dot3;
    const double A = dot3(d, d);
    if (!(A > 0.0)) return false;
    const double e[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const double dr = r1 - r0;
    const double ee = dot3(e, e);
    const double B = ee - dr * dr;
    if (!(B > 1e-12 * (ee + dr * dr))) {
        // Self-enclosing (or a point): the shape is the larger end ball; its cap is the only surface.
        const bool first = r0 >= r1;
        u = first ? 0.0 : 1.0;
        return ballEntry(o, d, first ? p0 : p1, first ? r0 : r1, tEnter);
    }
    // Shift the origin along the ray next to the segment's midpoint.
    const double mid[3] = {0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]), 0.5 * (p0[2] + p1[2])};
    const double om[3] = {mid[0] - o[0], mid[1] - o[1], mid[2] - o[2]};
    const double ts = dot3(om, d) / A;
    const double os[3] = {o[0] + ts * d[0], o[1] + ts * d[1], o[2] + ts * d[2]};
    const double w[3] = {os[0] - p0[0], os[1] - p0[1], os[2] - p0[2]};
    const double w1[3] = {os[0] - p1[0], os[1] - p1[1], os[2] - p1[2]};
    const double C = -dot3(d, e), D = dot3(w, d), E = -dot3(w, e) - r0 * dr, F = dot3(w, w) - r0 * r0;
    auto sStar = [&](double t) { return -(C * t + E) / B; };
    constexpr double kSlack = 1e-8;  // tolerance on s* at the cap/cone junctions, where both pieces agree
    double best = INFINITY, bestU = 0.0;
    auto consider = [&](double t, double s) {
        if (t < best) best = t, bestU = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    };
    double t0, t1;
    // Sphere 0 where s* <= 0.
    if (swept::quadraticRoots(A, D, F, t0, t1)) {
        for (double t : {t0, t1})
            if (sStar(t) <= kSlack) consider(t, 0.0);
    }
    // Sphere 1 where s* >= 1.
    if (swept::quadraticRoots(A, dot3(w1, d), dot3(w1, w1) - r1 * r1, t0, t1)) {
        for (double t : {t0, t1})
            if (sStar(t) >= 1.0 - kSlack) consider(t, 1.0);
    }
    // The cone where 0 <= s* <= 1.
    const double qa = A * B - C * C, qb = D * B - C * E, qc = F * B - E * E;
    auto coneRoot = [&](double t) {
        const double s = sStar(t);
        if (s >= -kSlack && s <= 1.0 + kSlack) consider(t, s);
    };
    if (qa != 0.0 && swept::quadraticRoots(qa, qb, qc, t0, t1)) {
        coneRoot(t0);
        coneRoot(t1);
    } else if (qa == 0.0 && qb != 0.0) {
        coneRoot(-qc / (2.0 * qb));
    }
    if (best == INFINITY) return false;
    tEnter = ts + best;
    u = bestU;
    return true;
}

// Ray/LSS candidate: true when the ray enters the shape at a t within [tMin, tMax] through a surface that exists
// (the midsection, or an end cap whose bit is set in caps). tOut and uOut receive t and the hit value.
inline bool intersectLss(const float org[3], const float dir[3], const float p0[3], float r0, const float p1[3],
                         float r1, uint32_t caps, float tMin, float tMax, float& tOut, float& uOut) {
    const double o[3] = {org[0], org[1], org[2]}, d[3] = {dir[0], dir[1], dir[2]};
    const double a[3] = {p0[0], p0[1], p0[2]}, b[3] = {p1[0], p1[1], p1[2]};
    double t, u;
    if (!lssEntry(o, d, a, double(r0), b, double(r1), t, u)) return false;
    if (u <= 0.0 && !(caps & kLssCapBit0)) return false;  // entering through an absent cap
    if (u >= 1.0 && !(caps & kLssCapBit1)) return false;
    if (!(t >= double(tMin) && t <= double(tMax))) return false;
    tOut = float(t);
    // Exactly 0 or 1 only on an end cap: a midsection hit next to a junction keeps a float strictly inside.
    uOut = float(u);
    if (u > 0.0 && uOut <= 0.0f) uOut = std::nextafter(0.0f, 1.0f);
    if (u < 1.0 && uOut >= 1.0f) uOut = std::nextafter(1.0f, 0.0f);
    return true;
}

}  // namespace vkas
