// The in-memory format of a vkas micromap (VkMicromapEXT of VK_EXT_opacity_micromap); docs/FORMAT.md, "Micromaps".
//
// A micromap is one contiguous block at the start of [offset, offset + size) of its buffer:
//   MicromapHeader | MicromapTriangle[triangleCount] | data
// Every offset inside is relative to the start of the block, so a byte copy of the first usedSize bytes is a valid
// clone. The build repacks each micromap triangle's states: triangle i's states start at byte
// dataOffset + triangles[i].dataOffset, exactly opacityTriangleDataBytes(level, format) bytes, packed "from LSB to MSB
// in each byte" as the application gave them.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vkas::format {

constexpr uint32_t kMicromapMagic = 0x4D4F'4B56u;  // "VKOM" read as little-endian bytes
constexpr uint32_t kMicromapVersion = 1;

// The subdivision levels vkas accepts for both formats (VkPhysicalDeviceOpacityMicromapPropertiesEXT reports them):
// 12, as NVIDIA's drivers report. A level-12 4-state triangle holds 4^12 states in 4 MiB.
constexpr uint32_t kMaxOpacity2StateSubdivisionLevel = 12;
constexpr uint32_t kMaxOpacity4StateSubdivisionLevel = 12;

// VkOpacityMicromapFormatEXT
constexpr uint32_t kOpacityFormat2State = 1;
constexpr uint32_t kOpacityFormat4State = 2;

struct MicromapHeader {
    uint32_t magic;
    uint32_t version;
    uint32_t type;        // VkMicromapTypeEXT (OPACITY_MICROMAP_EXT = 0)
    uint32_t buildFlags;  // VkBuildMicromapFlagsEXT of the build
    uint64_t usedSize;    // bytes from the start of the block that the micromap occupies (its compacted size)
    uint32_t triangleCount;
    uint32_t reserved0;
    uint64_t triangleOffset;  // MicromapTriangle[triangleCount]
    uint64_t dataOffset;      // the states of every triangle
    uint64_t dataSize;
    uint8_t reserved[64 - 56];
};
static_assert(sizeof(MicromapHeader) == 64);

// One micromap triangle, laid out as VkMicromapTriangleEXT; dataOffset is relative to the header's dataOffset.
struct MicromapTriangle {
    uint32_t dataOffset;
    uint16_t subdivisionLevel;
    uint16_t format;  // VkOpacityMicromapFormatEXT
};
static_assert(sizeof(MicromapTriangle) == 8);

constexpr bool isOpacityFormat(uint32_t format) {
    return format == kOpacityFormat2State || format == kOpacityFormat4State;
}
constexpr uint32_t maxOpacitySubdivisionLevel(uint32_t format) {
    return format == kOpacityFormat2State ? kMaxOpacity2StateSubdivisionLevel : kMaxOpacity4StateSubdivisionLevel;
}
// A triangle of subdivision level L has 4^L micro-triangles.
constexpr uint64_t microTriangleCount(uint32_t level) { return uint64_t(1) << (2 * level); }
// "one bit per element for VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT or two bits per element for
// VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT", rounded up to whole bytes (dataOffset "is a byte aligned value").
constexpr uint64_t opacityTriangleDataBytes(uint32_t level, uint32_t format) {
    const uint64_t bits = microTriangleCount(level) * (format == kOpacityFormat4State ? 2 : 1);
    return (bits + 7) / 8;
}
// The state of micro-triangle `index` in a triangle's data: "packed from LSB to MSB in each byte".
inline uint32_t opacityState(const std::byte* data, uint32_t format, uint64_t index) {
    if (format == kOpacityFormat2State) return (uint32_t(data[index >> 3]) >> (index & 7)) & 1u;
    return (uint32_t(data[index >> 2]) >> (2 * (index & 3))) & 3u;
}

inline const MicromapHeader* micromapHeader(const std::byte* base) {
    return reinterpret_cast<const MicromapHeader*>(base);
}
inline const MicromapTriangle* micromapTriangles(const std::byte* base) {
    return reinterpret_cast<const MicromapTriangle*>(base + micromapHeader(base)->triangleOffset);
}
inline const std::byte* micromapData(const std::byte* base) { return base + micromapHeader(base)->dataOffset; }

}  // namespace vkas::format

namespace vkas {

// Turns a VkMicromapEXT handle (as a 64-bit value) into the block of the constructed micromap it names, or nullptr
// when it names none. Supplied by the API layer, which owns the handles; bottom-level builds use it.
using MicromapResolver = const std::byte* (*)(uint64_t micromap);

}  // namespace vkas
