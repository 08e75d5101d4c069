// The rules of vkCopyMicromapEXT (VkCopyMicromapInfoEXT), vkCopyMicromapToMemoryEXT
// (VkCopyMicromapToMemoryInfoEXT), vkCopyMemoryToMicromapEXT (VkCopyMemoryToMicromapInfoEXT) and
// vkWriteMicromapsPropertiesEXT, but device-parameter, the deferred operation and pInfo-parameter, which
// micromap_copy_calls.hpp checks.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

void checkCopyMicromapInfo(Validator& v, const Device& dev, const VkCopyMicromapInfoEXT& info);
void checkCopyMicromapToMemoryInfo(Validator& v, const Device& dev, const VkCopyMicromapToMemoryInfoEXT& info);
// Returns true when the data is incompatible (src-07549): the command then returns VK_ERROR_INCOMPATIBLE_VERSION_KHR.
bool checkCopyMemoryToMicromapInfo(Validator& v, const Device& dev, const VkCopyMemoryToMicromapInfoEXT& info);
void checkWriteMicromapsProperties(Validator& v, const Device& dev, uint32_t micromapCount,
                                   const VkMicromapEXT* pMicromaps, VkQueryType queryType, size_t dataSize,
                                   void* pData, size_t stride);

}  // namespace vkas
