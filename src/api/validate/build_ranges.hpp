// The rules of a host build that need a geometry's range info and read its data: offsets, host pointers, AABB
// bounds, maxVertex against the indices read, transforms, and each instance (flags, transform, the structure it
// references). The build-info rules (build_infos.cpp) call them for each geometry, after the geometry's own rules
// (geometry_info.hpp). `where` names the info in messages, g the geometry.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <vector>

#include "engine/util/host_memory.hpp"
#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// AABBs: 03659 (primitiveOffset), 03774 (data), and min <= max on each axis (03546-03548), read only through a
// range that passed its rules.
void checkAabbRange(Validator& v, const VkAccelerationStructureGeometryAabbsDataKHR& a,
                    const VkAccelerationStructureBuildRangeInfoKHR& r, const char* where, uint32_t g);

// Triangles: 03771 / 03772 (data), 03656 / 03657 (primitiveOffset), 03658 and 03799 (the transform), 11820 (motion
// vertices), and maxVertex against the vertices actually read (10774 / 10775).
void checkTrianglesRange(Validator& v, const VkAccelerationStructureGeometryTrianglesDataKHR& t,
                         const VkAccelerationStructureBuildRangeInfoKHR& r, const char* where, uint32_t g);

// Instances ([NV-motion] motion instances when `buildFlags` has MOTION): 03660, 03801, 03778, each instance's flags
// and transform, and the structures they reference (03779 / 04930, 03709), which are added to `referenced` for the
// rules between infos. Returns false when primitiveCount exceeds maxInstanceCount (03801): nothing more is read from
// that info.
bool checkInstancesRange(Validator& v, const Device& dev, const VkAccelerationStructureGeometryInstancesDataKHR& inst,
                         const VkAccelerationStructureBuildRangeInfoKHR& r,
                         VkBuildAccelerationStructureFlagsKHR buildFlags, const char* where,
                         HostVector<const AccelerationStructure*>& referenced);

}  // namespace vkas
