// The runtime rules of a ray (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-*): those of vkasRayQueryInitialize and,
// for every ray of a batch, of vkasTraceRays and vkasTraceRaysProcedural.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cmath>
#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "api/objects.hpp"
#include "api/validate/validator.hpp"
#include "engine/format/layout.hpp"
#include "vkas/vkas.h"

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

// rayValueRules(...).all() for one ray of a batch in a few vector compares (a valid ray's whole cost, issue 36's
// 2% budget): origin and direction components finite (|x| < inf, NaN fails), tMin and tMax at least 0 (NaN fails),
// tMin at most tMax. The same verdict as all(): a ray it refuses goes to validateRay, which names the broken rules.
inline bool rayValuesValid(const VkasRay& r) {
#if defined(__SSE2__)
    static_assert(offsetof(VkasRay, tMin) == 12 && offsetof(VkasRay, direction) == 16 && offsetof(VkasRay, tMax) == 28,
                  "VkasRay is two rows of four floats: origin, tMin; direction, tMax");
    const __m128 a = _mm_loadu_ps(r.origin), b = _mm_loadu_ps(r.direction);  // (origin, tMin), (direction, tMax)
    const __m128 abs = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF)), inf = _mm_set1_ps(INFINITY);
    const __m128 zero = _mm_setzero_ps();
    const int finite =
        _mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(_mm_and_ps(a, abs), inf), _mm_cmplt_ps(_mm_and_ps(b, abs), inf)));
    const int nonNegative = _mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(a, zero), _mm_cmpge_ps(b, zero)));
    return (finite & 7) == 7 && (nonNegative & 8) != 0 && r.tMin <= r.tMax;
#else
    return rayValueRules(r.origin, r.tMin, r.direction, r.tMax).all();
#endif
}

// The same verdict for a ray given as its parts (vkasRayQueryInitialize's arguments), in a few scalar operations:
// x * 0 is NaN exactly where x is infinite or NaN (and +-0 otherwise), so one sum tells whether all six components
// are finite; the comparisons with 0 and between tMin and tMax fail for NaN.
inline bool rayValuesValid(const float origin[3], float tMin, const float direction[3], float tMax) {
    const float zeroIfFinite = ((origin[0] * 0.0f + origin[1] * 0.0f) + (origin[2] * 0.0f + direction[0] * 0.0f)) +
                               (direction[1] * 0.0f + direction[2] * 0.0f);
    return zeroIfFinite == 0.0f && tMin >= 0.0f && tMax >= 0.0f && tMin <= tMax;
}

// The ray-flag rules, each written once: at most one of Opaque, NoOpaque, CullOpaque and CullNoOpaque (06891), at
// most one of SkipTriangles, CullBackFacing and CullFrontFacing (06890), not both SkipTriangles and SkipAABBs (06889).
struct RayFlagRules {
    bool opaqueGroup, triangleGroup, notBothSkips;
    bool all() const { return opaqueGroup && triangleGroup && notBothSkips; }
};
inline RayFlagRules rayFlagRules(uint32_t rayFlags) {
    constexpr uint32_t kOpaqueGroup = VKAS_RAY_FLAG_OPAQUE | VKAS_RAY_FLAG_NO_OPAQUE | VKAS_RAY_FLAG_CULL_OPAQUE |
                                      VKAS_RAY_FLAG_CULL_NO_OPAQUE;
    constexpr uint32_t kTriangleGroup = VKAS_RAY_FLAG_SKIP_TRIANGLES | VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES |
                                        VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES;
    constexpr uint32_t kBothSkips = VKAS_RAY_FLAG_SKIP_TRIANGLES | VKAS_RAY_FLAG_SKIP_AABBS;
    auto atMostOneBit = [](uint32_t v) { return (v & (v - 1)) == 0; };
    return {atMostOneBit(rayFlags & kOpaqueGroup), atMostOneBit(rayFlags & kTriangleGroup),
            (rayFlags & kBothSkips) != kBothSkips};
}

// The structure rule (06352): `tlas` is a built top-level structure.
inline bool builtTopLevel(const AccelerationStructure& tlas) {
    const std::byte* block = tlas.block();
    const format::Header* h = block ? format::header(block) : nullptr;
    return h && h->magic == format::kMagic && h->type == uint32_t(format::StructureType::TopLevel);
}

// Whether a query's ray breaks none of the rules validateRay and checkTopLevelHandle report, in a few compares and
// without a message: vkasRayQueryInitialize asks it first and reports only for a ray that breaks one (issue 36).
inline bool queryRayValid(VkAccelerationStructureKHR topLevel, const AccelerationStructure* tlas, uint32_t rayFlags,
                          const float origin[3], float tMin, const float direction[3], float tMax) {
    return (topLevel == VK_NULL_HANDLE || tlas != nullptr) && rayValuesValid(origin, tMin, direction, tMax) &&
           rayFlagRules(rayFlags).all() && (!tlas || builtTopLevel(*tlas));
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
