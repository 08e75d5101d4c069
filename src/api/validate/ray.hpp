// The runtime rules of a ray (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-*): those of vkasRayQueryInitialize and,
// for every ray of a batch, of vkasTraceRays and vkasTraceRaysProcedural.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cmath>
#include <cstdint>

#include "api/objects.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// The value rules of a ray (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-*), each written once: the components of
// RayOrigin and RayDirection finite (06348), RayTmin and RayTmax not NaN (06351), non-negative (06349), and RayTmin
// at most RayTmax (06350). validateRay reports the broken ones; a batch asks all() first, so that a valid ray costs a
// few compares and no message is built for it (issue 36: formatting a prefix for every valid ray was 20% of a batch's
// work).
struct RayValueRules {
    bool originFinite, directionFinite, notNaN, nonNegative, ordered;
    bool all() const { return originFinite && directionFinite && notNaN && nonNegative && ordered; }
};
inline RayValueRules rayValueRules(const float origin[3], float tMin, const float direction[3], float tMax) {
    auto finite3 = [](const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); };
    return {finite3(origin), finite3(direction), !std::isnan(tMin) && !std::isnan(tMax),
            !(tMin < 0.0f) && !(tMax < 0.0f), !(tMin > tMax)};
}

// The ray-parameter rules of OpRayQueryInitializeKHR (and of the batch call): finite origin and direction, RayTmin
// and RayTmax not NaN, non-negative and ordered, the ray-flag groups, and (when `tlas` is not null) a built
// top-level structure. `where` prefixes each message ("" or "pRays[3]: "). Returns false when violated.
bool validateRay(Validator& v, const AccelerationStructure* tlas, uint32_t rayFlags, const float origin[3],
                 float tMin, const float direction[3], float tMax, const char* where);

// Reports a topLevel handle that names no live acceleration structure (VUID-...-06352: the operand must be a
// top-level acceleration structure). Returns false then.
bool checkTopLevelHandle(Validator& v, VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas);

}  // namespace vkas
