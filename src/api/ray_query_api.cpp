// vkasRayQuery*: one function per SPIR-V OpRayQuery*KHR instruction, over the engine's RayQueryState that
// lives inside the caller's VkasRayQuery, next to the device whose messenger reports the runtime rules.
#include <cstring>

#include "api/device.hpp"
#include "api/objects.hpp"
#include "api/validate/ray_query_calls.hpp"
#include "engine/format/motion.hpp"
#include "engine/trace/ray_query.hpp"
#include "vkas/vkas.h"

namespace {

using vkas::QueryHit;
using vkas::RayQueryState;

// What a VkasRayQuery holds.
struct QueryObject {
    RayQueryState engine;
    const vkas::Device* device;  // of the top-level structure given to Initialize; null for a null one
    bool motion;                 // that structure was built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV
};

// The live acceleration structure `handle` names (looked up before it is dereferenced), or nullptr.
const vkas::AccelerationStructure* lookUpStructure(VkAccelerationStructureKHR handle) {
    if (!vkas::Device::ownerOf(handle)) return nullptr;
    auto* as = vkas::fromHandle<vkas::AccelerationStructure>(handle);
    return as->magic == vkas::ObjectMagic::AccelerationStructure ? as : nullptr;
}

// The live structure `handle` names, or null. A ray query is initialised once per ray, usually on the same top
// level: the last answer is kept per thread and reused while the registry has not changed (no object created or
// destroyed since), which saves the registry's lock and lookup on every ray.
const vkas::AccelerationStructure* liveStructure(VkAccelerationStructureKHR handle) {
    struct Last {
        VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
        uint64_t generation = 0;
        const vkas::AccelerationStructure* structure = nullptr;
    };
    thread_local Last last;
    const uint64_t generation = vkas::Device::registryGeneration();
    if (handle && handle == last.handle && generation == last.generation) return last.structure;
    const vkas::AccelerationStructure* as = lookUpStructure(handle);
    last = {handle, generation, as};
    return as;
}

static_assert(sizeof(QueryObject) <= VKAS_RAY_QUERY_SIZE, "VKAS_RAY_QUERY_SIZE is too small");
static_assert(alignof(QueryObject) <= 16);

QueryObject& object(VkasRayQuery* q) { return *reinterpret_cast<QueryObject*>(q->opaque); }
RayQueryState& state(VkasRayQuery* q) { return object(q).engine; }
const RayQueryState& state(const VkasRayQuery* q) {
    return reinterpret_cast<const QueryObject*>(q->opaque)->engine;
}
// After queryInitialize: the device of the query's structure, and whether it was built with motion (queryInitialize
// read the header; a query that traverses nothing, a null or empty structure or an invalid ray, never has a candidate
// for GenerateIntersection to reject).
void recordStructure(VkasRayQuery* q, const vkas::AccelerationStructure* tlas) {
    object(q).device = tlas ? tlas->device : nullptr;
    object(q).motion = state(q).topLevelMotion;
}
const QueryHit& hit(const VkasRayQuery* q, VkBool32 committed) {
    return committed ? state(q).committed : state(q).candidate;
}

}  // namespace

