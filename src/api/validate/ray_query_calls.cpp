#include "api/validate/ray_query_calls.hpp"

#include "engine/format/layout.hpp"

namespace vkas {

bool checkRayQueryGenerateIntersection(Validator& v, bool motion, float tHit, float tMin, float tMax) {
    if (!v.enabled()) return true;
    // A motion structure takes no generated intersections: the instruction has no effect.
    if (!v.check(!motion, "VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06354",
                 "the ray query traverses a structure built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV; "
                 "the intersection is not generated."))
        return false;
    v.check(tHit >= tMin && tHit <= tMax, "VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06353",
            "Hit T %g is outside [RayTmin %g, committed T %g]; the intersection is not generated.", double(tHit),
            double(tMin), double(tMax));
    return true;
}

bool checkRayQueryTriangleVertexPositions(Validator& v, const std::byte* blas, VkBool32 committed) {
    if (v.enabled() && blas &&
        !v.check(format::header(blas)->buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR,
                 "VUID-RuntimeSpirv-flags-08761",
                 "the %s intersection's bottom-level structure was not built with "
                 "VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR.",
                 committed ? "committed" : "candidate"))
        return false;
    return true;
}

}  // namespace vkas
