// Names of Vulkan enum values for messages and reports.
#pragma once

#include <string>

#include <vkas/vkas.h>

namespace vkas_tool {

// "VK_ERROR_OUT_OF_HOST_MEMORY (-1)": the name and the value.
std::string resultName(VkResult result);
// "VK_FORMAT_R32G32B32_SFLOAT", or "VkFormat(123)" for a value this tool does not name.
std::string formatName(VkFormat format);

}  // namespace vkas_tool
