// [EXT-OMM] How an opacity micromap decides a triangle candidate (the spec's "Ray Opacity Micromap"): the micro-
// triangle its barycentrics select, that micro-triangle's state, and the state's meaning under the 2-state override.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/format/opacity_section.hpp"

namespace vkas {

// "These values are mapped into a linear index with a space filling curve which is defined recursively by traversing
// into the sub-triangle nearest vertex 0, then the middle triangle with ordering flipped, then nearest vertex 1, then
// nearest vertex 2 with ordering flipped." This is the mapping of the specification's reference code
// (BarycentricsToSpaceFillingCurveIndex, appendix VK_EXT_opacity_micromap), step for step in float, so that every
// (u, v) selects exactly one micro-triangle: a point on an edge between two micro-triangles belongs to the one the
// reference code's rounding picks (the float sum of the fractional parts, compared with 1), never to both or none.
// tests/support/oracle_micromap.cpp checks it against an independent recursive descent in double precision.
inline uint32_t microTriangleIndex(float u, float v, uint32_t level) {
    const uint32_t n = 1u << level;  // micro-triangles along an edge
    u = u < 0.0f ? 0.0f : (u > 1.0f ? 1.0f : u);
    v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
    // Quantize: row iu, column iv of the grid of micro-triangle pairs (scaling by a power of two is exact).
    const float su = u * float(n), sv = v * float(n);
    uint32_t iu = uint32_t(su), iv = uint32_t(sv);
    const float fracU = su - float(iu), fracV = sv - float(iv);
    if (iu >= n) iu = n - 1;
    if (iv >= n) iv = n - 1;
    const uint32_t iuv = iu + iv;
    if (iuv >= n) iu -= iuv - n + 1;  // past the hypotenuse: back into the last diagonal
    uint32_t iw = ~(iu + iv);
    if (fracU + fracV >= 1.0f && iuv < n - 1) --iw;  // the upper ("flipped") triangle of the pair
    // The curve's two bits per level, computed for all levels at once.
    const uint32_t mask = n - 1;
    const uint32_t low = ~(iu ^ iw) & mask;
    const uint32_t t = (iu ^ iv) & low;
    uint32_t prefix = t;  // xor of t's higher bits: the flips inherited from the coarser levels
    prefix ^= prefix >> 1;
    prefix ^= prefix >> 2;
    prefix ^= prefix >> 4;
    prefix ^= prefix >> 8;
    const uint32_t high = ((prefix ^ iu) & ~low) | t;
    auto spread = [](uint32_t x) {  // bit k to bit 2k
        x = (x | (x << 8)) & 0x00FF'00FFu;
        x = (x | (x << 4)) & 0x0F0F'0F0Fu;
        x = (x | (x << 2)) & 0x3333'3333u;
        x = (x | (x << 1)) & 0x5555'5555u;
        return x;
    };
    return spread(low) | (spread(high) << 1);
}

enum class MicromapOpacity : uint8_t { Ignored, Opaque, NonOpaque };

// "The final result of the opacity micromap lookup operation is determined as shown in the following table based on
// the format and retrieved value from the micromap":
//   4-state 0 / 2-state 0 / FULLY_TRANSPARENT: Ignored;  1 / 1 / FULLY_OPAQUE: Opaque;
//   2 / FULLY_UNKNOWN_TRANSPARENT: Non-opaque;  3 / FULLY_UNKNOWN_OPAQUE: Non-opaque,
// "Unless if the VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_BIT_KHR flag is included in the instance flags
// of the candidate intersection or ForceOpacityMicromap2StateEXT is included in the ray flags on the ray, in which
// case the opacity micromap information is interpreted in 2 state override mode": 2 is Ignored and 3 Opaque.
constexpr MicromapOpacity opacityOfState(uint32_t state, bool force2State) {
    if (state == 0) return MicromapOpacity::Ignored;
    if (state == 1) return MicromapOpacity::Opaque;
    if (force2State) return state == 2 ? MicromapOpacity::Ignored : MicromapOpacity::Opaque;
    return MicromapOpacity::NonOpaque;
}

// The micromap's verdict on primitive `primitiveIndex` of geometry `geometryIndex` of bottom level `blas` (whose
// record has format::kTriangleMicromap) met at barycentrics (u, v). "The opacity information in the micromap object
// is accessed using the candidate intersection u and v coordinates."
inline MicromapOpacity micromapOpacity(const std::byte* blas, uint32_t geometryIndex, uint32_t primitiveIndex, float u,
                                       float v, bool force2State) {
    const format::OpacityGeometry* g = format::opacityGeometry(blas, geometryIndex);
    const format::OpacityPrimitive& p = format::opacityPrimitives(g)[primitiveIndex];
    const std::byte* data = blas + g->dataOffset + p.dataOffset;
    const uint32_t index = p.subdivisionLevel == 0 ? 0 : microTriangleIndex(u, v, p.subdivisionLevel);
    return opacityOfState(format::opacityState(data, p.format, index), force2State);
}

}  // namespace vkas
