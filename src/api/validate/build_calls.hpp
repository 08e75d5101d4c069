// The valid-usage rules of vkBuildAccelerationStructuresKHR (api/build_commands.cpp): the device here, then the
// infos and ranges (build_infos.hpp). Reports what it finds and returns whether the command may go on.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkBuildAccelerationStructuresCall(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                          uint32_t infoCount, const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
                                          const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos);

}  // namespace vkas
