// What validation asks of a VkAccelerationStructureBuildGeometryInfoKHR beyond the engine's reading of it
// (engine/input/build_inputs.hpp: geometry i, the structure type): whether every geometry is there to read.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "engine/input/build_inputs.hpp"  // geometryAt, buildGeometry, structureTypeOf

namespace vkas {

// Whether every geometry of the info is there to read (validation reports a NULL one; what reads all of them waits).
inline bool allGeometriesPresent(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (info.geometryCount != 0 && !info.pGeometries && !info.ppGeometries) return false;
    for (uint32_t g = 0; g < info.geometryCount; ++g)
        if (!geometryAt(info, g)) return false;
    return true;
}

}  // namespace vkas
