#include "engine/assemble/micromap_build.hpp"

#include <cstring>
#include <limits>

namespace vkas {

namespace {

constexpr uint64_t kSaturated = std::numeric_limits<uint64_t>::max();

uint64_t addSaturating(uint64_t a, uint64_t b) { return a > kSaturated - b ? kSaturated : a + b; }
uint64_t mulSaturating(uint64_t a, uint64_t b) { return b != 0 && a > kSaturated / b ? kSaturated : a * b; }

bool buildable(const format::MicromapTriangle& t) {
    return format::isOpacityFormat(t.format) && t.subdivisionLevel <= format::maxOpacitySubdivisionLevel(t.format);
}

}  // namespace

const VkMicromapUsageEXT& micromapUsage(const VkMicromapBuildInfoEXT& info, uint32_t i) {
    return info.pUsageCounts ? info.pUsageCounts[i] : *info.ppUsageCounts[i];
}

uint64_t micromapTriangleCount(const VkMicromapBuildInfoEXT& info) {
    uint64_t n = 0;
    for (uint32_t i = 0; i < info.usageCountsCount; ++i) n += micromapUsage(info, i).count;  // < 2^64: u32 * u32
    return n;
}

uint64_t micromapSizeForUsage(const VkMicromapBuildInfoEXT& info) {
    uint64_t size = sizeof(format::MicromapHeader);
    for (uint32_t i = 0; i < info.usageCountsCount; ++i) {
        const VkMicromapUsageEXT& u = micromapUsage(info, i);
        // A format or level vkas does not build has no size (validation reports it; with validation off it must
        // not shift by an arbitrary level).
        if (!format::isOpacityFormat(u.format) || u.subdivisionLevel > format::maxOpacitySubdivisionLevel(u.format))
            return kSaturated;
        const uint64_t perTriangle =
            sizeof(format::MicromapTriangle) + format::opacityTriangleDataBytes(u.subdivisionLevel, u.format);
        size = addSaturating(size, mulSaturating(u.count, perTriangle));
    }
    return size;
}

format::MicromapTriangle readMicromapTriangle(const VkMicromapBuildInfoEXT& info, uint64_t i) {
    // Spec: "The data at triangleArray is laid out as a 4 byte unsigned integer for the dataOffset followed by a 2
    // byte unsigned integer for the subdivision level then a 2 byte unsigned integer for the format."
    format::MicromapTriangle t;
    std::memcpy(&t, static_cast<const std::byte*>(info.triangleArray.hostAddress) + i * info.triangleArrayStride,
                sizeof t);
    return t;
}

VkResult buildMicromap(const VkMicromapBuildInfoEXT& info, std::byte* dst, uint64_t dstSize) {
    const uint64_t count = micromapTriangleCount(info);
    // The layout first: every triangle must be buildable and the whole block must fit, before a byte is written.
    const uint64_t triangleOffset = sizeof(format::MicromapHeader);
    const uint64_t dataOffset = addSaturating(triangleOffset, mulSaturating(count, sizeof(format::MicromapTriangle)));
    if (dataOffset > dstSize || count > std::numeric_limits<uint32_t>::max()) return VK_ERROR_UNKNOWN;
    uint64_t dataSize = 0;
    for (uint64_t i = 0; i < count; ++i) {
        const format::MicromapTriangle t = readMicromapTriangle(info, i);
        if (!buildable(t)) return VK_ERROR_UNKNOWN;
        dataSize += format::opacityTriangleDataBytes(t.subdivisionLevel, t.format);  // <= 2^32 * 8 MiB
        if (dataSize > dstSize - dataOffset) return VK_ERROR_UNKNOWN;
    }
    // Triangle i's states follow triangle i-1's and MicromapTriangle::dataOffset is a u32: states beyond 4 GiB (more
    // than 512 level-12 4-state triangles) are more than a vkas micromap holds.
    if (dataSize > uint64_t(std::numeric_limits<uint32_t>::max()) + 1) return VK_ERROR_OUT_OF_DEVICE_MEMORY;

    format::MicromapHeader h{};
    h.magic = format::kMicromapMagic;
    h.version = format::kMicromapVersion;
    h.type = uint32_t(info.type);
    h.buildFlags = info.flags;
    h.usedSize = dataOffset + dataSize;
    h.triangleCount = uint32_t(count);
    h.triangleOffset = triangleOffset;
    h.dataOffset = dataOffset;
    h.dataSize = dataSize;
    std::memcpy(dst, &h, sizeof h);
    const auto* source = static_cast<const std::byte*>(info.data.hostAddress);
    uint64_t at = 0;
    for (uint64_t i = 0; i < count; ++i) {
        format::MicromapTriangle t = readMicromapTriangle(info, i);
        const uint64_t bytes = format::opacityTriangleDataBytes(t.subdivisionLevel, t.format);
        // Spec (VkMicromapTriangleEXT): "dataOffset is the offset in bytes of the start of the data for this
        // triangle", relative to data; the block keeps the states at its own offset, contiguous.
        std::memcpy(dst + dataOffset + at, source + t.dataOffset, bytes);
        t.dataOffset = uint32_t(at);
        std::memcpy(dst + triangleOffset + i * sizeof t, &t, sizeof t);
        at += bytes;
    }
    return VK_SUCCESS;
}

}  // namespace vkas
