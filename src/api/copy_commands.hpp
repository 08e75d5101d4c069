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
#include "api/structure_bytes.hpp"
#include "engine/format/serialize.hpp"

namespace vkas {

// vkCopyAccelerationStructureKHR: CLONE and COMPACT both copy [0, usedSize) (the compacted size).
VkResult copyAccelerationStructure(const AccelerationStructure& src, AccelerationStructure& dst);

// vkCopyAccelerationStructureToMemoryKHR (SERIALIZE): writes the serialized form at `dst`, each bottom level as
// its device address (0 for an instance whose structure no longer exists or has no memory).
VkResult serializeAccelerationStructure(const AccelerationStructure& src, void* dst);

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
