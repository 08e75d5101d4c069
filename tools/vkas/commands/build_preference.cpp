#include "build_preference.hpp"

#include <stdexcept>

namespace vkas_tool {

VkBuildAccelerationStructureFlagsKHR preferenceFlags(const std::string& name) {
    if (name == "default") return 0;
    if (name == "fast-trace") return VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
    if (name == "fast-build") return VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
    throw std::invalid_argument("--preference " + name + ": expected default, fast-trace or fast-build");
}

const std::vector<std::string>& preferenceNames() {
    static const std::vector<std::string> names{"default", "fast-trace", "fast-build"};
    return names;
}

std::string buildFlagNames(VkBuildAccelerationStructureFlagsKHR flags) {
    static const std::pair<VkBuildAccelerationStructureFlagsKHR, const char*> kNames[] = {
        {VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR, "ALLOW_UPDATE"},
        {VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR, "ALLOW_COMPACTION"},
        {VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR, "PREFER_FAST_TRACE"},
        {VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR, "PREFER_FAST_BUILD"},
        {VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR, "LOW_MEMORY"},
        {VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV, "MOTION"},
        {VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR, "ALLOW_DATA_ACCESS"},
    };
    std::string s;
    for (const auto& [bit, name] : kNames) {
        if (!(flags & bit)) continue;
        if (!s.empty()) s += " | ";
        s += name;
        flags &= ~bit;
    }
    if (flags) s += (s.empty() ? "" : " | ") + std::to_string(flags);
    return s.empty() ? "none" : s;
}

}  // namespace vkas_tool
