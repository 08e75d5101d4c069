// The valid-usage rules of each command of api/query_commands.cpp (vkWriteAccelerationStructuresPropertiesKHR,
// vkGetDeviceAccelerationStructureCompatibilityKHR), one function a command. Each reports what it finds and returns
// whether the command may go on; the properties query's own rules are in properties_query.hpp.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkWriteAccelerationStructuresPropertiesKHR: device, then checkWriteAccelerationStructuresProperties. False: return
// VK_ERROR_VALIDATION_FAILED_EXT.
bool checkWriteAccelerationStructuresPropertiesCall(Validator& v, const Device* dev,
                                                    uint32_t accelerationStructureCount,
                                                    const VkAccelerationStructureKHR* pAccelerationStructures,
                                                    VkQueryType queryType, size_t dataSize, void* pData, size_t stride);

// vkGetDeviceAccelerationStructureCompatibilityKHR: device, pCompatibility and pVersionInfo. False: return.
bool checkGetDeviceAccelerationStructureCompatibility(Validator& v, const Device* dev,
                                                      const VkAccelerationStructureVersionInfoKHR* pVersionInfo,
                                                      const VkAccelerationStructureCompatibilityKHR* pCompatibility);

}  // namespace vkas
