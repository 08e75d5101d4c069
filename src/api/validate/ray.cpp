#include "api/validate/ray.hpp"

#include "engine/format/layout.hpp"
#include "vkas/vkas.h"

namespace vkas {

bool validateRay(Validator& v, const AccelerationStructure* tlas, uint32_t rayFlags, const float origin[3],
                 float tMin, const float direction[3], float tMax, const char* where) {
    const RayValueRules rules = rayValueRules(origin, tMin, direction, tMax);
    const RayFlagRules flags = rayFlagRules(rayFlags);
    bool ok = true;
    ok &= v.check(rules.originFinite, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348",
                  "%sthe ray origin (%g, %g, %g) is not finite.", where, origin[0], origin[1], origin[2]);
    ok &= v.check(rules.directionFinite, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348",
                  "%sthe ray direction (%g, %g, %g) is not finite.", where, direction[0], direction[1], direction[2]);
    ok &= v.check(rules.notNaN, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06351",
                  "%sRayTmin %g or RayTmax %g is NaN.", where, tMin, tMax);
    ok &= v.check(rules.nonNegative, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06349",
                  "%sRayTmin %g and RayTmax %g must be non-negative.", where, tMin, tMax);
    ok &= v.check(rules.ordered, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06350",
                  "%sRayTmin %g is greater than RayTmax %g.", where, tMin, tMax);
    ok &= v.check(flags.opaqueGroup, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06891",
                  "%sRayFlags 0x%x has more than one of Opaque, NoOpaque, CullOpaque and CullNoOpaque.", where,
                  rayFlags);
    ok &= v.check(flags.triangleGroup, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06890",
                  "%sRayFlags 0x%x has more than one of SkipTriangles, CullBackFacing and CullFrontFacing.", where,
                  rayFlags);
    // ForceOpacityMicromap2StateEXT (0x400) needs the RayTracingOpacityMicromapKHR capability (VUID 11542), which
    // vkas's host ray queries have since VK_EXT_opacity_micromap (docs/VALIDATION.md): the flag is accepted.
    ok &= v.check(flags.notBothSkips, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06889",
                  "%sRayFlags 0x%x has both SkipTriangles and SkipAABBs.", where, rayFlags);
    if (tlas)
        ok &= v.check(builtTopLevel(*tlas), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352",
                      "%sthe acceleration structure is not a built top-level structure.", where);
    return ok;
}

bool checkTopLevelHandle(Validator& v, VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas) {
    return v.check(topLevel == VK_NULL_HANDLE || tlas != nullptr, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352",
                   "topLevel (0x%llx) is not a live VkAccelerationStructureKHR.",
                   static_cast<unsigned long long>(reinterpret_cast<uintptr_t>(topLevel)));
}

}  // namespace vkas
