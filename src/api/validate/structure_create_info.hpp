// Rules on the VkAccelerationStructureCreateInfoKHR of vkCreateAccelerationStructureKHR: sType, type, pNext, flags,
// the capture-replay address vkas does not support, [NV-motion] the motion info, and the buffer range.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

void checkAccelerationStructureCreateInfo(Validator& v, const Device& dev,
                                          const VkAccelerationStructureCreateInfoKHR& ci);

}  // namespace vkas