extern "C" {

VKAS_API void vkasRayQueryInitialize(VkasRayQuery* q, VkAccelerationStructureKHR topLevel, uint32_t rayFlags,
                                     uint32_t cullMask, const float origin[3], float tMin, const float direction[3],
                                     float tMax) {
    const vkas::AccelerationStructure* tlas = liveStructure(topLevel);
    vkas::Validator v(tlas ? tlas->device : nullptr, "vkasRayQueryInitialize");
    bool valid = true;
    if (v.enabled() && !vkas::queryRayValid(topLevel, tlas, rayFlags, origin, tMin, direction, tMax))
        valid = vkas::checkTopLevelHandle(v, topLevel, tlas) &&
                vkas::validateRay(v, tlas, rayFlags, origin, tMin, direction, tMax, "");
    const std::byte* block = (tlas && valid) ? tlas->block() : nullptr;
    // An invalid ray traverses nothing: the query behaves as for a null acceleration structure.
    static const float zero[3] = {0, 0, 0};
    vkas::queryInitialize(state(q), block, vkas::resolveAccelerationStructure, rayFlags, cullMask,
                          valid ? origin : zero, valid ? tMin : 0.0f, valid ? direction : zero, valid ? tMax : 0.0f);
    recordStructure(q, tlas);
}

// [NV-motion] vkasRayQueryInitialize with a ray time, whose rule is that of OpTraceRayMotionNV
// (api/validate/ray_query_calls.hpp). A query that breaks it (NaN included) is reported and behaves as for a null
// acceleration structure.
VKAS_API void vkasRayQueryInitializeMotion(VkasRayQuery* q, VkAccelerationStructureKHR topLevel, uint32_t rayFlags,
                                           uint32_t cullMask, const float origin[3], float tMin,
                                           const float direction[3], float tMax, float time) {
    const vkas::AccelerationStructure* tlas = liveStructure(topLevel);
    vkas::Validator v(tlas ? tlas->device : nullptr, "vkasRayQueryInitializeMotion");
    const bool valid =
        vkas::checkRayQueryInitializeMotion(v, topLevel, tlas, rayFlags, origin, tMin, direction, tMax, time);
    const std::byte* block = (tlas && valid) ? tlas->block() : nullptr;
    static const float zero[3] = {0, 0, 0};
    vkas::queryInitialize(state(q), block, vkas::resolveAccelerationStructure, rayFlags, cullMask,
                          valid ? origin : zero, valid ? tMin : 0.0f, valid ? direction : zero, valid ? tMax : 0.0f,
                          valid ? time : 0.0f);
    recordStructure(q, tlas);
}

VKAS_API VkBool32 vkasRayQueryProceed(VkasRayQuery* q) { return vkas::queryProceed(state(q)) ? VK_TRUE : VK_FALSE; }
VKAS_API void vkasRayQueryTerminate(VkasRayQuery* q) { vkas::queryTerminate(state(q)); }
VKAS_API void vkasRayQueryGenerateIntersection(VkasRayQuery* q, float tHit) {
    const RayQueryState& s = state(q);
    // Without a pending AABB candidate the instruction has no effect, as in the engine.
    if (s.candidatePending && s.candidate.type == vkas::kCandidateAabb) {
        vkas::Validator v(object(q).device, "vkasRayQueryGenerateIntersection");
        // s.tMax is the committed hit's t, or RayTmax while there is none: the bound 06353 names.
        // v.enabled() here: a call per candidate costs nothing without validation.
        if (v.enabled() && !vkas::checkRayQueryGenerateIntersection(v, object(q).motion, tHit, s.tMin, s.tMax)) return;
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
// [NV-motion] Motion instances report their transforms at the ray time (the ones traversal used).
VKAS_API void vkasRayQueryGetIntersectionObjectToWorld(const VkasRayQuery* q, VkBool32 committed, float out[3][4]) {
    const QueryHit& h = hit(q, committed);
    float unused[3][4];
    if (h.instance)
        vkas::motion::instanceTransformsAt(*h.instance, state(q).time, out, unused);
    else
        std::memset(out, 0, 12 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionWorldToObject(const VkasRayQuery* q, VkBool32 committed, float out[3][4]) {
    const QueryHit& h = hit(q, committed);
    float unused[3][4];
    if (h.instance)
        vkas::motion::instanceTransformsAt(*h.instance, state(q).time, unused, out);
    else
        std::memset(out, 0, 12 * sizeof(float));
}
VKAS_API void vkasRayQueryGetIntersectionTriangleVertexPositions(const VkasRayQuery* q, VkBool32 committed,
                                                                 float out[3][3]) {
    const QueryHit& h = hit(q, committed);  // AABB candidates and generated hits have no triangle: zeros
    if (h.isTriangle && h.instance) {
        // Positions are kept for every build, but the rule asks for ALLOW_DATA_ACCESS on the hit's structure.
        const std::byte* blas = vkas::resolveAccelerationStructure(h.instance->reference);
        const auto* query = reinterpret_cast<const QueryObject*>(q->opaque);
        vkas::Validator v(query->device, "vkasRayQueryGetIntersectionTriangleVertexPositions");
        if (v.enabled() && !vkas::checkRayQueryTriangleVertexPositions(v, blas, committed)) return;
    }
    // The positions the intersection used ([NV-motion] those at the ray time), kept with the hit.
    if (h.isTriangle)
        std::memcpy(out, h.trianglePositions, 9 * sizeof(float));
    else
        std::memset(out, 0, 9 * sizeof(float));
}

VKAS_API uint32_t vkasRayQueryGetIntersectionPrimitiveType(const VkasRayQuery* q, VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    if (committed ? h.type == VKAS_COMMITTED_INTERSECTION_NONE : !state(q).candidatePending)
        return VKAS_INTERSECTION_PRIMITIVE_NONE;
    return h.isTriangle ? VKAS_INTERSECTION_PRIMITIVE_TRIANGLE
           : h.aabb   ? VKAS_INTERSECTION_PRIMITIVE_AABB
           : h.sphere ? VKAS_INTERSECTION_PRIMITIVE_SPHERE
           : h.lss    ? VKAS_INTERSECTION_PRIMITIVE_LSS
                      : VKAS_INTERSECTION_PRIMITIVE_NONE;
}

VKAS_API VkBool32 vkasRayQueryIsSphereHit(const VkasRayQuery* q, VkBool32 committed) {
    return hit(q, committed).sphere ? VK_TRUE : VK_FALSE;
}
VKAS_API VkBool32 vkasRayQueryIsLssHit(const VkasRayQuery* q, VkBool32 committed) {
    return hit(q, committed).lss ? VK_TRUE : VK_FALSE;
}
VKAS_API void vkasRayQueryGetIntersectionSpherePosition(const VkasRayQuery* q, VkBool32 committed, float out[3]) {
    const QueryHit& h = hit(q, committed);
    if (h.sphere)
        std::memcpy(out, h.sphere->center, 3 * sizeof(float));
    else
        std::memset(out, 0, 3 * sizeof(float));
}
VKAS_API float vkasRayQueryGetIntersectionSphereRadius(const VkasRayQuery* q, VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    return h.sphere ? h.sphere->radius : 0.0f;
}
VKAS_API void vkasRayQueryGetIntersectionLssPositions(const VkasRayQuery* q, VkBool32 committed, float out[2][3]) {
    const QueryHit& h = hit(q, committed);
    if (h.lss) {
        std::memcpy(out[0], h.lss->p0, 3 * sizeof(float));
        std::memcpy(out[1], h.lss->p1, 3 * sizeof(float));
    } else {
        std::memset(out, 0, 6 * sizeof(float));
    }
}
VKAS_API void vkasRayQueryGetIntersectionLssRadii(const VkasRayQuery* q, VkBool32 committed, float out[2]) {
    const QueryHit& h = hit(q, committed);
    out[0] = h.lss ? h.lss->r0 : 0.0f;
    out[1] = h.lss ? h.lss->r1 : 0.0f;
}
VKAS_API float vkasRayQueryGetIntersectionLssHitValue(const VkasRayQuery* q, VkBool32 committed) {
    const QueryHit& h = hit(q, committed);
    return h.lss ? h.lssHitValue : 0.0f;
}

}  // extern "C"
