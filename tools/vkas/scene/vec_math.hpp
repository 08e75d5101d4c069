// Small vector and affine-transform helpers for the tool (scene generation and shading).
#pragma once

#include <cmath>
#include <cstdint>

#include <vkas/vkas.h>

namespace vkas_tool {

struct Vec3 {
    float x = 0, y = 0, z = 0;
};

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator*(float s, Vec3 a) { return a * s; }
inline Vec3 mul(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) {
    float l = length(a);
    return l > 0.0f ? a * (1.0f / l) : Vec3{0.0f, 1.0f, 0.0f};
}

// Row-major 3x4 affine transform, the layout of VkTransformMatrixKHR: p' = M[:, 0..2] * p + M[:, 3].
struct Affine {
    float m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

    Vec3 point(Vec3 p) const {
        return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
                m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
                m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
    }
    Vec3 vector(Vec3 v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    // Transforms a normal with the inverse transpose of the linear part (up to scale: the cofactor matrix).
    Vec3 normal(Vec3 n) const {
        Vec3 c0{m[0][0], m[1][0], m[2][0]}, c1{m[0][1], m[1][1], m[2][1]}, c2{m[0][2], m[1][2], m[2][2]};
        Vec3 r0 = cross(c1, c2), r1 = cross(c2, c0), r2 = cross(c0, c1);
        return r0 * n.x + r1 * n.y + r2 * n.z;
    }
    // The inverse transform (the linear part must be invertible).
    Affine inverse() const {
        Vec3 c0{m[0][0], m[1][0], m[2][0]}, c1{m[0][1], m[1][1], m[2][1]}, c2{m[0][2], m[1][2], m[2][2]};
        Vec3 r0 = cross(c1, c2), r1 = cross(c2, c0), r2 = cross(c0, c1);  // rows of the inverse, times det
        float invDet = 1.0f / dot(c0, r0);
        Affine a;
        const Vec3 rows[3] = {r0 * invDet, r1 * invDet, r2 * invDet};
        const Vec3 t{m[0][3], m[1][3], m[2][3]};
        for (int r = 0; r < 3; ++r) {
            a.m[r][0] = rows[r].x, a.m[r][1] = rows[r].y, a.m[r][2] = rows[r].z;
            a.m[r][3] = -dot(rows[r], t);
        }
        return a;
    }
    VkTransformMatrixKHR toVk() const {
        VkTransformMatrixKHR t{};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) t.matrix[r][c] = m[r][c];
        return t;
    }

    static Affine translation(Vec3 t) {
        Affine a;
        a.m[0][3] = t.x, a.m[1][3] = t.y, a.m[2][3] = t.z;
        return a;
    }
    static Affine scale(Vec3 s) {
        Affine a;
        a.m[0][0] = s.x, a.m[1][1] = s.y, a.m[2][2] = s.z;
        return a;
    }
    // Rotation by `angle` radians about the unit axis `u`.
    static Affine rotation(Vec3 u, float angle) {
        u = normalize(u);
        float c = std::cos(angle), s = std::sin(angle), t = 1.0f - c;
        Affine a;
        a.m[0][0] = t * u.x * u.x + c, a.m[0][1] = t * u.x * u.y - s * u.z, a.m[0][2] = t * u.x * u.z + s * u.y;
        a.m[1][0] = t * u.x * u.y + s * u.z, a.m[1][1] = t * u.y * u.y + c, a.m[1][2] = t * u.y * u.z - s * u.x;
        a.m[2][0] = t * u.x * u.z - s * u.y, a.m[2][1] = t * u.y * u.z + s * u.x, a.m[2][2] = t * u.z * u.z + c;
        return a;
    }
};

// a * b: apply b first, then a.
inline Affine operator*(const Affine& a, const Affine& b) {
    Affine r;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
            float v = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
            if (j == 3) v += a.m[i][3];
            r.m[i][j] = v;
        }
    }
    return r;
}

// Small deterministic random numbers (PCG32): scene generation and sampling give the same image on every run.
class Rng {
public:
    explicit Rng(uint64_t seed, uint64_t stream = 1) : inc_((stream << 1u) | 1u) {
        next();
        state_ += seed;
        next();
    }
    uint32_t next() {
        uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
    }
    float uniform() { return static_cast<float>(next() >> 8) * (1.0f / 16777216.0f); }  // [0, 1)
    float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }

private:
    uint64_t state_ = 0;
    uint64_t inc_;
};

}  // namespace vkas_tool
