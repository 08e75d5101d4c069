// Small vector and box types shared by the builder and the traversal. Plain structs, no SIMD: the hot loops
// that need SIMD write it themselves.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace vkas {

struct Vec3 {
    float x = 0, y = 0, z = 0;
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 vmin(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 vmax(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

struct Aabb {
    Vec3 lower{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
               std::numeric_limits<float>::infinity()};
    Vec3 upper{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
               -std::numeric_limits<float>::infinity()};

    void extend(Vec3 p) {
        lower = vmin(lower, p);
        upper = vmax(upper, p);
    }
    void extend(const Aabb& b) {
        lower = vmin(lower, b.lower);
        upper = vmax(upper, b.upper);
    }
    bool empty() const { return !(lower.x <= upper.x && lower.y <= upper.y && lower.z <= upper.z); }
    Vec3 center2() const { return lower + upper; }  // twice the centre: saves a multiply in binning
    // Half the surface area; only ratios matter to the SAH.
    float halfArea() const {
        if (empty()) return 0.0f;
        Vec3 d = upper - lower;
        return d.x * d.y + d.y * d.z + d.z * d.x;
    }
};

// Row-major 3x4 affine transform, the layout of VkTransformMatrixKHR.
struct Affine3x4d {
    double m[3][4];
};

inline Affine3x4d affineFromFloat(const float src[3][4]) {
    Affine3x4d a;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) a.m[r][c] = src[r][c];
    return a;
}

inline void applyAffine(const Affine3x4d& a, const double p[3], double out[3]) {
    for (int r = 0; r < 3; ++r) out[r] = a.m[r][0] * p[0] + a.m[r][1] * p[1] + a.m[r][2] * p[2] + a.m[r][3];
}

inline void applyLinear(const Affine3x4d& a, const double v[3], double out[3]) {
    for (int r = 0; r < 3; ++r) out[r] = a.m[r][0] * v[0] + a.m[r][1] * v[1] + a.m[r][2] * v[2];
}

// Inverse of an affine transform, in double. Returns false when the 3x3 part is singular (an app error: the
// spec requires invertible transforms); the result is then the identity's inverse-safe fallback of zeros.
inline bool invertAffine(const Affine3x4d& a, Affine3x4d& inv) {
    const double(*m)[4] = a.m;
    double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (det == 0.0 || !std::isfinite(det)) {
        std::memset(&inv, 0, sizeof inv);
        return false;
    }
    double id = 1.0 / det;
    double r[3][3];
    r[0][0] = c00 * id;
    r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id;
    r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id;
    r[1][0] = c01 * id;
    r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id;
    r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id;
    r[2][0] = c02 * id;
    r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id;
    r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) inv.m[i][j] = r[i][j];
        inv.m[i][3] = -(r[i][0] * m[0][3] + r[i][1] * m[1][3] + r[i][2] * m[2][3]);
    }
    return true;
}

// Unaligned loads and stores: host pointers given to builds have no alignment requirement.
template <class T>
inline T loadUnaligned(const void* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
template <class T>
inline void storeUnaligned(void* p, const T& v) {
    std::memcpy(p, &v, sizeof v);
}

// The float nearest below / above a double: bounds computed in double, rounded outwards so the float box holds them.
inline float roundDown(double v) {
    float f = float(v);
    return double(f) > v ? std::nextafter(f, -INFINITY) : f;
}
inline float roundUp(double v) {
    float f = float(v);
    return double(f) < v ? std::nextafter(f, INFINITY) : f;
}

// True when a triangle collapses to a line or a point: it never produces an intersection. Inline so that builds,
// refits and traversal (motion triangles at the ray time) decide with the very same operations.
inline bool isDegenerateTriangle(const float v[3][3]) {
    // Differences of floats are exact in double (barring extreme exponent ranges), so a zero cross product
    // means the three points are collinear.
    double e1[3], e2[3];
    for (int c = 0; c < 3; ++c) {
        e1[c] = double(v[1][c]) - double(v[0][c]);
        e2[c] = double(v[2][c]) - double(v[0][c]);
    }
    const double n0 = e1[1] * e2[2] - e1[2] * e2[1];
    const double n1 = e1[2] * e2[0] - e1[0] * e2[2];
    const double n2 = e1[0] * e2[1] - e1[1] * e2[0];
    return n0 == 0.0 && n1 == 0.0 && n2 == 0.0;
}

}  // namespace vkas
