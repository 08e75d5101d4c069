#include "engine/format/micromap_check.hpp"

#include <cstring>

#include <vulkan/vulkan_core.h>

#include "engine/util/byte_io.hpp"

namespace vkas::format {

namespace {

CheckResult corrupt(const char* reason) { return {CheckStatus::Corrupt, reason}; }

constexpr uint32_t kKnownBuildFlags = VK_BUILD_MICROMAP_PREFER_FAST_TRACE_BIT_EXT |
                                      VK_BUILD_MICROMAP_PREFER_FAST_BUILD_BIT_EXT |
                                      VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;

}  // namespace

CheckResult checkMicromapBlock(const std::byte* block, uint64_t size) {
    if (!block || size < sizeof(MicromapHeader)) return corrupt("the block is shorter than a micromap header");
    MicromapHeader h;
    std::memcpy(&h, block, sizeof h);
    if (h.magic != kMicromapMagic) return corrupt("the block is not a micromap (magic)");
    if (h.version != kMicromapVersion) return corrupt("the micromap format version is not one vkas loads");
    if (h.type != 0) return corrupt("the micromap type is not OPACITY_MICROMAP_EXT");
    if (h.buildFlags & ~kKnownBuildFlags) return corrupt("the micromap build flags have unknown bits");
    if (h.reserved0 != 0) return corrupt("a reserved micromap header field is not zero");
    for (uint8_t b : h.reserved)
        if (b != 0) return corrupt("a reserved micromap header field is not zero");
    if (h.usedSize < sizeof h || h.usedSize > size) return corrupt("the micromap's usedSize is out of range");
    // The layout the build writes, exactly: header, triangles, states; no gaps, nothing after.
    if (h.triangleOffset != sizeof h) return corrupt("the micromap triangle offset is not the header size");
    const uint64_t trianglesEnd = h.triangleOffset + uint64_t(h.triangleCount) * sizeof(MicromapTriangle);
    if (trianglesEnd > h.usedSize) return corrupt("the micromap triangles run past usedSize");
    if (h.dataOffset != trianglesEnd) return corrupt("the micromap data does not follow the triangles");
    if (h.dataSize != h.usedSize - h.dataOffset) return corrupt("the micromap data size does not match usedSize");
    uint64_t at = 0;
    for (uint32_t i = 0; i < h.triangleCount; ++i) {
        MicromapTriangle t;
        std::memcpy(&t, block + h.triangleOffset + uint64_t(i) * sizeof t, sizeof t);
        if (!isOpacityFormat(t.format)) return corrupt("a micromap triangle has an unknown format");
        if (t.subdivisionLevel > maxOpacitySubdivisionLevel(t.format))
            return corrupt("a micromap triangle's subdivision level exceeds the format's maximum");
        if (t.dataOffset != at) return corrupt("a micromap triangle's states are not where the build puts them");
        at += opacityTriangleDataBytes(t.subdivisionLevel, t.format);
        if (at > h.dataSize) return corrupt("a micromap triangle's states run past the block");
    }
    if (at != h.dataSize) return corrupt("the micromap has bytes after its last triangle's states");
    return {};
}

CheckResult checkSerializedMicromap(const std::byte* data, uint64_t size, serial::SerializedMicromapView* view) {
    using namespace serial;
    if (!data || size < kMicromapBlockOffset) return corrupt("the blob is shorter than the serialized micromap header");
    if (!compatibleMicromapVersion(reinterpret_cast<const uint8_t*>(data)))
        return {CheckStatus::Incompatible, "the driver or compatibility UUID is not the pair vkas writes for micromaps"};
    SerializedMicromapView v;
    v.data = data;
    v.serializedSize = load64(data + kSerializedSizeOffset);
    v.deserializedSize = load64(data + kDeserializedSizeOffset);
    // The sizes must agree with each other before anything past the header is read: the header's serialized size is
    // the extent the application vouches for.
    if (v.serializedSize < kMicromapBlockOffset || v.serializedSize > size)
        return corrupt("the serialized size is out of range");
    if (v.serializedSize - kMicromapBlockOffset != v.deserializedSize)
        return corrupt("the serialized size does not match the deserialized size");
    if (load64(data + kMicromapReservedOffset) != 0) return corrupt("the reserved header field is not zero");
    v.storedHash = load64(data + kMicromapHashOffset);
    v.block = data + kMicromapBlockOffset;
    if (micromapIntegrityHash(v) != v.storedHash)
        return corrupt("the integrity hash does not match the data (the blob was changed)");
    const CheckResult block = checkMicromapBlock(v.block, v.deserializedSize);
    if (!block.ok()) return block;
    MicromapHeader h;
    std::memcpy(&h, v.block, sizeof h);
    if (h.usedSize != v.deserializedSize) return corrupt("the deserialized size is not the micromap's usedSize");
    if (view) *view = v;
    return {};
}

}  // namespace vkas::format
