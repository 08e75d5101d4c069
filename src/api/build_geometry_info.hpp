// Reading a VkAccelerationStructureBuildGeometryInfoKHR: the geometry at an index (through pGeometries or
// ppGeometries) and the engine's structure type for its type. Shared by the build commands and their validation.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "engine/format/layout.hpp"

namespace vkas {

// Geometry i of the info: pGeometries[i], else *ppGeometries[i] (which may be NULL), else nullptr.
inline const VkAccelerationStructureGeometryKHR* geometryAt(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                            uint32_t i) {
    if (info.pGeometries) return &info.pGeometries[i];
    return info.ppGeometries ? info.ppGeometries[i] : nullptr;
}

inline format::StructureType structureType(VkAccelerationStructureTypeKHR t) {
    return t == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ? format::StructureType::TopLevel
                                                             : format::StructureType::BottomLevel;
}

}  // namespace vkas
