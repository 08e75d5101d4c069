// Copies, compaction and serialization of acceleration structures on plain memory (docs/FORMAT.md, "Serialized
// form"). The format holds relative offsets only, so a clone or a compacted copy is a byte copy of [0, usedSize).
// The serialized form is the spec's header (driverUUID, compatibility UUID, serialized size, deserialized size,
// handle count N, N bottom-level device addresses) followed by the opaque part: in serialized layout 2 an XXH3-64
// integrity hash and the block itself (layout 1, still loaded, had no hash).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"

namespace vkas::serial {

constexpr size_t kUuidSize = 16;  // VK_UUID_SIZE
// The serialized header: offsets of its fields.
constexpr size_t kDriverUuidOffset = 0;
constexpr size_t kCompatibilityUuidOffset = 16;
constexpr size_t kSerializedSizeOffset = 32;
constexpr size_t kDeserializedSizeOffset = 40;
constexpr size_t kHandleCountOffset = 48;
constexpr size_t kHandlesOffset = 56;  // N u64 device addresses follow, then the opaque part
constexpr size_t kHeaderSize = 56;
constexpr size_t kIntegrityHashSize = 8;  // layout 2: the u64 hash right after the handle array
// From this many bytes on, the hash runs on a thread of its own beside the copy (serialization) or beside the
// structural checks (deserialization), when a second processor is there (a thread costs tens of microseconds;
// hashing 1 MiB about as much).
constexpr uint64_t kHashAlongsideBytes = 1 << 20;

// The layouts of the serialized form. The driverUUID names the layout (the envelope around the block), the
// compatibility UUID the block's format version; both are fixed ASCII strings (no terminator). A later vkas keeps
// loading every pair it ever wrote.
enum class Layout : uint32_t {
    None = 0,  // not a pair this build loads
    V1 = 1,    // header, handle array (handle values), block
    V2 = 2,    // header, handle array (device addresses), integrity hash, block
};
inline constexpr Layout kWrittenLayout = Layout::V2;
inline constexpr uint8_t kDriverUuidV1[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'D', 'R', 'I',
                                                     'V', 'E', 'R', '-', 'F', 'M', 'T', '1'};
inline constexpr uint8_t kDriverUuidV2[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'S', 'E', 'R',
                                                     'I', 'A', 'L', 'I', 'Z', 'E', 'D', '2'};
// The block's format version, in both layouts: 1 (loaded and converted, format/convert.hpp) or 2 (written).
inline constexpr uint8_t kCompatibilityUuidV1[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'A', 'S', '-',
                                                            'F', 'O', 'R', 'M', 'A', 'T', '-', '1'};
inline constexpr uint8_t kCompatibilityUuidV2[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'A', 'S', '-',
                                                            'F', 'O', 'R', 'M', 'A', 'T', '-', '2'};
// The block format version the compatibility UUID of a serialized header names (0: none this build loads).
uint32_t blockVersionOf(const uint8_t* versionData);

// The layout the first 2 * VK_UUID_SIZE bytes of a serialized header (driverUUID, compatibility UUID) name, or
// Layout::None for a pair this build does not load.
Layout layoutOf(const uint8_t* versionData);
// vkGetDeviceAccelerationStructureCompatibilityKHR: whether this build loads data with that UUID pair.
inline bool compatibleVersion(const uint8_t* versionData) { return layoutOf(versionData) != Layout::None; }
// Bytes between the handle array and the block.
constexpr uint64_t opaquePrefixSize(Layout layout) { return layout == Layout::V2 ? kIntegrityHashSize : 0; }

// Offsets inside an instance record (the base of a motion instance record too).
constexpr size_t kInstanceReferenceOffset = offsetof(format::InstanceRecord, reference);
constexpr size_t kInstanceIdOffset = offsetof(format::InstanceRecord, instanceId);
constexpr size_t kInstanceMotionTypeOffset = offsetof(format::InstanceRecord, motionType);

// Query values of a well-formed block (a structure built or loaded by vkas).
uint64_t compactedSize(const std::byte* block);   // usedSize
uint64_t handleCount(const std::byte* block);     // top level: instances given to the build; bottom level: 0
uint64_t serializedSize(const std::byte* block);  // kHeaderSize + 8 * handleCount + kIntegrityHashSize + usedSize

// Clone / compact: copies [0, usedSize) of `src` to `dst` (which must hold compactedSize(src) bytes).
void copyBlock(const std::byte* src, std::byte* dst);

// Maps a stored instance reference to the handle-array value (its structure's device address) through the
// application's objects, which the API layer knows and the engine does not. 0: none.
using ReferenceMapper = uint64_t (*)(const void* context, uint64_t value);

// How serialization computes the integrity hash; the bytes written are the same either way.
enum class HashSchedule {
    Alongside,  // a large block (1 MiB and up) is hashed on a second processor, when there is one, while it is copied
    Fused,      // each chunk is hashed right after it is copied, while it is in cache (one processor)
};

// Writes serializedSize(block) bytes at `out` (any alignment) in layout 2. Handle slot k holds toAddress(reference)
// of the instance whose instanceId is k (0 for an inactive instance); the block's own instance references are
// written as 0, so the hashed bytes depend only on the build inputs.
void serializeBlock(const std::byte* block, std::byte* out, ReferenceMapper toAddress, const void* context,
                    HashSchedule schedule = HashSchedule::Alongside);

// Where the parts of a serialized blob lie; filled by format::checkSerializedLayout.
struct SerializedView {
    Layout layout = Layout::None;
    uint64_t serializedSize = 0;
    uint64_t deserializedSize = 0;  // == the block's usedSize
    uint64_t handleCount = 0;
    const std::byte* data = nullptr;     // the blob: its first kHeaderSize bytes are hashed (layout 2)
    const std::byte* handles = nullptr;  // handleCount u64 (unaligned)
    uint64_t storedHash = 0;             // layout 2: the integrity hash the blob carries
    uint32_t blockVersion = 0;           // the block's format version, named by the compatibility UUID
    const std::byte* block = nullptr;    // deserializedSize bytes (unaligned)
};

// The integrity hash of the blob `view` describes, computed afresh (compare with view.storedHash).
uint64_t integrityHash(const SerializedView& view);
// Rewrites the integrity hash of a layout-2 blob after its bytes were changed on purpose (tests, fuzzers).
void sealIntegrityHash(const SerializedView& view, std::byte* data);

// Sets each instance reference of the loaded top level at `dst` to referenceOfSlot[instanceId] (handleCount values,
// resolved by the caller from the handle array; 0 makes the instance inactive).
void bindReferences(const SerializedView& view, std::byte* dst, const uint64_t* referenceOfSlot);

}  // namespace vkas::serial
