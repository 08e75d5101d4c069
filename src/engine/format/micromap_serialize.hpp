// Clone, compaction and serialization of micromaps on plain memory (docs/FORMAT.md, "Serialized micromaps"). The
// block holds relative offsets only, so a clone or a compacted copy is a byte copy of [0, usedSize). The serialized
// form follows the structures' serialized layout 2 with no handle array: the spec's header (driverUUID,
// compatibility UUID), the serialized size, the deserialized size, a zero where a structure keeps its handle count,
// the XXH3-64 integrity hash and the block.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/micromap_layout.hpp"
#include "engine/format/serialize.hpp"

namespace vkas::serial {

// The micromap block's format version, as the compatibility UUID names it; the driverUUID is vkas's (kDriverUuidV2,
// the structures' layout 2), so a micromap blob and a structure blob never pass for each other.
inline constexpr uint8_t kMicromapCompatibilityUuidV1[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'M', 'I', 'C',
                                                                    'R', 'O', 'M', 'A', 'P', '-', 'V', '1'};
constexpr size_t kMicromapReservedOffset = kHandleCountOffset;  // always 0 (a structure's handle count)
constexpr size_t kMicromapHashOffset = kHandlesOffset;          // the integrity hash
constexpr size_t kMicromapBlockOffset = kMicromapHashOffset + kIntegrityHashSize;  // 64: the block

// vkGetDeviceMicromapCompatibilityEXT: whether this build loads micromap data with that UUID pair (2 * VK_UUID_SIZE
// bytes).
bool compatibleMicromapVersion(const uint8_t* versionData);

// Query values of a well-formed micromap block (built or loaded by vkas).
uint64_t micromapCompactedSize(const std::byte* block);   // usedSize
uint64_t micromapSerializedSize(const std::byte* block);  // kMicromapBlockOffset + usedSize

// Clone / compact: copies [0, usedSize) of `src` to `dst` (which must hold micromapCompactedSize(src) bytes).
void copyMicromapBlock(const std::byte* src, std::byte* dst);

// Writes micromapSerializedSize(block) bytes at `out` (any alignment).
void serializeMicromapBlock(const std::byte* block, std::byte* out);

// Where the parts of a serialized micromap lie; filled by format::checkSerializedMicromap.
struct SerializedMicromapView {
    uint64_t serializedSize = 0;
    uint64_t deserializedSize = 0;   // == the block's usedSize
    uint64_t storedHash = 0;
    const std::byte* data = nullptr;   // the blob: its first kHeaderSize bytes are hashed
    const std::byte* block = nullptr;  // deserializedSize bytes (unaligned)
};

// The integrity hash of the blob `view` describes, computed afresh (compare with view.storedHash).
uint64_t micromapIntegrityHash(const SerializedMicromapView& view);
// Rewrites the integrity hash of a blob after its bytes were changed on purpose (tests, fuzzers).
void sealMicromapIntegrityHash(const SerializedMicromapView& view, std::byte* data);

}  // namespace vkas::serial
