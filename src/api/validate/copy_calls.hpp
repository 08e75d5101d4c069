// The valid-usage rules of each command of api/copy_commands.cpp (vkCopyAccelerationStructureKHR,
// vkCopyAccelerationStructureToMemoryKHR, vkCopyMemoryToAccelerationStructureKHR), one function a command:
// device-parameter, the deferred operation and pInfo-parameter here, the infos' own rules in copy_infos.hpp. Each
// reports what it finds and returns VK_SUCCESS when the command may go on, else what the command returns.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

VkResult checkCopyAccelerationStructure(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                        const VkCopyAccelerationStructureInfoKHR* pInfo);
VkResult checkCopyAccelerationStructureToMemory(Validator& v, const Device* dev,
                                                VkDeferredOperationKHR deferredOperation,
                                                const VkCopyAccelerationStructureToMemoryInfoKHR* pInfo);
// VK_ERROR_INCOMPATIBLE_VERSION_KHR when the data is incompatible.
VkResult checkCopyMemoryToAccelerationStructure(Validator& v, const Device* dev,
                                                VkDeferredOperationKHR deferredOperation,
                                                const VkCopyMemoryToAccelerationStructureInfoKHR* pInfo);

}  // namespace vkas
