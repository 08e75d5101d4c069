// What every reader of a build's inputs needs first, written once for the engine and the API: geometry i of a
// VkAccelerationStructureBuildGeometryInfoKHR (pGeometries or ppGeometries), the structure type it builds, and
// whether the build stores motion records.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "engine/format/layout.hpp"

namespace vkas {

// Geometry i of the info: pGeometries[i], else *ppGeometries[i] (which may be NULL), else nullptr. Validation and
// the size query read infos that may name no geometry.
inline const VkAccelerationStructureGeometryKHR* geometryAt(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                            uint32_t i) {
    if (info.pGeometries) return &info.pGeometries[i];
    return info.ppGeometries ? info.ppGeometries[i] : nullptr;
}

// Geometry i of a validated info (VUID-VkAccelerationStructureBuildGeometryInfoKHR-pGeometries-03788: exactly one
// array, every entry valid).
inline const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                               uint32_t i) {
    return *geometryAt(info, i);
}

// The format's structure type a build of `type` writes: TOP_LEVEL a top level, BOTTOM_LEVEL a bottom level (a
// build's type is never GENERIC: VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03654).
inline format::StructureType structureTypeOf(VkAccelerationStructureTypeKHR type) {
    return type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ? format::StructureType::TopLevel
                                                                : format::StructureType::BottomLevel;
}

// [NV-motion] Whether a build stores motion records: built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV and a
// top level, or a bottom level of triangles (motion AABBs keep their ordinary records: only the application's
// intersection code knows how a box moves).
bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info);

// The VkGeometryTypeKHR of the records a build stores. All geometries of a bottom-level structure have one type (VUID
// 03792): geometry 0 names it; anything but AABBs, spheres and LSS is read as triangles (so is a build without
// geometries). A top level stores instances.
VkGeometryTypeKHR recordPrimitiveType(const VkAccelerationStructureBuildGeometryInfoKHR& info);

}  // namespace vkas
