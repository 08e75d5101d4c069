// Copies, compaction and serialization of acceleration structures on plain memory (docs/FORMAT.md, "Serialized
// form"). The format holds relative offsets only, so a clone or a compacted copy is a byte copy of [0, usedSize).
// The serialized form is the spec's header (driverUUID, compatibility UUID, serialized size, deserialized size,
// handle count N, N bottom-level references) followed by the block itself.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format.hpp"

namespace vkas::serial {

constexpr size_t kUuidSize = 16;  // VK_UUID_SIZE
// The serialized header: offsets of its fields.
constexpr size_t kDriverUuidOffset = 0;
constexpr size_t kCompatibilityUuidOffset = 16;
constexpr size_t kSerializedSizeOffset = 32;
constexpr size_t kDeserializedSizeOffset = 40;
constexpr size_t kHandleCountOffset = 48;
constexpr size_t kHandlesOffset = 56;  // N u64 references follow, then the block
constexpr size_t kHeaderSize = 56;

// The UUIDs of format version 1: fixed ASCII strings (no terminator). A later vkas keeps accepting them (it may
// write new ones for a new format version, and then accepts both).
inline constexpr uint8_t kDriverUuidV1[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'D', 'R', 'I',
                                                     'V', 'E', 'R', '-', 'F', 'M', 'T', '1'};
inline constexpr uint8_t kCompatibilityUuidV1[kUuidSize] = {'V', 'K', 'A', 'S', '-', 'A', 'S', '-',
                                                            'F', 'O', 'R', 'M', 'A', 'T', '-', '1'};

// Bytes per record of a block with these header fields (format.hpp): instance records for a top level (motion:
// 256), 96 for a motion bottom level of triangles, 48 for every other bottom level.
constexpr uint64_t recordSize(uint32_t type, uint32_t primitiveType, uint32_t buildFlags) {
    const bool motion = (buildFlags & 0x20u) != 0;  // VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV
    if (type == uint32_t(format::StructureType::TopLevel))
        return motion ? sizeof(format::MotionInstanceRecord) : sizeof(format::InstanceRecord);
    if (motion && primitiveType == 0 /* VK_GEOMETRY_TYPE_TRIANGLES_KHR */) return sizeof(format::MotionTriangleRecord);
    return sizeof(format::TriangleRecord);
}
// Offsets inside an instance record (the base of a motion instance record too).
constexpr size_t kInstanceReferenceOffset = offsetof(format::InstanceRecord, reference);
constexpr size_t kInstanceIdOffset = offsetof(format::InstanceRecord, instanceId);
constexpr size_t kInstanceMotionTypeOffset = offsetof(format::InstanceRecord, motionType);

// Whether the first 2 * VK_UUID_SIZE bytes of a serialized header (driverUUID, compatibility UUID) name data this
// build of vkas can load (vkGetDeviceAccelerationStructureCompatibilityKHR).
bool compatibleVersion(const uint8_t* versionData);

// Query values of a well-formed block (a structure built or loaded by vkas).
uint64_t compactedSize(const std::byte* block);     // usedSize
uint64_t handleCount(const std::byte* block);       // top level: instances given to the build; bottom level: 0
uint64_t serializedSize(const std::byte* block);    // kHeaderSize + 8 * handleCount + usedSize

// Clone / compact: copies [0, usedSize) of `src` to `dst` (which must hold compactedSize(src) bytes).
void copyBlock(const std::byte* src, std::byte* dst);

// Writes serializedSize(block) bytes at `out` (any alignment). Handle slot k holds the reference of the instance
// whose instanceId is k (0 for an inactive instance); the block's own instance references are written as 0.
void serializeBlock(const std::byte* block, std::byte* out);

// Where the parts of a serialized blob lie; filled by format::checkSerialized.
struct SerializedView {
    uint64_t serializedSize = 0;
    uint64_t deserializedSize = 0;  // == the block's usedSize
    uint64_t handleCount = 0;
    const std::byte* handles = nullptr;  // handleCount u64 (unaligned)
    const std::byte* block = nullptr;    // deserializedSize bytes (unaligned)
};

// Maps a value of the handle array to the instance reference the loaded structure stores (0: inactive).
using ReferenceMapper = uint64_t (*)(const void* context, uint64_t value);

// Loads a blob that format::checkSerialized accepted into `dst` (aligned like a structure's block, at least
// view.deserializedSize bytes): copies the block and sets each instance's reference to
// map(handles[instanceId]).
void deserializeBlock(const SerializedView& view, std::byte* dst, ReferenceMapper map, const void* context);

}  // namespace vkas::serial
