// The valid-usage rules of each command of api/memory_commands.cpp (buffers, device memory, device addresses and
// vkDestroyDevice), one function a command. Each reports what it finds and returns whether the command may go on;
// the structures' own rules are in memory.hpp.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkCreateBuffer: device, pCreateInfo and pBuffer. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkCreateBuffer(Validator& v, const Device* dev, const VkBufferCreateInfo* pCreateInfo, VkBuffer* pBuffer);

// vkDestroyBuffer: device, buffer and the allocator. False: return without destroying (also for a NULL buffer).
bool checkDestroyBuffer(Validator& v, const Device* dev, VkBuffer buffer, const VkAllocationCallbacks* pAllocator);

// vkGetBufferMemoryRequirements: device, buffer and pMemoryRequirements. False: return.
bool checkGetBufferMemoryRequirements(Validator& v, const Device* dev, VkBuffer buffer,
                                      const VkMemoryRequirements* pMemoryRequirements);

// vkAllocateMemory: device, pAllocateInfo (with the VkMemoryAllocateFlagsInfo of its chain) and pMemory. False:
// return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkAllocateMemory(Validator& v, const Device* dev, const VkMemoryAllocateInfo* pAllocateInfo,
                         const VkDeviceMemory* pMemory);

// vkFreeMemory: device and memory. False: return without freeing (also for a NULL memory).
bool checkFreeMemory(Validator& v, const Device* dev, VkDeviceMemory memory);

// vkBindBufferMemory: device, buffer, memory and memoryOffset (`alignment`: the buffers' required alignment).
// False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkBindBufferMemory(Validator& v, const Device* dev, VkBuffer buffer, VkDeviceMemory memory,
                           VkDeviceSize memoryOffset, VkDeviceSize alignment);

// vkMapMemory: device, flags, memory, offset, size and ppData. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkMapMemory(Validator& v, const Device* dev, VkDeviceMemory memory, VkDeviceSize offset, VkDeviceSize size,
                    VkMemoryMapFlags flags, void** ppData);

// vkUnmapMemory: device and memory. False: return.
bool checkUnmapMemory(Validator& v, const Device* dev, VkDeviceMemory memory);

// vkGetBufferDeviceAddress: device and pInfo. False: return 0.
bool checkGetBufferDeviceAddress(Validator& v, const Device* dev, const VkBufferDeviceAddressInfo* pInfo);

// vkDestroyDevice (`dev` of a non-NULL device): the device and the allocator. False: return without destroying.
bool checkDestroyDevice(Validator& v, const Device* dev, const VkAllocationCallbacks* pAllocator);

}  // namespace vkas
