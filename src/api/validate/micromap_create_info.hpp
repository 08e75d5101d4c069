// The rules of VkMicromapCreateInfoEXT (vkCreateMicromapEXT).
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

void checkMicromapCreateInfo(Validator& v, const Device& dev, const VkMicromapCreateInfoEXT& ci);

}  // namespace vkas
