#include "engine/serialize.hpp"

#include <cstring>

#include "engine/byte_io.hpp"
#include "engine/integrity_hash.hpp"

namespace vkas::serial {

namespace {

format::Header loadHeader(const std::byte* block) {
    format::Header h;
    std::memcpy(&h, block, sizeof h);
    return h;
}

// Zeroing the references chunk by chunk relies on no reference field straddling a chunk boundary: records start
// 64-byte aligned and their strides are multiples of 64, so a field inside one 64-byte line never does.
static_assert(kInstanceReferenceOffset % 64 + 8 <= 64 && IntegrityHash::kChunk % 64 == 0);

}  // namespace

Layout layoutOf(const uint8_t* versionData) {
    if (std::memcmp(versionData + kCompatibilityUuidOffset, kCompatibilityUuidV1, kUuidSize) != 0) return Layout::None;
    if (std::memcmp(versionData + kDriverUuidOffset, kDriverUuidV2, kUuidSize) == 0) return Layout::V2;
    if (std::memcmp(versionData + kDriverUuidOffset, kDriverUuidV1, kUuidSize) == 0) return Layout::V1;
    return Layout::None;
}

uint64_t compactedSize(const std::byte* block) { return loadHeader(block).usedSize; }

uint64_t handleCount(const std::byte* block) {
    const format::Header h = loadHeader(block);
    return h.type == uint32_t(format::StructureType::TopLevel) ? h.primitiveCount : 0;
}

uint64_t serializedSize(const std::byte* block) {
    return kHeaderSize + 8 * handleCount(block) + opaquePrefixSize(kWrittenLayout) + compactedSize(block);
}

void copyBlock(const std::byte* src, std::byte* dst) {
    if (src != dst) std::memmove(dst, src, compactedSize(src));
}

void serializeBlock(const std::byte* block, std::byte* out, ReferenceMapper toAddress, const void* context) {
    const format::Header h = loadHeader(block);
    const uint64_t n = handleCount(block);
    const bool topLevel = h.type == uint32_t(format::StructureType::TopLevel);
    std::memcpy(out + kDriverUuidOffset, kDriverUuidV2, kUuidSize);
    std::memcpy(out + kCompatibilityUuidOffset, kCompatibilityUuidV1, kUuidSize);
    store64(out + kSerializedSizeOffset, serializedSize(block));
    store64(out + kDeserializedSizeOffset, h.usedSize);
    store64(out + kHandleCountOffset, n);
    // Spec (serialized header): "The corresponding handles matching the values returned by
    // vkGetAccelerationStructureDeviceAddressKHR or vkGetAccelerationStructureHandleNV are tightly packed in the
    // buffer following the count." Slot k belongs to the instance whose instanceId is k.
    std::byte* handles = out + kHandlesOffset;
    std::memset(handles, 0, 8 * n);
    const uint64_t stride = recordSize(h.type, h.primitiveType, h.buildFlags);
    if (topLevel)
        for (uint64_t r = 0; r < h.recordCount; ++r) {
            const std::byte* rec = block + h.recordOffset + r * stride;
            const uint32_t slot = load32(rec + kInstanceIdOffset);
            const uint64_t reference = load64(rec + kInstanceReferenceOffset);
            if (slot < n && reference != 0) store64(handles + 8 * uint64_t(slot), toAddress(context, reference));
        }
    // The block, chunk by chunk: copy, clear the instance references in the chunk, hash it while it is in cache.
    IntegrityHash hash;
    hash.add(out, kHeaderSize);
    std::byte* payload = handles + 8 * n + kIntegrityHashSize;
    uint64_t nextReference = h.recordOffset + kInstanceReferenceOffset, recordsLeft = topLevel ? h.recordCount : 0;
    for (uint64_t at = 0; at < h.usedSize; at += IntegrityHash::kChunk) {
        const uint64_t end = h.usedSize - at < IntegrityHash::kChunk ? h.usedSize : at + IntegrityHash::kChunk;
        std::memcpy(payload + at, block + at, end - at);
        for (; recordsLeft != 0 && nextReference < end; --recordsLeft, nextReference += stride)
            store64(payload + nextReference, 0);
        hash.add(payload + at, end - at);
    }
    store64(handles + 8 * n, hash.digest());
}

uint64_t integrityHash(const SerializedView& view) {
    IntegrityHash hash;
    hash.add(view.data, kHeaderSize);
    hash.add(view.block, view.deserializedSize);
    return hash.digest();
}

void sealIntegrityHash(const SerializedView& view, std::byte* data) {
    if (view.layout != Layout::V2) return;
    store64(data + kHandlesOffset + 8 * view.handleCount, integrityHash(view));
}

uint64_t loadBlock(const SerializedView& view, std::byte* dst) {
    if (view.layout != Layout::V2) {
        std::memcpy(dst, view.block, view.deserializedSize);
        return 0;
    }
    IntegrityHash hash;
    hash.add(view.data, kHeaderSize);
    hash.copyAndAdd(dst, view.block, view.deserializedSize);
    return hash.digest();
}

bool bindReferences(const SerializedView& view, std::byte* dst, ReferenceMapper toReference, const void* context) {
    const format::Header h = loadHeader(dst);
    if (h.type != uint32_t(format::StructureType::TopLevel)) return true;
    const uint64_t stride = recordSize(h.type, h.primitiveType, h.buildFlags);
    for (uint64_t r = 0; r < h.recordCount; ++r) {
        std::byte* rec = dst + h.recordOffset + r * stride;
        const uint32_t slot = load32(rec + kInstanceIdOffset);  // < handleCount: checked by format::checkLoadedBlock
        const uint64_t value = slot < view.handleCount ? load64(view.handles + 8 * uint64_t(slot)) : 0;
        const uint64_t reference = value == 0 ? 0 : toReference(context, value);
        if (value != 0 && reference == 0) return false;
        store64(rec + kInstanceReferenceOffset, reference);
    }
    return true;
}

}  // namespace vkas::serial
