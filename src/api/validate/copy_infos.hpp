// Rules on the info structures of vkCopyAccelerationStructureKHR (CLONE, COMPACT),
// vkCopyAccelerationStructureToMemoryKHR (SERIALIZE) and vkCopyMemoryToAccelerationStructureKHR (DESERIALIZE): sType,
// pNext, mode, the structures and host addresses, and what the source holds. `pInfo` is not NULL (copy_calls.hpp checks
// that, and the device and deferredOperation parameters, first).
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

void checkCopyAccelerationStructureInfo(Validator& v, const Device& dev,
                                        const VkCopyAccelerationStructureInfoKHR* pInfo);

void checkCopyAccelerationStructureToMemoryInfo(Validator& v, const Device& dev,
                                                const VkCopyAccelerationStructureToMemoryInfoKHR* pInfo);

// Also checks the serialized data at pInfo->src completely, and that each handle-array entry names a bottom level of
// `dev`. Returns true when the data is another implementation's (03414 reported): the command then returns
// VK_ERROR_INCOMPATIBLE_VERSION_KHR, the result the specification gives, instead of VK_ERROR_VALIDATION_FAILED_EXT.
bool checkCopyMemoryToAccelerationStructureInfo(Validator& v, const Device& dev,
                                                const VkCopyMemoryToAccelerationStructureInfoKHR* pInfo);

}  // namespace vkas
