// --preference default|fast-trace|fast-build: the build flags it stands for, and their names for reports.
#pragma once

#include <string>
#include <vector>

#include <vkas/vkas.h>

namespace vkas_tool {

// Throws std::invalid_argument for an unknown name.
VkBuildAccelerationStructureFlagsKHR preferenceFlags(const std::string& name);
const std::vector<std::string>& preferenceNames();
// "PREFER_FAST_TRACE | ALLOW_COMPACTION", or "none".
std::string buildFlagNames(VkBuildAccelerationStructureFlagsKHR flags);

}  // namespace vkas_tool
