// What every reader of a build's inputs needs first: geometry i of a VkAccelerationStructureBuildGeometryInfoKHR
// (pGeometries or ppGeometries), and whether the build stores motion records.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

namespace vkas {

const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                        uint32_t i);

// [NV-motion] Whether a build stores motion records: built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV and a
// top level, or a bottom level of triangles (motion AABBs keep their ordinary records: only the application's
// intersection code knows how a box moves).
bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info);

// The VkGeometryTypeKHR of the records a build stores. All geometries of a bottom-level structure have one type (VUID
// 03792): geometry 0 names it; anything but AABBs, spheres and LSS is read as triangles (so is a build without
// geometries). A top level stores instances.
VkGeometryTypeKHR recordPrimitiveType(const VkAccelerationStructureBuildGeometryInfoKHR& info);

}  // namespace vkas
