// The valid-usage rules of each command of api/micromap_commands.cpp (vkCreate/DestroyMicromapEXT,
// vkGetMicromapBuildSizesEXT, vkBuildMicromapsEXT), one function a command. Each reports what it finds and returns
// whether the command may go on; the structures' own rules are in micromap_create_info.hpp and
// micromap_build_infos.hpp.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkCreateMicromapEXT: device, pCreateInfo and pMicromap. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkCreateMicromap(Validator& v, const Device* dev, const VkMicromapCreateInfoEXT* pCreateInfo,
                         const VkMicromapEXT* pMicromap);

// vkDestroyMicromapEXT: device, micromap and the allocator. False: return without destroying (also for a NULL
// micromap).
bool checkDestroyMicromap(Validator& v, const Device* dev, VkMicromapEXT micromap,
                          const VkAllocationCallbacks* pAllocator);

// vkGetMicromapBuildSizesEXT: device, buildType, pBuildInfo and pSizeInfo. False: return without writing.
bool checkGetMicromapBuildSizes(Validator& v, const Device* dev, VkAccelerationStructureBuildTypeKHR buildType,
                                const VkMicromapBuildInfoEXT* pBuildInfo, const VkMicromapBuildSizesInfoEXT* pSizeInfo);

// vkBuildMicromapsEXT: device, then checkBuildMicromaps (micromap_build_infos.hpp). False: return
// VK_ERROR_VALIDATION_FAILED_EXT.
bool checkBuildMicromapsCall(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                             uint32_t infoCount, const VkMicromapBuildInfoEXT* pInfos);

}  // namespace vkas
