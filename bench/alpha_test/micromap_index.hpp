// The application side of VK_EXT_opacity_micromap for vkas_bench_alpha: the mapping from a triangle's barycentrics
// to the index of its micro-triangle at a subdivision level (the space-filling curve of the spec's "Ray Opacity
// Micromap"; the specification's reference code is BarycentricsToSpaceFillingCurveIndex in the extension appendix),
// the state bits "packed from LSB to MSB in each byte", and the centroid of every micro-triangle of a level, with
// which the bench fills the micromaps and checks that the mapping is a bijection.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace alpha {

// Spreads the low 16 bits of x to the even bit positions.
inline uint32_t spreadBits(uint32_t x) {
    x = (x | (x << 8)) & 0x00ff00ffu;
    x = (x | (x << 4)) & 0x0f0f0f0fu;
    x = (x | (x << 2)) & 0x33333333u;
    x = (x | (x << 1)) & 0x55555555u;
    return x;
}

// The micro-triangle of subdivision level `level` that the barycentrics (u, v) fall in (u weighs vertex 1, v vertex
// 2), as an index along the micromap's space-filling curve. The same arithmetic as the specification's reference code,
// in float, so that an application's alpha test and an implementation's micromap lookup agree exactly.
inline uint32_t microTriangleIndex(float u, float v, uint32_t level) {
    const uint32_t n = 1u << level;
    u = std::clamp(u, 0.0f, 1.0f);
    v = std::clamp(v, 0.0f, 1.0f);
    const float fu = u * float(n), fv = v * float(n);
    uint32_t iu = uint32_t(fu), iv = uint32_t(fv);
    const float uf = fu - float(iu), vf = fv - float(iv);
    iu = std::min(iu, n - 1u);
    iv = std::min(iv, n - 1u);
    const uint32_t iuv = iu + iv;
    if (iuv >= n) iu -= iuv - n + 1u;  // past the hypotenuse: back into the triangle
    uint32_t iw = ~(iu + iv);
    if (uf + vf >= 1.0f && iuv < n - 1u) --iw;  // the upper ("flipped") micro-triangle of the (iu, iv) cell
    uint32_t b0 = ~(iu ^ iw) & (n - 1u);
    const uint32_t t = (iu ^ iv) & b0;
    uint32_t f = t;  // prefix parity of t
    f ^= f >> 1u;
    f ^= f >> 2u;
    f ^= f >> 4u;
    f ^= f >> 8u;
    const uint32_t b1 = ((f ^ iu) & ~b0) | t;
    return spreadBits(b0) | (spreadBits(b1) << 1u);
}

// States "packed from LSB to MSB in each byte": 1 bit for 2-state, 2 bits for 4-state.
inline uint32_t state2(const uint8_t* data, uint32_t index) { return (data[index >> 3] >> (index & 7u)) & 1u; }
inline uint32_t state4(const uint8_t* data, uint32_t index) { return (data[index >> 2] >> (2u * (index & 3u))) & 3u; }
inline void setState2(uint8_t* data, uint32_t index, uint32_t s) {
    data[index >> 3] = uint8_t((data[index >> 3] & ~(1u << (index & 7u))) | ((s & 1u) << (index & 7u)));
}
inline void setState4(uint8_t* data, uint32_t index, uint32_t s) {
    const uint32_t shift = 2u * (index & 3u);
    data[index >> 2] = uint8_t((data[index >> 2] & ~(3u << shift)) | ((s & 3u) << shift));
}
constexpr uint32_t bytes2(uint32_t level) { return std::max(1u, (1u << (2 * level)) / 8u); }
constexpr uint32_t bytes4(uint32_t level) { return std::max(1u, (1u << (2 * level)) / 4u); }

// The centroid (u, v) of every micro-triangle of a level: the lower triangle of each grid cell (iu, iv) with
// iu + iv < n, and the upper one where iu + iv < n - 1.
struct Centroid {
    float u, v;
};
inline std::vector<Centroid> microTriangleCentroids(uint32_t level) {
    const uint32_t n = 1u << level;
    std::vector<Centroid> c;
    c.reserve(size_t(n) * n);
    for (uint32_t iv = 0; iv < n; ++iv)
        for (uint32_t iu = 0; iu + iv < n; ++iu) {
            c.push_back({(float(iu) + 1.0f / 3) / float(n), (float(iv) + 1.0f / 3) / float(n)});
            if (iu + iv + 1 < n) c.push_back({(float(iu) + 2.0f / 3) / float(n), (float(iv) + 2.0f / 3) / float(n)});
        }
    return c;
}

}  // namespace alpha
