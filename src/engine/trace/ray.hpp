// Ray set-up shared by every traversal path: the ray prepared once per structure it enters (inverse direction for
// the node test, the shear of the watertight triangle test) and the world-to-object transform of an instance.
#pragma once

#include <cmath>
#include <cstdint>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace vkas {

// The plane offsets of ShearedRay for each octant of the direction (bit i: invDir[i] < 0, the ray enters a box
// through its upper plane on axis i: 32 bytes past the lower one; each axis is 64 bytes past the previous, as
// format::Node lays them out, which node_intersector_sse.hpp checks).
struct OctantPlanes {
    uint32_t nearPlane[3], farPlane[3];
};

struct ShearedRay {
    float org[3];
    float dir[3];
    float invDir[3];  // for box tests
    int kx, ky, kz;
    float sx, sy, sz;
    // The byte offsets in a node (format::Node: lowerX, upperX, lowerY, upperY, lowerZ, upperZ, 8 floats each) of the
    // planes the ray meets first (near) and last (far) on each axis, resolved once per ray from the sign of invDir,
    // not once per node (node_intersector_sse.hpp's NodePlanes).
    OctantPlanes planes;
};

// The axis of the largest direction component (|d| per axis), the watertight test's kz; ties go to the later axis
// of each comparison, as the shear has always chosen.
inline int dominantAxis(float ax, float ay, float az) { return (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2); }

constexpr OctantPlanes octantPlanes(uint32_t octant) {
    OctantPlanes p{};
    for (uint32_t i = 0; i < 3; ++i) {
        const uint32_t upper = (octant >> i) & 1u ? 32u : 0u;
        p.nearPlane[i] = 64u * i + upper;
        p.farPlane[i] = 64u * i + 32u - upper;
    }
    return p;
}
inline constexpr OctantPlanes kOctantPlanes[8] = {octantPlanes(0), octantPlanes(1), octantPlanes(2), octantPlanes(3),
                                                  octantPlanes(4), octantPlanes(5), octantPlanes(6), octantPlanes(7)};

// The part of the set-up the node test reads (origin, direction, reciprocals, plane offsets): all a ray needs in a
// top level, whose leaves are instances, not triangles. The shear fields are left unset.
inline void prepareBoxRay(ShearedRay& r, const float org[3], const float dir[3]) {
    // Everything in locals first: `r` may alias `org` and `dir` for the compiler, which would reload them after
    // every store.
    const float o0 = org[0], o1 = org[1], o2 = org[2], d0 = dir[0], d1 = dir[1], d2 = dir[2];
    const float i0 = 1.0f / d0, i1 = 1.0f / d1, i2 = 1.0f / d2;
    // A negative reciprocal (dir < 0, or -0: invDir = -inf) enters a box through its upper plane.
    r.planes = kOctantPlanes[(i0 < 0.0f ? 1u : 0u) | (i1 < 0.0f ? 2u : 0u) | (i2 < 0.0f ? 4u : 0u)];
    r.org[0] = o0, r.org[1] = o1, r.org[2] = o2;
    r.dir[0] = d0, r.dir[1] = d1, r.dir[2] = d2;
    r.invDir[0] = i0, r.invDir[1] = i1, r.invDir[2] = i2;
}

// The whole set-up: the box part and the shear of the watertight triangle test.
inline void prepareShearedRay(ShearedRay& r, const float org[3], const float dir[3]) {
    const float d[3] = {dir[0], dir[1], dir[2]};
    prepareBoxRay(r, org, d);
    const int kz = dominantAxis(std::fabs(d[0]), std::fabs(d[1]), std::fabs(d[2]));
    static constexpr int kNext[3] = {1, 2, 0};
    int kx = kNext[kz], ky = kNext[kx];
    if (d[kz] < 0.0f) {  // keep the winding of the sheared triangle
        const int t = kx;
        kx = ky;
        ky = t;
    }
    r.kx = kx, r.ky = ky, r.kz = kz;
    r.sx = d[kx] / d[kz], r.sy = d[ky] / d[kz], r.sz = 1.0f / d[kz];
}

// The ray in an instance's object space: the 3x4 row-major world-to-object matrix applied in double, each result
// rounded once.
inline void transformRay(const float (*m)[4], const float o[3], const float d[3], float oo[3], float od[3]) {
    const double o0 = o[0], o1 = o[1], o2 = o[2], d0 = d[0], d1 = d[1], d2 = d[2];  // (oo, od may alias m, o, d)
    float ro[3], rd[3];
    for (int r = 0; r < 3; ++r) {
        const double m0 = m[r][0], m1 = m[r][1], m2 = m[r][2], m3 = m[r][3];
        ro[r] = float(m0 * o0 + m1 * o1 + m2 * o2 + m3);
        rd[r] = float(m0 * d0 + m1 * d1 + m2 * d2);
    }
    for (int r = 0; r < 3; ++r) oo[r] = ro[r], od[r] = rd[r];
}

#if defined(__x86_64__)
// transformRay in AVX: the same double operations in the same order, on the matrix's columns, so that the three
// rows are computed at once (each product of two floats is exact in double; the sums keep the scalar order
// ((m0 o0 + m1 o1) + m2 o2) + m3): the results are transformRay's bits. Callable only where the CPU has AVX2.
__attribute__((target("avx2"))) inline void transformRayAvx2(const float (*m)[4], const float o[3], const float d[3],
                                                             float oo[3], float od[3]) {
    __m128 c0 = _mm_loadu_ps(m[0]), c1 = _mm_loadu_ps(m[1]), c2 = _mm_loadu_ps(m[2]), c3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(c0, c1, c2, c3);  // c_j = (m[0][j], m[1][j], m[2][j], 0)
    const __m256d m0 = _mm256_cvtps_pd(c0), m1 = _mm256_cvtps_pd(c1), m2 = _mm256_cvtps_pd(c2),
                  m3 = _mm256_cvtps_pd(c3);
    const __m256d o0 = _mm256_set1_pd(o[0]), o1 = _mm256_set1_pd(o[1]), o2 = _mm256_set1_pd(o[2]);
    const __m256d d0 = _mm256_set1_pd(d[0]), d1 = _mm256_set1_pd(d[1]), d2 = _mm256_set1_pd(d[2]);
    const __m256d ro = _mm256_add_pd(
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m0, o0), _mm256_mul_pd(m1, o1)), _mm256_mul_pd(m2, o2)), m3);
    const __m256d rd =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m0, d0), _mm256_mul_pd(m1, d1)), _mm256_mul_pd(m2, d2));
    alignas(16) float fo[4], fd[4];
    _mm_store_ps(fo, _mm256_cvtpd_ps(ro));
    _mm_store_ps(fd, _mm256_cvtpd_ps(rd));
    for (int r = 0; r < 3; ++r) oo[r] = fo[r], od[r] = fd[r];
}
#endif

}  // namespace vkas
