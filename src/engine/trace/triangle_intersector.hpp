// Watertight ray/triangle intersection (Woop, Benthin and Wald, JCGT 2013) with a consistent tie-break.
//
// The ray is sheared so that it runs along +z through the origin; the three 2D edge functions U, V, W then
// decide coverage. Edge functions that are exactly zero in single precision are recomputed in double, where
// the products of floats are exact, so a zero is a true zero. A ray exactly on an edge or vertex is resolved
// by symbolic perturbation: the ray is moved by (e, e*eta) with 0 < eta << e infinitesimal, and a zero edge
// function takes the sign of its derivative in that direction. Neighbouring triangles share bit-identical
// sheared vertices, so a ray through a shared edge or through the vertex of a closed fan is reported by
// exactly one of them.
#pragma once

#include <cmath>
#include <cstdlib>

#include "engine/trace/ray.hpp"

namespace vkas {

struct TriangleHit {
    float t;
    float b, c;      // barycentric weights of vertices 1 and 2
    bool frontFace;  // before instance flags: the ray sees the vertices counter-clockwise (right-handed)
};

namespace detail {
// Sign of edge function cross(p1, p2) after the symbolic perturbation, for an edge function that is zero.
inline float perturbedSign(float p1x, float p1y, float p2x, float p2y) {
    if (p1y != p2y) return p1y > p2y ? 1.0f : -1.0f;
    if (p2x != p1x) return p2x > p1x ? 1.0f : -1.0f;
    return 0.0f;
}
}  // namespace detail

// The hit of a triangle the ray covers, from its edge functions U, V, W (float, each of one sign and not zero, or
// recomputed in double and rounded) and the vertices' z before the shear's scale (Az0 = v0[kz] - org[kz], ...).
// Shared by intersectTriangle and the four-lane leaf test (triangle_leaf_intersector.hpp), so both give the same bits.
inline bool coveredTriangleHit(const ShearedRay& r, float U, float V, float W, float Az0, float Bz0, float Cz0,
                               TriangleHit& hit) {
    // t and the barycentrics in double: the products of floats are exact there, so only the sums and the
    // division round (a ray from z = 1 to the plane z = -2 gets t = 3 exactly, not 3 + 2 ulp).
    const double det = double(U) + double(V) + double(W);
    if (det == 0.0 || !std::isfinite(det)) return false;  // edge-on: never a candidate
    const double Az = double(r.sz) * Az0, Bz = double(r.sz) * Bz0, Cz = double(r.sz) * Cz0;
    const double T = double(U) * Az + double(V) * Bz + double(W) * Cz;
    hit.t = float(T / det);
    hit.b = float(double(V) / det);
    hit.c = float(double(W) / det);
    hit.frontFace = det > 0.0;
    return true;
}

// Returns true and fills `hit` when the ray covers the triangle with a non-zero determinant. The caller
// applies the t interval.
inline bool intersectTriangle(const ShearedRay& r, const float v0[3], const float v1[3], const float v2[3],
                              TriangleHit& hit) {
    const float Ax0 = v0[r.kx] - r.org[r.kx], Ay0 = v0[r.ky] - r.org[r.ky], Az0 = v0[r.kz] - r.org[r.kz];
    const float Bx0 = v1[r.kx] - r.org[r.kx], By0 = v1[r.ky] - r.org[r.ky], Bz0 = v1[r.kz] - r.org[r.kz];
    const float Cx0 = v2[r.kx] - r.org[r.kx], Cy0 = v2[r.ky] - r.org[r.ky], Cz0 = v2[r.kz] - r.org[r.kz];
    const float Ax = Ax0 - r.sx * Az0, Ay = Ay0 - r.sy * Az0;
    const float Bx = Bx0 - r.sx * Bz0, By = By0 - r.sy * Bz0;
    const float Cx = Cx0 - r.sx * Cz0, Cy = Cy0 - r.sy * Cz0;

    float U = Cx * By - Cy * Bx;
    float V = Ax * Cy - Ay * Cx;
    float W = Bx * Ay - By * Ax;
    float su = U, sv = V, sw = W;  // signs that decide coverage
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        const double dU = double(Cx) * double(By) - double(Cy) * double(Bx);
        const double dV = double(Ax) * double(Cy) - double(Ay) * double(Cx);
        const double dW = double(Bx) * double(Ay) - double(By) * double(Ax);
        U = float(dU), V = float(dV), W = float(dW);
        // Signs after perturbation decide coverage; the unperturbed values give t and the barycentrics.
        su = dU != 0.0 ? (dU > 0.0 ? 1.0f : -1.0f) : detail::perturbedSign(Cx, Cy, Bx, By);
        sv = dV != 0.0 ? (dV > 0.0 ? 1.0f : -1.0f) : detail::perturbedSign(Ax, Ay, Cx, Cy);
        sw = dW != 0.0 ? (dW > 0.0 ? 1.0f : -1.0f) : detail::perturbedSign(Bx, By, Ax, Ay);
    }
    if ((su < 0.0f || sv < 0.0f || sw < 0.0f) && (su > 0.0f || sv > 0.0f || sw > 0.0f)) return false;
    if (su == 0.0f || sv == 0.0f || sw == 0.0f) return false;  // a collapsed edge
    return coveredTriangleHit(r, U, V, W, Az0, Bz0, Cz0, hit);
}

}  // namespace vkas
