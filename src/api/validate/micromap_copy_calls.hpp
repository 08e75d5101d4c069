// The valid-usage rules of each command of api/micromap_copy_commands.cpp (vkCopyMicromapEXT,
// vkCopyMicromapToMemoryEXT, vkCopyMemoryToMicromapEXT, vkWriteMicromapsPropertiesEXT,
// vkGetDeviceMicromapCompatibilityEXT), one function a command: device-parameter, the deferred operation and
// pInfo-parameter here, the infos' own rules in micromap_copy_infos.hpp. Each reports what it finds; those of a
// command returning VkResult return VK_SUCCESS when the command may go on, else what it returns.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

VkResult checkCopyMicromap(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                           const VkCopyMicromapInfoEXT* pInfo);
VkResult checkCopyMicromapToMemory(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                   const VkCopyMicromapToMemoryInfoEXT* pInfo);
// VK_ERROR_INCOMPATIBLE_VERSION_KHR when the data is incompatible (src-07549).
VkResult checkCopyMemoryToMicromap(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                   const VkCopyMemoryToMicromapInfoEXT* pInfo);
VkResult checkWriteMicromapsPropertiesCall(Validator& v, const Device* dev, uint32_t micromapCount,
                                           const VkMicromapEXT* pMicromaps, VkQueryType queryType, size_t dataSize,
                                           void* pData, size_t stride);
// vkGetDeviceMicromapCompatibilityEXT: device, pCompatibility and pVersionInfo. False: return.
bool checkGetDeviceMicromapCompatibility(Validator& v, const Device* dev, const VkMicromapVersionInfoEXT* pVersionInfo,
                                         const VkAccelerationStructureCompatibilityKHR* pCompatibility);

}  // namespace vkas
