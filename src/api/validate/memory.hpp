// Rules on the structures of the buffer and memory commands: VkBufferCreateInfo (vkCreateBuffer), and
// VkMemoryAllocateInfo with the VkMemoryAllocateFlagsInfo of its pNext chain (vkAllocateMemory).
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/validate/validator.hpp"

namespace vkas {

// vkas enables no sparse, protected-memory or capture-replay feature and has one queue family; usage and flag bits
// of extensions it does not enable are not valid values.
void checkBufferCreateInfo(Validator& v, const VkBufferCreateInfo& ci);

// sType, memoryTypeIndex (vkas has one memory type), allocationSize and the pNext chain.
void checkMemoryAllocateInfo(Validator& v, const VkMemoryAllocateInfo& ai);

// The flags, the device mask (vkas is a device group of one) and capture replay, which vkas does not enable.
void checkMemoryAllocateFlagsInfo(Validator& v, const VkMemoryAllocateFlagsInfo& f);

}  // namespace vkas
