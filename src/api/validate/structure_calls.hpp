// The valid-usage rules of each command of api/structure_commands.cpp (vkGetAccelerationStructureBuildSizesKHR,
// vkCreate/DestroyAccelerationStructureKHR, vkGetAccelerationStructureDeviceAddressKHR), one function a command.
// Each reports what it finds and returns whether the command may go on; the structures' own rules are in
// geometry_info.hpp and structure_create_info.hpp.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkGetAccelerationStructureBuildSizesKHR: device, buildType, pBuildInfo, pMaxPrimitiveCounts and pSizeInfo.
// False: return without writing.
bool checkGetAccelerationStructureBuildSizes(Validator& v, const Device* dev,
                                             VkAccelerationStructureBuildTypeKHR buildType,
                                             const VkAccelerationStructureBuildGeometryInfoKHR* pBuildInfo,
                                             const uint32_t* pMaxPrimitiveCounts,
                                             const VkAccelerationStructureBuildSizesInfoKHR* pSizeInfo);

// vkCreateAccelerationStructureKHR: device, pCreateInfo and pAccelerationStructure. False: return
// VK_ERROR_VALIDATION_FAILED_EXT.
bool checkCreateAccelerationStructure(Validator& v, const Device* dev,
                                      const VkAccelerationStructureCreateInfoKHR* pCreateInfo,
                                      const VkAccelerationStructureKHR* pAccelerationStructure);

// vkDestroyAccelerationStructureKHR: device, accelerationStructure and the allocator. False: return without
// destroying (also for a NULL accelerationStructure).
bool checkDestroyAccelerationStructure(Validator& v, const Device* dev,
                                       VkAccelerationStructureKHR accelerationStructure,
                                       const VkAllocationCallbacks* pAllocator);

// vkGetAccelerationStructureDeviceAddressKHR: device and pInfo. False: return 0.
bool checkGetAccelerationStructureDeviceAddress(Validator& v, const Device* dev,
                                                const VkAccelerationStructureDeviceAddressInfoKHR* pInfo);

}  // namespace vkas
