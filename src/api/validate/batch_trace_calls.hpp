// The valid-usage rules of vkas's own batch calls, vkasTraceRays and vkasTraceRaysProcedural (api/batch_trace.cpp):
// their parameters, named like Vulkan's implicit VUIDs, then every ray's values (ray.hpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/device.hpp"
#include "api/objects.hpp"
#include "api/validate/validator.hpp"
#include "vkas/vkas.h"

namespace vkas {

// The parameter VUIDs of one batch call.
struct TraceVuids {
    const char* command;
    const char* device;    // device is a live VkDevice
    const char* topLevel;  // topLevel is VK_NULL_HANDLE or a live VkAccelerationStructureKHR
    const char* mode;      // mode is a VkasTraceMode
    const char* rays;      // pRays and pHits are not NULL when rayCount is not 0
};
inline constexpr TraceVuids kTraceRaysVuids{"vkasTraceRays", "VUID-vkasTraceRays-device-parameter",
                                            "VUID-vkasTraceRays-topLevel-parameter", "VUID-vkasTraceRays-mode-parameter",
                                            "VUID-vkasTraceRays-pRays-parameter"};
inline constexpr TraceVuids kTraceRaysProceduralVuids{
    "vkasTraceRaysProcedural", "VUID-vkasTraceRaysProcedural-device-parameter",
    "VUID-vkasTraceRaysProcedural-topLevel-parameter", "VUID-vkasTraceRaysProcedural-mode-parameter",
    "VUID-vkasTraceRaysProcedural-pRays-parameter"};

// A batch call's device. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkTraceDevice(Validator& v, const Device* dev, const TraceVuids& vuids);

// The rest of a batch call (device checked; `tlas`: the live structure topLevel names, or null): topLevel, mode,
// pRays and pHits, then the ray flags and every ray's values (reports stop after 8 failures). False: return
// VK_ERROR_VALIDATION_FAILED_EXT.
bool checkTraceBatch(Validator& v, VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas,
                     VkasTraceMode mode, uint32_t rayFlags, uint32_t rayCount, const VkasRay* pRays,
                     const VkasHit* pHits, const TraceVuids& vuids);

}  // namespace vkas
