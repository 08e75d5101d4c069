// The rules of VkMicromapBuildInfoEXT (vkGetMicromapBuildSizesEXT, vkBuildMicromapsEXT) and of vkBuildMicromapsEXT.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// The structure's own rules and those of its usage counts (what the size query reads). `name` is the info as the
// message shows it ("pInfos[1]"). Returns whether the usage counts are readable and valid (the size can be computed).
bool checkMicromapBuildInfoUsage(Validator& v, const VkMicromapBuildInfoEXT& info, const char* name);

// Every rule of vkBuildMicromapsEXT but device-parameter: the deferred operation, each info (usage counts,
// triangles, destination) and the overlap of the destinations.
void checkBuildMicromaps(Validator& v, const Device& dev, VkDeferredOperationKHR deferredOperation,
                         uint32_t infoCount, const VkMicromapBuildInfoEXT* pInfos);

}  // namespace vkas
