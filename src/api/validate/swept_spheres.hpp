// [NV-LSS] Valid-usage rules of sphere and linear-swept-sphere geometries (VK_NV_ray_tracing_linear_swept_spheres).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/validate/validator.hpp"

namespace vkas {

// Rules on the data structure itself (shared by the build and the size query): its presence in pNext, sType,
// formats, strides, index type and the two mode enums. `where` names the info, g the geometry.
void checkSweptSpheresGeometry(Validator& v, const VkAccelerationStructureGeometryKHR& geometry, const char* where,
                               uint32_t g);
// Rules of a host build that need the range and the data: the host pointers (11822-11829), SUCCESSIVE indexing
// without indices (10427) and non-negative radii (10426 / 10436), read only once the rest passed.
void checkSweptSpheresRange(Validator& v, const VkAccelerationStructureGeometryKHR& geometry,
                            const VkAccelerationStructureBuildRangeInfoKHR& range, const char* where, uint32_t g);

}  // namespace vkas
