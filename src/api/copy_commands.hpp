// The work of the copy, serialization and property commands, with plain parameters and no validation, so that a
// command can run it at once or (later) from a deferred operation. Each function checks what it must to stay inside
// the memory it was given (with validation on or off) and returns VK_ERROR_UNKNOWN when it cannot proceed, with
// nothing written; deserialization checks its input completely (engine/format/check.hpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>
#include <unordered_map>

#include "engine/util/host_memory.hpp"
#include "api/device.hpp"
#include "api/objects.hpp"
#include "engine/format/serialize.hpp"

namespace vkas {

// Two helpers the work functions share with the copy rules (api/validate/copy_infos.cpp).
// Whether the host ranges [a, a + aSize) and [b, b + bSize) overlap (an empty range overlaps nothing).
bool rangesOverlap(uintptr_t a, uint64_t aSize, uintptr_t b, uint64_t bSize);

// The readable extent the application promises for a serialized blob: its header's serialized size (at least the
// header itself, which every blob has).
uint64_t blobExtent(const void* src);

// The block of `as` when it holds a structure vkas wrote (built, copied or deserialized) that fits in its range,
// else nullptr.
const std::byte* constructedBlock(const AccelerationStructure& as);

// vkCopyAccelerationStructureKHR: CLONE and COMPACT both copy [0, usedSize) (the compacted size).
VkResult copyAccelerationStructure(const AccelerationStructure& src, AccelerationStructure& dst);

// vkCopyAccelerationStructureToMemoryKHR (SERIALIZE): writes the serialized form at `dst`, each bottom level as
// its device address (0 for an instance whose structure no longer exists or has no memory).
VkResult serializeAccelerationStructure(const AccelerationStructure& src, void* dst);

// Maps handle-array entries of serialized data to the bottom levels of `device` they name: in layout 2 a device
// address (vkGetAccelerationStructureDeviceAddressKHR) of a live structure created as BOTTOM_LEVEL or GENERIC; in
// layout 1 (older vkas wrote handle values there) such an address or else such a VkAccelerationStructureKHR.
class SerializedReferences {
public:
    SerializedReferences(const Device& device, serial::Layout layout) : device_(device), layout_(layout) {}
    // The instance reference (a VkAccelerationStructureKHR handle) a loaded top level stores for `value`, or 0
    // when it names no such structure. Allocates (the address index, built on first use): may throw bad_alloc.
    uint64_t toReference(uint64_t value);

private:
    const Device& device_;
    serial::Layout layout_;
    bool indexed_ = false;
    HostUnorderedMap<uint64_t, const AccelerationStructure*> byAddress_;
};

// vkCopyMemoryToAccelerationStructureKHR (DESERIALIZE): checks the blob at `src` and loads it into `dst`, mapping
// each handle-array entry through SerializedReferences. VK_ERROR_INCOMPATIBLE_VERSION_KHR for UUIDs vkas does not
// load, VK_ERROR_UNKNOWN for malformed or altered data (integrity hash), a `dst` too small or an entry naming no
// bottom level; on any failure `dst` is left unconstructed.
VkResult deserializeAccelerationStructure(const Device& device, const void* src, AccelerationStructure& dst);

// vkWriteAccelerationStructuresPropertiesKHR: one u64 per structure at pData + i * stride, only where it fits in
// dataSize. A structure vkas has not constructed gives 0.
void writeAccelerationStructureProperties(const AccelerationStructure* const* structures, uint32_t count,
                                          VkQueryType queryType, size_t dataSize, void* pData, size_t stride);

}  // namespace vkas
