// vkasRayQuery*: one function per SPIR-V OpRayQuery*KHR instruction, over the engine's RayQueryState that
// lives inside the caller's VkasRayQuery, next to the device whose messenger reports the runtime rules.
#include <cmath>
#include <cstring>

#include "api/device.hpp"
#include "api/objects.hpp"
#include "api/validation.hpp"
#include "engine/traversal.hpp"
#include "vkas/vkas.h"

namespace {

using vkas::QueryHit;
using vkas::RayQueryState;

// What a VkasRayQuery holds.
struct QueryObject {
    RayQueryState engine;
    const vkas::Device* device;  // of the top-level structure given to Initialize; null for a null one
};
static_assert(sizeof(QueryObject) <= VKAS_RAY_QUERY_SIZE, "VKAS_RAY_QUERY_SIZE is too small");
static_assert(alignof(QueryObject) <= 16);

QueryObject& object(VkasRayQuery* q) { return *reinterpret_cast<QueryObject*>(q->opaque); }
RayQueryState& state(VkasRayQuery* q) { return object(q).engine; }
const RayQueryState& state(const VkasRayQuery* q) {
    return reinterpret_cast<const QueryObject*>(q->opaque)->engine;
}
const QueryHit& hit(const VkasRayQuery* q, VkBool32 committed) {
    return committed ? state(q).committed : state(q).candidate;
}

constexpr uint32_t kOpaqueGroup = VKAS_RAY_FLAG_OPAQUE | VKAS_RAY_FLAG_NO_OPAQUE | VKAS_RAY_FLAG_CULL_OPAQUE |
                                  VKAS_RAY_FLAG_CULL_NO_OPAQUE;
constexpr uint32_t kTriangleGroup = VKAS_RAY_FLAG_SKIP_TRIANGLES | VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES |
                                    VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES;

bool atMostOneBit(uint32_t v) { return (v & (v - 1)) == 0; }

}  // namespace

namespace vkas {

// The ray-parameter rules of OpRayQueryInitializeKHR (and of the batch call). Returns false when violated.
bool validateRay(Validator& v, const AccelerationStructure* tlas, uint32_t rayFlags, const float origin[3],
                 float tMin, const float direction[3], float tMax, const char* where) {
    bool ok = true;
    auto finite3 = [](const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); };
    ok &= v.check(finite3(origin), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348",
                  "%sthe ray origin (%g, %g, %g) is not finite.", where, origin[0], origin[1], origin[2]);
    ok &= v.check(finite3(direction), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348",
                  "%sthe ray direction (%g, %g, %g) is not finite.", where, direction[0], direction[1], direction[2]);
    ok &= v.check(!std::isnan(tMin) && !std::isnan(tMax), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06351",
                  "%sRayTmin %g or RayTmax %g is NaN.", where, tMin, tMax);
    ok &= v.check(tMin >= 0.0f && tMax >= 0.0f, "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06349",
                  "%sRayTmin %g and RayTmax %g must be non-negative.", where, tMin, tMax);
    ok &= v.check(!(tMin > tMax), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06350",
                  "%sRayTmin %g is greater than RayTmax %g.", where, tMin, tMax);
    ok &= v.check(atMostOneBit(rayFlags & kOpaqueGroup), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06891",
                  "%sRayFlags 0x%x has more than one of Opaque, NoOpaque, CullOpaque and CullNoOpaque.", where,
                  rayFlags);
    ok &= v.check(atMostOneBit(rayFlags & kTriangleGroup), "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06890",
                  "%sRayFlags 0x%x has more than one of SkipTriangles, CullBackFacing and CullFrontFacing.", where,
                  rayFlags);
    ok &= v.check(!((rayFlags & VKAS_RAY_FLAG_SKIP_TRIANGLES) && (rayFlags & VKAS_RAY_FLAG_SKIP_AABBS)),
                  "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06889",
                  "%sRayFlags 0x%x has both SkipTriangles and SkipAABBs.", where, rayFlags);
    if (tlas) {
        const std::byte* block = tlas->block();
        const auto* h = block ? format::header(block) : nullptr;
        ok &= v.check(h && h->magic == format::kMagic && h->type == uint32_t(format::StructureType::TopLevel),
                      "VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352",
                      "%sthe acceleration structure is not a built top-level structure.", where);
    }
    return ok;
}

}  // namespace vkas

