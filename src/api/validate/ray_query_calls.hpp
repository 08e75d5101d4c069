// The valid-usage rules of the ray-query calls of api/ray_query_api.cpp that have their own (the ray's are in
// ray.hpp): the ray time of vkasRayQueryInitializeMotion, the Hit T of vkasRayQueryGenerateIntersection and the
// data access of vkasRayQueryGetIntersectionTriangleVertexPositions. A ray query is per ray: the initialisation's
// rule is inline and reports only for a ray that breaks one.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/objects.hpp"
#include "api/validate/ray.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkasRayQueryInitializeMotion: the ray (as vkasRayQueryInitialize) and its time, which follows the rule of
// OpTraceRayMotionNV (SPIR-V has no ray-query instruction with a time): VUID-RuntimeSpirv-OpTraceRayMotionNV-06366,
// time in [0.0, 1.0]. Returns whether the query traverses: false for a ray that breaks a rule, and for a time
// outside [0, 1] (NaN included) even without validation (never interpolate outside it).
inline bool checkRayQueryInitializeMotion(Validator& v, VkAccelerationStructureKHR topLevel,
                                          const AccelerationStructure* tlas, uint32_t rayFlags, const float origin[3],
                                          float tMin, const float direction[3], float tMax, float time) {
    bool valid = true;
    if (v.enabled()) {
        if (!queryRayValid(topLevel, tlas, rayFlags, origin, tMin, direction, tMax))
            valid = checkTopLevelHandle(v, topLevel, tlas) &&
                    validateRay(v, tlas, rayFlags, origin, tMin, direction, tMax, "");
        valid &= v.check(time >= 0.0f && time <= 1.0f, "VUID-RuntimeSpirv-OpTraceRayMotionNV-06366",
                         "the ray time %g is not between 0.0 and 1.0.", double(time));
    } else if (!(time >= 0.0f && time <= 1.0f)) {
        valid = false;  // never interpolate outside [0, 1], even without validation
    }
    return valid;
}

// vkasRayQueryGenerateIntersection with a pending AABB candidate: a query on a motion structure takes no generated
// intersection (06354), and tHit must lie in [tMin, tMax] (06353; tMax is the committed hit's t, or RayTmax while
// there is none). False: the instruction has no effect (06354 only; a Hit T outside the range is ignored by the
// engine).
bool checkRayQueryGenerateIntersection(Validator& v, bool motion, float tHit, float tMin, float tMax);

// vkasRayQueryGetIntersectionTriangleVertexPositions: the hit's bottom-level structure `blas` (null: none to check)
// was built with ALLOW_DATA_ACCESS. False: return without writing.
bool checkRayQueryTriangleVertexPositions(Validator& v, const std::byte* blas, VkBool32 committed);

}  // namespace vkas
