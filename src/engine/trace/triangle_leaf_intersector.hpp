// The watertight triangle test (triangle_intersector.hpp) on four lanes of a format-2 triangle leaf at once (layout.hpp,
// TriangleLeaf), for the ray query and both batch kernels.
//
// The leaf's rows are loaded as they are stored (one unaligned load per row: the ray's axis permutation selects the
// rows, no transpose), each vertex is sheared once per lane, and the three edge functions are computed with the same
// float operations as intersectTriangle (no FMA: the project compiles with -ffp-contract=off), so every lane gets
// intersectTriangle's bits:
//   - lanes whose edge functions are all non-zero and of one sign are covered: only their determinant and t are
//     computed (coveredTriangleHit, in double, as intersectTriangle does);
//   - lanes with a zero edge function (the products of an edge are equal) go to intersectTriangle, whose double
//     recomputation and tie-break decide them; so do lanes with a NaN, which no comparison decides;
//   - lanes with edge functions of both strict signs are missed, as intersectTriangle would decide.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/ray.hpp"
#include "engine/trace/triangle_intersector.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vkas {

// The edge functions of (up to) four lanes of a leaf, and which lanes may be hit.
struct FourLaneEdges {
    alignas(16) float U[4], V[4], W[4];
    alignas(16) float Az0[4], Bz0[4], Cz0[4];
    uint32_t covered;  // lanes covered with non-zero edge functions: coveredTriangleHit gives the hit
    uint32_t undecided;  // lanes intersectTriangle must decide (a zero or NaN edge function)
};

// Lanes [lane0, lane0 + count) of `leaf` (count 1-4) against `r`. Rows are read 4 floats at a time: lanes past
// `count` read neighbouring bytes of the leaf (or its array's zero tail) and are masked off.
// Always inlined: a call (and the struct it fills, read back through memory) cost a fifth of the test itself.
[[gnu::always_inline]] inline void edgesOfFour(const format::ConstTriangleLeaf& leaf, uint32_t lane0, uint32_t count, const ShearedRay& r,
                        FourLaneEdges& e) {
    const uint32_t live = (1u << count) - 1u;
#if defined(__SSE2__)
    // Row 3 * vertex + axis starts at row(0) + (3 * vertex + axis) * n: one pointer per sheared axis and the
    // vertex stride, so the nine loads are addressing modes, not nine products of the ray's axes and the leaf size.
    const size_t n = leaf.n, vertexStride = 3 * n;
    const float* first = leaf.row(0) + lane0;
    const float *px = first + size_t(r.kx) * n, *py = first + size_t(r.ky) * n, *pz = first + size_t(r.kz) * n;
    auto row = [&](uint32_t vertex, const float* axisRow) { return _mm_loadu_ps(axisRow + vertex * vertexStride); };
    const __m128 ox = _mm_set1_ps(r.org[r.kx]), oy = _mm_set1_ps(r.org[r.ky]), oz = _mm_set1_ps(r.org[r.kz]);
    const __m128 sx = _mm_set1_ps(r.sx), sy = _mm_set1_ps(r.sy);
    const __m128 Az0 = _mm_sub_ps(row(0, pz), oz), Bz0 = _mm_sub_ps(row(1, pz), oz),
                 Cz0 = _mm_sub_ps(row(2, pz), oz);
    const __m128 Ax = _mm_sub_ps(_mm_sub_ps(row(0, px), ox), _mm_mul_ps(sx, Az0));
    const __m128 Ay = _mm_sub_ps(_mm_sub_ps(row(0, py), oy), _mm_mul_ps(sy, Az0));
    const __m128 Bx = _mm_sub_ps(_mm_sub_ps(row(1, px), ox), _mm_mul_ps(sx, Bz0));
    const __m128 By = _mm_sub_ps(_mm_sub_ps(row(1, py), oy), _mm_mul_ps(sy, Bz0));
    const __m128 Cx = _mm_sub_ps(_mm_sub_ps(row(2, px), ox), _mm_mul_ps(sx, Cz0));
    const __m128 Cy = _mm_sub_ps(_mm_sub_ps(row(2, py), oy), _mm_mul_ps(sy, Cz0));
    const __m128 U = _mm_sub_ps(_mm_mul_ps(Cx, By), _mm_mul_ps(Cy, Bx));
    const __m128 V = _mm_sub_ps(_mm_mul_ps(Ax, Cy), _mm_mul_ps(Ay, Cx));
    const __m128 W = _mm_sub_ps(_mm_mul_ps(Bx, Ay), _mm_mul_ps(By, Ax));
    const __m128 z = _mm_setzero_ps();
    const uint32_t allPositive = uint32_t(_mm_movemask_ps(
        _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(U, z), _mm_cmpgt_ps(V, z)), _mm_cmpgt_ps(W, z))));
    const uint32_t allNegative = uint32_t(_mm_movemask_ps(
        _mm_and_ps(_mm_and_ps(_mm_cmplt_ps(U, z), _mm_cmplt_ps(V, z)), _mm_cmplt_ps(W, z))));
    const __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, z), _mm_cmplt_ps(V, z)), _mm_cmplt_ps(W, z));
    const __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, z), _mm_cmpgt_ps(V, z)), _mm_cmpgt_ps(W, z));
    const __m128 zero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, z), _mm_cmpeq_ps(V, z)), _mm_cmpeq_ps(W, z));
    const uint32_t missed = uint32_t(_mm_movemask_ps(_mm_andnot_ps(zero, _mm_and_ps(neg, pos))));
    e.covered = (allPositive | allNegative) & live;
    e.undecided = ~(allPositive | allNegative | missed) & live;
    if (e.covered == 0) return;  // undecided lanes are recomputed from the positions
    _mm_store_ps(e.U, U), _mm_store_ps(e.V, V), _mm_store_ps(e.W, W);
    _mm_store_ps(e.Az0, Az0), _mm_store_ps(e.Bz0, Bz0), _mm_store_ps(e.Cz0, Cz0);
#else
    e.covered = 0;
    e.undecided = live;  // without SSE2 every lane takes the scalar test
    (void)leaf, (void)lane0, (void)r;
#endif
}

// The intersection of lane `lane` (of the four starting at lane0) that edgesOfFour found covered or undecided: the
// same result as intersectTriangle on the lane's positions.
inline bool laneIntersection(const format::ConstTriangleLeaf& leaf, uint32_t lane0, uint32_t lane,
                             const FourLaneEdges& e, const ShearedRay& r, TriangleHit& hit) {
    if (e.covered & (1u << lane))
        return coveredTriangleHit(r, e.U[lane], e.V[lane], e.W[lane], e.Az0[lane], e.Bz0[lane], e.Cz0[lane], hit);
    float v[3][3];
    leaf.positions(lane0 + lane, v);
    return intersectTriangle(r, v[0], v[1], v[2], hit);
}

}  // namespace vkas
