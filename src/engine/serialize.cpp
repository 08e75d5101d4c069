#include "engine/serialize.hpp"

#include <cstring>

#include "engine/byte_io.hpp"

namespace vkas::serial {

namespace {

format::Header loadHeader(const std::byte* block) {
    format::Header h;
    std::memcpy(&h, block, sizeof h);
    return h;
}

}  // namespace

bool compatibleVersion(const uint8_t* versionData) {
    return std::memcmp(versionData + kDriverUuidOffset, kDriverUuidV1, kUuidSize) == 0 &&
           std::memcmp(versionData + kCompatibilityUuidOffset, kCompatibilityUuidV1, kUuidSize) == 0;
}

uint64_t compactedSize(const std::byte* block) { return loadHeader(block).usedSize; }

uint64_t handleCount(const std::byte* block) {
    const format::Header h = loadHeader(block);
    return h.type == uint32_t(format::StructureType::TopLevel) ? h.primitiveCount : 0;
}

uint64_t serializedSize(const std::byte* block) {
    return kHeaderSize + 8 * handleCount(block) + compactedSize(block);
}

void copyBlock(const std::byte* src, std::byte* dst) {
    if (src != dst) std::memmove(dst, src, compactedSize(src));
}

void serializeBlock(const std::byte* block, std::byte* out) {
    const format::Header h = loadHeader(block);
    const uint64_t n = handleCount(block);
    std::memcpy(out + kDriverUuidOffset, kDriverUuidV1, kUuidSize);
    std::memcpy(out + kCompatibilityUuidOffset, kCompatibilityUuidV1, kUuidSize);
    store64(out + kSerializedSizeOffset, serializedSize(block));
    store64(out + kDeserializedSizeOffset, h.usedSize);
    store64(out + kHandleCountOffset, n);
    std::byte* handles = out + kHandlesOffset;
    std::memset(handles, 0, 8 * n);
    std::byte* payload = handles + 8 * n;
    std::memcpy(payload, block, h.usedSize);
    if (h.type != uint32_t(format::StructureType::TopLevel)) return;
    // Move each instance's reference into the handle slot of its instanceId; the payload keeps 0 there, so the
    // payload bytes depend only on the build inputs, not on handle values.
    const uint64_t stride = recordSize(h.type, h.primitiveType, h.buildFlags);
    for (uint64_t r = 0; r < h.recordCount; ++r) {
        std::byte* rec = payload + h.recordOffset + r * stride;
        const uint32_t slot = load32(rec + kInstanceIdOffset);
        if (slot < n) store64(handles + 8 * uint64_t(slot), load64(rec + kInstanceReferenceOffset));
        store64(rec + kInstanceReferenceOffset, 0);
    }
}

void deserializeBlock(const SerializedView& view, std::byte* dst, ReferenceMapper map, const void* context) {
    std::memcpy(dst, view.block, view.deserializedSize);
    const format::Header h = loadHeader(dst);
    if (h.type != uint32_t(format::StructureType::TopLevel)) return;
    const uint64_t stride = recordSize(h.type, h.primitiveType, h.buildFlags);
    for (uint64_t r = 0; r < h.recordCount; ++r) {
        std::byte* rec = dst + h.recordOffset + r * stride;
        const uint32_t slot = load32(rec + kInstanceIdOffset);  // < handleCount: checked by checkSerialized
        const uint64_t value = slot < view.handleCount ? load64(view.handles + 8 * uint64_t(slot)) : 0;
        store64(rec + kInstanceReferenceOffset, value == 0 ? 0 : map(context, value));
    }
}

}  // namespace vkas::serial
