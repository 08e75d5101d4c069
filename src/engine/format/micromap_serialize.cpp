#include "engine/format/micromap_serialize.hpp"

#include <cstring>

#include "engine/util/byte_io.hpp"
#include "engine/util/integrity_hash.hpp"

namespace vkas::serial {

namespace {
format::MicromapHeader loadMicromapHeader(const std::byte* block) {
    format::MicromapHeader h;
    std::memcpy(&h, block, sizeof h);
    return h;
}
}  // namespace

bool compatibleMicromapVersion(const uint8_t* versionData) {
    return std::memcmp(versionData + kDriverUuidOffset, kDriverUuidV2, kUuidSize) == 0 &&
           std::memcmp(versionData + kCompatibilityUuidOffset, kMicromapCompatibilityUuidV1, kUuidSize) == 0;
}

uint64_t micromapCompactedSize(const std::byte* block) { return loadMicromapHeader(block).usedSize; }

uint64_t micromapSerializedSize(const std::byte* block) { return kMicromapBlockOffset + micromapCompactedSize(block); }

void copyMicromapBlock(const std::byte* src, std::byte* dst) {
    if (src != dst) std::memmove(dst, src, micromapCompactedSize(src));
}

void serializeMicromapBlock(const std::byte* block, std::byte* out) {
    const uint64_t used = micromapCompactedSize(block);
    std::byte head[kHeaderSize];
    std::memcpy(head + kDriverUuidOffset, kDriverUuidV2, kUuidSize);
    std::memcpy(head + kCompatibilityUuidOffset, kMicromapCompatibilityUuidV1, kUuidSize);
    store64(head + kSerializedSizeOffset, kMicromapBlockOffset + used);
    store64(head + kDeserializedSizeOffset, used);
    store64(head + kMicromapReservedOffset, 0);
    std::memcpy(out, head, kHeaderSize);
    std::memcpy(out + kMicromapBlockOffset, block, used);
    // The hash of the bytes as written (the header's first 56 bytes, then the block), as a structure's blob has it.
    IntegrityHash hash;
    hash.add(head, kHeaderSize);
    hash.add(out + kMicromapBlockOffset, used);
    store64(out + kMicromapHashOffset, hash.digest());
}

uint64_t micromapIntegrityHash(const SerializedMicromapView& view) {
    IntegrityHash hash;
    hash.add(view.data, kHeaderSize);
    hash.add(view.block, view.deserializedSize);
    return hash.digest();
}

void sealMicromapIntegrityHash(const SerializedMicromapView& view, std::byte* data) {
    store64(data + kMicromapHashOffset, micromapIntegrityHash(view));
}

}  // namespace vkas::serial
