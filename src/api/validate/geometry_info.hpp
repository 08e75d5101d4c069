// Rules on a VkAccelerationStructureBuildGeometryInfoKHR and its geometries that need no range info and no handle:
// the ones vkGetAccelerationStructureBuildSizesKHR and vkBuildAccelerationStructuresKHR share.
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/validate/validator.hpp"

namespace vkas {

// sType, pNext, flags, type, the geometry arrays (03788, 03789-03793) and each geometry's own structure (sType,
// pNext, geometryType, flags; the triangles, AABB, instance, sphere and LSS data structures). `where` names the info
// in messages, e.g. "pInfos[2]".
void checkGeometryInfo(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info, const char* where);

// A bottom level's primitives summed over its geometries (the ranges' primitiveCount in a build, pMaxPrimitiveCounts
// in the size query) against maxPrimitiveCount (03794 AABBs, 03795 triangles and the other types): the limit is also
// the format's (docs/FORMAT.md, "Limits"), so every count up to it fits the structure's fields. False when exceeded.
bool checkPrimitiveTotal(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t total,
                         const char* where);

}  // namespace vkas
