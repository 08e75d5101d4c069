#include "api/validate/batch_trace_calls.hpp"

#include <cstdio>

#include "api/validate/ray.hpp"

namespace vkas {

bool checkTraceDevice(Validator& v, const Device* dev, const TraceVuids& vuids) {
    if (!dev) {
        v.fail(vuids.device, "device is not a valid VkDevice.");
        return false;
    }
    return true;
}

bool checkTraceBatch(Validator& v, VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas,
                     VkasTraceMode mode, uint32_t rayFlags, uint32_t rayCount, const VkasRay* pRays,
                     const VkasHit* pHits, const TraceVuids& vuids) {
    if (!v.enabled()) return true;
    v.check(topLevel == VK_NULL_HANDLE || tlas != nullptr, vuids.topLevel,
            "topLevel is not a live VkAccelerationStructureKHR.");
    v.check(mode == VKAS_TRACE_MODE_CLOSEST_HIT || mode == VKAS_TRACE_MODE_ANY_HIT, vuids.mode,
            "mode %d is not a VkasTraceMode.", int(mode));
    v.check(rayCount == 0 || (pRays && pHits), vuids.rays, "pRays or pHits is NULL with rayCount %u.", rayCount);
    if (!v.failed()) {
        static const float origin[3] = {0, 0, 0}, direction[3] = {0, 0, 1};
        validateRay(v, tlas, rayFlags, origin, 0.0f, direction, 1.0f, "");
        for (uint32_t i = 0; i < rayCount; ++i) {
            const VkasRay& r = pRays[i];
            if (rayValuesValid(r)) continue;  // no message
            if (v.failureCount() >= 8) break;
            char where[48];
            std::snprintf(where, sizeof where, "pRays[%u]: ", i);
            validateRay(v, nullptr, 0 /* the flags are checked once, above */, r.origin, r.tMin, r.direction, r.tMax,
                        where);
        }
    }
    return !v.failed();
}

}  // namespace vkas
