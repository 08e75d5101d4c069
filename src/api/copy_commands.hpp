// The work of the copy, serialization and property commands, with plain parameters and no validation, so that a
// command can run it at once or (later) from a deferred operation. Each function checks what it must to stay inside
// the memory it was given (with validation on or off) and returns VK_ERROR_UNKNOWN when it cannot proceed, with
// nothing written; deserialization checks its input completely (engine/format_check.hpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/objects.hpp"

namespace vkas {

// The block of `as` when it holds a structure vkas wrote (built, copied or deserialized) that fits in its range,
// else nullptr.
const std::byte* constructedBlock(const AccelerationStructure& as);

// vkCopyAccelerationStructureKHR: CLONE and COMPACT both copy [0, usedSize) (the compacted size).
VkResult copyAccelerationStructure(const AccelerationStructure& src, AccelerationStructure& dst);

// vkCopyAccelerationStructureToMemoryKHR (SERIALIZE): writes the serialized form at `dst`.
VkResult serializeAccelerationStructure(const AccelerationStructure& src, void* dst);

// vkCopyMemoryToAccelerationStructureKHR (DESERIALIZE): checks the blob at `src` and loads it into `dst`, mapping
// each handle-array entry (a VkAccelerationStructureKHR of `device`, or the device address of one) to its handle.
// VK_ERROR_INCOMPATIBLE_VERSION_KHR for UUIDs vkas does not load, VK_ERROR_UNKNOWN for malformed data or a `dst`
// too small.
VkResult deserializeAccelerationStructure(const Device& device, const void* src, AccelerationStructure& dst);

// The handle-array entry `value` as the reference a loaded top level stores: itself when it is a live structure of
// `device`, the structure at that device address, or 0 when it names none.
uint64_t mapSerializedReference(const Device& device, uint64_t value);

// vkWriteAccelerationStructuresPropertiesKHR: one u64 per structure at pData + i * stride, only where it fits in
// dataSize. A structure vkas has not constructed gives 0.
void writeAccelerationStructureProperties(const AccelerationStructure* const* structures, uint32_t count,
                                          VkQueryType queryType, size_t dataSize, void* pData, size_t stride);

}  // namespace vkas
