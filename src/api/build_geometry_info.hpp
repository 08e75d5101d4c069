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

// Whether every geometry of the info is there to read (validation reports a NULL one; what reads all of them waits).
inline bool allGeometriesPresent(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (info.geometryCount != 0 && !info.pGeometries && !info.ppGeometries) return false;
    for (uint32_t g = 0; g < info.geometryCount; ++g)
        if (!geometryAt(info, g)) return false;
    return true;
}

inline format::StructureType structureType(VkAccelerationStructureTypeKHR t) {
    return t == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ? format::StructureType::TopLevel
                                                             : format::StructureType::BottomLevel;
}

}  // namespace vkas
