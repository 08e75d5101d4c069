#include "engine/input/vertex_format.hpp"

#include <algorithm>
#include <cstring>

#include "engine/util/math.hpp"

namespace vkas {

const VkFormat kSupportedVertexFormats[] = {
    VK_FORMAT_R32G32_SFLOAT,       VK_FORMAT_R32G32B32_SFLOAT,    VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R16G16_SFLOAT,       VK_FORMAT_R16G16B16_SFLOAT,    VK_FORMAT_R16G16B16A16_SFLOAT,
    VK_FORMAT_R16G16_SNORM,        VK_FORMAT_R16G16B16_SNORM,     VK_FORMAT_R16G16B16A16_SNORM,
    VK_FORMAT_R8G8_SNORM,          VK_FORMAT_R8G8B8_SNORM,        VK_FORMAT_R8G8B8A8_SNORM,
    VK_FORMAT_R64G64_SFLOAT,       VK_FORMAT_R64G64B64_SFLOAT,    VK_FORMAT_R64G64B64A64_SFLOAT,
    VK_FORMAT_A2B10G10R10_UNORM_PACK32,
};
const uint32_t kSupportedVertexFormatCount = sizeof(kSupportedVertexFormats) / sizeof(kSupportedVertexFormats[0]);

const VertexFormatInfo* vertexFormatInfo(VkFormat format) {
    static const VertexFormatInfo f32x2{8, 4, false}, f32x3{12, 4, false}, f32x4{16, 4, false};
    static const VertexFormatInfo f16x2{4, 2, false}, f16x3{6, 2, false}, f16x4{8, 2, false};
    static const VertexFormatInfo s8x2{2, 1, false}, s8x3{3, 1, false}, s8x4{4, 1, false};
    static const VertexFormatInfo f64x2{16, 8, false}, f64x3{24, 8, false}, f64x4{32, 8, false};
    static const VertexFormatInfo packed{4, 4, true};
    switch (format) {
        case VK_FORMAT_R32G32_SFLOAT: return &f32x2;
        case VK_FORMAT_R32G32B32_SFLOAT: return &f32x3;
        case VK_FORMAT_R32G32B32A32_SFLOAT: return &f32x4;
        case VK_FORMAT_R16G16_SFLOAT:
        case VK_FORMAT_R16G16_SNORM: return &f16x2;
        case VK_FORMAT_R16G16B16_SFLOAT:
        case VK_FORMAT_R16G16B16_SNORM: return &f16x3;
        case VK_FORMAT_R16G16B16A16_SFLOAT:
        case VK_FORMAT_R16G16B16A16_SNORM: return &f16x4;
        case VK_FORMAT_R8G8_SNORM: return &s8x2;
        case VK_FORMAT_R8G8B8_SNORM: return &s8x3;
        case VK_FORMAT_R8G8B8A8_SNORM: return &s8x4;
        case VK_FORMAT_R64G64_SFLOAT: return &f64x2;
        case VK_FORMAT_R64G64B64_SFLOAT: return &f64x3;
        case VK_FORMAT_R64G64B64A64_SFLOAT: return &f64x4;
        case VK_FORMAT_A2B10G10R10_UNORM_PACK32: return &packed;
        default: return nullptr;
    }
}

float halfToFloat(uint16_t h) {
    uint32_t sign = uint32_t(h >> 15) << 31;
    uint32_t exponent = (h >> 10) & 0x1F;
    uint32_t mantissa = h & 0x3FF;
    uint32_t bits;
    if (exponent == 0x1F) {
        bits = sign | 0x7F80'0000u | (mantissa << 13);  // inf or NaN (payload kept)
    } else if (exponent != 0) {
        bits = sign | ((exponent + 112) << 23) | (mantissa << 13);
    } else if (mantissa == 0) {
        bits = sign;
    } else {  // subnormal half: normalise
        int e = -1;
        do {
            ++e;
            mantissa <<= 1;
        } while ((mantissa & 0x400) == 0);
        bits = sign | uint32_t(112 - e) << 23 | ((mantissa & 0x3FF) << 13);
    }
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

namespace {

template <int N>
void decodeFloat32(const std::byte* p, double out[3]) {
    for (int i = 0; i < N; ++i) out[i] = loadUnaligned<float>(p + 4 * i);
}
template <int N>
void decodeFloat16(const std::byte* p, double out[3]) {
    for (int i = 0; i < N; ++i) out[i] = halfToFloat(loadUnaligned<uint16_t>(p + 2 * i));
}
template <int N>
void decodeFloat64(const std::byte* p, double out[3]) {
    for (int i = 0; i < N; ++i) out[i] = loadUnaligned<double>(p + 8 * i);
}
// SNORM: max(c / (2^(b-1) - 1), -1), evaluated in single precision as the spec's conversion does.
template <int N>
void decodeSnorm16(const std::byte* p, double out[3]) {
    for (int i = 0; i < N; ++i) out[i] = std::max(float(loadUnaligned<int16_t>(p + 2 * i)) / 32767.0f, -1.0f);
}
template <int N>
void decodeSnorm8(const std::byte* p, double out[3]) {
    for (int i = 0; i < N; ++i) out[i] = std::max(float(loadUnaligned<int8_t>(p + i)) / 127.0f, -1.0f);
}

}  // namespace

void decodeVertex(VkFormat format, const std::byte* p, double out[3]) {
    out[2] = 0.0;
    switch (format) {
        case VK_FORMAT_R32G32_SFLOAT: return decodeFloat32<2>(p, out);
        case VK_FORMAT_R32G32B32_SFLOAT:
        case VK_FORMAT_R32G32B32A32_SFLOAT: return decodeFloat32<3>(p, out);
        case VK_FORMAT_R16G16_SFLOAT: return decodeFloat16<2>(p, out);
        case VK_FORMAT_R16G16B16_SFLOAT:
        case VK_FORMAT_R16G16B16A16_SFLOAT: return decodeFloat16<3>(p, out);
        case VK_FORMAT_R16G16_SNORM: return decodeSnorm16<2>(p, out);
        case VK_FORMAT_R16G16B16_SNORM:
        case VK_FORMAT_R16G16B16A16_SNORM: return decodeSnorm16<3>(p, out);
        case VK_FORMAT_R8G8_SNORM: return decodeSnorm8<2>(p, out);
        case VK_FORMAT_R8G8B8_SNORM:
        case VK_FORMAT_R8G8B8A8_SNORM: return decodeSnorm8<3>(p, out);
        case VK_FORMAT_R64G64_SFLOAT: return decodeFloat64<2>(p, out);
        case VK_FORMAT_R64G64B64_SFLOAT:
        case VK_FORMAT_R64G64B64A64_SFLOAT: return decodeFloat64<3>(p, out);
        case VK_FORMAT_A2B10G10R10_UNORM_PACK32: {
            uint32_t w = loadUnaligned<uint32_t>(p);
            out[0] = float(w & 0x3FF) / 1023.0f;
            out[1] = float((w >> 10) & 0x3FF) / 1023.0f;
            out[2] = float((w >> 20) & 0x3FF) / 1023.0f;
            return;
        }
        default: out[0] = out[1] = out[2] = 0.0; return;
    }
}

}  // namespace vkas