extern "C" {

VKAS_API void vkasRayQueryInitialize(VkasRayQuery* q, VkAccelerationStructureKHR topLevel, uint32_t rayFlags,
                                     uint32_t cullMask, const float origin[3], float tMin, const float direction[3],
                                     float tMax) {
    auto* tlas = vkas::fromHandle<vkas::AccelerationStructure>(topLevel);
    if (tlas && tlas->magic != vkas::ObjectMagic::AccelerationStructure) tlas = nullptr;
    vkas::Validator v(tlas ? tlas->device : nullptr, "vkasRayQueryInitialize");
    bool valid = true;
    if (v.enabled()) valid = vkas::validateRay(v, tlas, rayFlags, origin, tMin, direction, tMax, "");
    const std::byte* block = (tlas && valid) ? tlas->block() : nullptr;
    // An invalid ray traverses nothing: the query behaves as for a null acceleration structure.
    static const float zero[3] = {0, 0, 0};
    vkas::queryInitialize(state(q), block, vkas::resolveAccelerationStructure, rayFlags, cullMask,
                          valid ? origin : zero, valid ? tMin : 0.0f, valid ? direction : zero, valid ? tMax : 0.0f);
    object(q).device = tlas ? tlas->device : nullptr;
}

VKAS_API VkBool32 vkasRayQueryProceed(VkasRayQuery* q) { return vkas::queryProceed(state(q)) ? VK_TRUE : VK_FALSE; }
VKAS_API void vkasRayQueryTerminate(VkasRayQuery* q) { vkas::queryTerminate(state(q)); }
VKAS_API void vkasRayQueryGenerateIntersection(VkasRayQuery* q, float tHit) {
    const RayQueryState& s = state(q);
    // Without a pending AABB candidate the instruction has no effect, as in the engine.
    if (s.candidatePending && s.candidate.type == vkas::kCandidateAabb) {
        vkas::Validator v(object(q).device, "vkasRayQueryGenerateIntersection");
        // s.tMax is the committed hit's t, or RayTmax while there is none: the bound 06353 names.
        if (v.enabled())
            v.check(tHit >= s.tMin && tHit <= s.tMax, "VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06353",
                    "Hit T %g is outside [RayTmin %g, committed T %g]; the intersection is not generated.",
                    double(tHit), double(s.tMin), double(s.tMax));
    }
    vkas::queryGenerate(state(q), tHit);  // ignores a Hit T outside that range
}
VKAS_API void vkasRayQueryConfirmIntersection(VkasRayQuery* q) { vkas::queryConfirm(state(q)); }

VKAS_API uint32_t vkasRayQueryGetIntersectionType(const VkasRayQuery* q, VkBool32 committed) {
    return hit(q, committed).type;
}
VKAS_API float vkasRayQueryGetRayTMin(const VkasRayQuery* q) { return state(q).tMin; }
VKAS_API uint32_t vkasRayQueryGetRayFlags(const VkasRayQuery* q) { return state(q).flags; }
VKAS_API void vkasRayQueryGetWorldRayOrigin(const VkasRayQuery* q, float out[3]) {
    std::memcpy(out, state(q).worldOrigin, 3 * sizeof(float));
}
VKAS_API void vkasRayQueryGetWorldRayDirection(const VkasRayQuery* q, float out[3]) {
    std::memcpy(out, state(q).worldDirection, 3 * sizeof(float));
}
VKAS_API float vkasRayQueryGetIntersectionT(const VkasRayQuery* q, VkBool32 committed) { return hit(q, committed).t; }
VKAS_API int32_t vkasRayQueryGetIntersectionInstanceCustomIndex(const VkasRayQuery* q, VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    return h.instance ? int32_t(h.instance->customIndexAndMask & 0xFFFFFFu) : -1;
}
VKAS_API int32_t vkasRayQueryGetIntersectionInstanceId(const VkasRayQuery* q, VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    return h.instance ? int32_t(h.instance->instanceId) : -1;
}
VKAS_API uint32_t vkasRayQueryGetIntersectionInstanceShaderBindingTableRecordOffset(const VkasRayQuery* q,
                                                                                    VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    return h.instance ? (h.instance->sbtOffsetAndFlags & 0xFFFFFFu) : 0u;
}
VKAS_API int32_t vkasRayQueryGetIntersectionGeometryIndex(const VkasRayQuery* q, VkBool32 committed) {
    return vkas::hitGeometryIndex(hit(q, committed));
}
VKAS_API int32_t vkasRayQueryGetIntersectionPrimitiveIndex(const VkasRayQuery* q, VkBool32 committed) {
    return vkas::hitPrimitiveIndex(hit(q, committed));
}
VKAS_API void vkasRayQueryGetIntersectionBarycentrics(const VkasRayQuery* q, VkBool32 committed, float out[2]) {
    std::memcpy(out, hit(q, committed).barycentrics, 2 * sizeof(float));
}
VKAS_API VkBool32 vkasRayQueryGetIntersectionFrontFace(const VkasRayQuery* q, VkBool32 committed) {
    return hit(q, committed).frontFace ? VK_TRUE : VK_FALSE;
}
VKAS_API VkBool32 vkasRayQueryGetIntersectionCandidateAABBOpaque(const VkasRayQuery* q) {
    return state(q).candidate.aabbOpaque ? VK_TRUE : VK_FALSE;
}
VKAS_API void vkasRayQueryGetIntersectionObjectRayOrigin(const VkasRayQuery* q, VkBool32 committed, float out[3]) {
    std::memcpy(out, hit(q, committed).objectOrigin, 3 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionObjectRayDirection(const VkasRayQuery* q, VkBool32 committed,
                                                            float out[3]) {
    std::memcpy(out, hit(q, committed).objectDirection, 3 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionObjectToWorld(const VkasRayQuery* q, VkBool32 committed, float out[3][4]) {
    const QueryHit& h = hit(q, committed);
    if (h.instance)
        std::memcpy(out, h.instance->objectToWorld, 12 * sizeof(float));
    else
        std::memset(out, 0, 12 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionWorldToObject(const VkasRayQuery* q, VkBool32 committed, float out[3][4]) {
    const QueryHit& h = hit(q, committed);
    if (h.instance)
        std::memcpy(out, h.instance->worldToObject, 12 * sizeof(float));
    else
        std::memset(out, 0, 12 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionTriangleVertexPositions(const VkasRayQuery* q, VkBool32 committed,
                                                                 float out[3][3]) {
    const QueryHit& h = hit(q, committed);  // AABB candidates and generated hits have no triangle: zeros
    if (h.triangle)
        std::memcpy(out, h.triangle->v, 9 * sizeof(float));
    else
        std::memset(out, 0, 9 * sizeof(float));
}

}  // extern "C"
