// The runtime rules of a ray (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-*): those of vkasRayQueryInitialize and,
// for every ray of a batch, of vkasTraceRays and vkasTraceRaysProcedural.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/objects.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// The ray-parameter rules of OpRayQueryInitializeKHR (and of the batch call): finite origin and direction, RayTmin
// and RayTmax not NaN, non-negative and ordered, the ray-flag groups, and (when `tlas` is not null) a built
// top-level structure. `where` prefixes each message ("" or "pRays[3]: "). Returns false when violated.
bool validateRay(Validator& v, const AccelerationStructure* tlas, uint32_t rayFlags, const float origin[3],
                 float tMin, const float direction[3], float tMax, const char* where);

// Reports a topLevel handle that names no live acceleration structure (VUID-...-06352: the operand must be a
// top-level acceleration structure). Returns false then.
bool checkTopLevelHandle(Validator& v, VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas);

}  // namespace vkas
