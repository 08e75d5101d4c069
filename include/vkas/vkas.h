/*
 * vkas.h - Vulkan acceleration-structure host commands and host ray queries.
 *
 * vkas implements VK_KHR_acceleration_structure's host commands on the CPU. A program creates a vkas device,
 * obtains the Vulkan commands it needs with vkasGetDeviceProcAddr (they have exactly the Vulkan PFN_vk...
 * signatures), builds acceleration structures with vkBuildAccelerationStructuresKHR and traces rays through them
 * with the vkasRayQuery* functions, one per SPIR-V OpRayQuery*KHR instruction, with the same semantics.
 *
 * All memory is host memory: memory type 0 is HOST_VISIBLE | HOST_COHERENT | DEVICE_LOCAL, vkMapMemory returns
 * the allocation's address and every VkDeviceOrHostAddress* is a host pointer. See docs/API.md.
 */
#ifndef VKAS_H_
#define VKAS_H_

#include <stddef.h>
#include <stdint.h>
#include <vulkan/vulkan_core.h>

#include "vkas_compat.h"

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define VKAS_API
#else
#define VKAS_API __attribute__((visibility("default")))
#endif

#define VKAS_VERSION_MAJOR 0
#define VKAS_VERSION_MINOR 1
#define VKAS_VERSION_PATCH 0

/* ---------------------------------------------------------------------------------------------------------- */
/* Bootstrap                                                                                                   */
/* ---------------------------------------------------------------------------------------------------------- */

typedef struct VkasDeviceCreateInfo {
    VkBool32 disableValidation;                        /* VK_FALSE (default): every command checks its valid usage */
    PFN_vkDebugUtilsMessengerCallbackEXT pfnMessenger; /* NULL: messages go to stderr */
    void* pMessengerUserData;
    uint32_t workerThreadCount; /* threads of vkasTraceRays and vkasTraceRaysProcedural (the calling one included); 0 = all cores */
} VkasDeviceCreateInfo;

VKAS_API VkResult vkasCreateDevice(const VkasDeviceCreateInfo* pCreateInfo /* may be NULL */, VkDevice* pDevice);
/* vkasCreateDevice with the application's allocator: the device's own memory comes from pAllocator with
   VK_SYSTEM_ALLOCATION_SCOPE_DEVICE, and every command of the device that has no pAllocator of its own allocates its
   temporaries from it with VK_SYSTEM_ALLOCATION_SCOPE_COMMAND (docs/API.md, "Host memory"). pAllocator may be NULL
   (the same as vkasCreateDevice); its pfnReallocation is never called. vkDestroyDevice must then be given compatible
   callbacks (vkasDestroyDevice needs none). */
VKAS_API VkResult vkasCreateDeviceWithAllocator(const VkasDeviceCreateInfo* pCreateInfo /* may be NULL */,
                                                const VkAllocationCallbacks* pAllocator, VkDevice* pDevice);
VKAS_API void vkasDestroyDevice(VkDevice device);
/* The implementation of the Vulkan command named pName, or NULL when vkas does not implement it. */
VKAS_API PFN_vkVoidFunction vkasGetDeviceProcAddr(VkDevice device, const char* pName);

/* What a Vulkan physical device would report. vkas has no VkPhysicalDevice; these take the device instead. */
VKAS_API void vkasGetAccelerationStructureFeatures(VkDevice device,
                                                   VkPhysicalDeviceAccelerationStructureFeaturesKHR* pFeatures);
VKAS_API void vkasGetAccelerationStructureProperties(VkDevice device,
                                                     VkPhysicalDeviceAccelerationStructurePropertiesKHR* pProperties);
/* bufferFeatures holds VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR for usable vertex formats. */
VKAS_API void vkasGetFormatProperties(VkDevice device, VkFormat format, VkFormatProperties* pFormatProperties);

/* ---------------------------------------------------------------------------------------------------------- */
/* Host ray queries (SPV_KHR_ray_query)                                                                         */
/* ---------------------------------------------------------------------------------------------------------- */

/* Ray flags: the SPIR-V RayFlags values. */
#define VKAS_RAY_FLAG_NONE 0x0u
#define VKAS_RAY_FLAG_OPAQUE 0x1u
#define VKAS_RAY_FLAG_NO_OPAQUE 0x2u
#define VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT 0x4u
#define VKAS_RAY_FLAG_SKIP_CLOSEST_HIT_SHADER 0x8u
#define VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES 0x10u
#define VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES 0x20u
#define VKAS_RAY_FLAG_CULL_OPAQUE 0x40u
#define VKAS_RAY_FLAG_CULL_NO_OPAQUE 0x80u
#define VKAS_RAY_FLAG_SKIP_TRIANGLES 0x100u
#define VKAS_RAY_FLAG_SKIP_AABBS 0x200u
#define VKAS_RAY_FLAG_FORCE_OPACITY_MICROMAP_2_STATE 0x400u /* ForceOpacityMicromap2StateEXT (SPV_EXT_opacity_micromap) */

/* OpRayQueryGetIntersectionTypeKHR results (SPIR-V RayQueryCommittedIntersectionType / CandidateIntersectionType). */
#define VKAS_COMMITTED_INTERSECTION_NONE 0u
#define VKAS_COMMITTED_INTERSECTION_TRIANGLE 1u
#define VKAS_COMMITTED_INTERSECTION_GENERATED 2u
#define VKAS_CANDIDATE_INTERSECTION_TRIANGLE 0u
#define VKAS_CANDIDATE_INTERSECTION_AABB 1u

/* Size in bytes of a ray query's state: it holds the traversal stacks, so a query never allocates. */
#define VKAS_RAY_QUERY_SIZE 12288

typedef struct VkasRayQuery { /* 16-byte aligned */
#if defined(__cplusplus)
    alignas(16)
#else
    _Alignas(16)
#endif
        unsigned char opaque[VKAS_RAY_QUERY_SIZE];
} VkasRayQuery;

VKAS_API void vkasRayQueryInitialize(VkasRayQuery* q, VkAccelerationStructureKHR topLevel, uint32_t rayFlags,
                                     uint32_t cullMask, const float origin[3], float tMin, const float direction[3],
                                     float tMax);
/*
 * [VK_NV_ray_tracing_motion_blur] vkasRayQueryInitialize with a ray time in [0, 1] (VUID-RuntimeSpirv-
 * OpTraceRayMotionNV-06366): motion instances and motion triangles are intersected as they are at that time.
 * vkasRayQueryInitialize traces at time 0.
 */
VKAS_API void vkasRayQueryInitializeMotion(VkasRayQuery* q, VkAccelerationStructureKHR topLevel, uint32_t rayFlags,
                                           uint32_t cullMask, const float origin[3], float tMin,
                                           const float direction[3], float tMax, float time);
VKAS_API VkBool32 vkasRayQueryProceed(VkasRayQuery* q);
VKAS_API void vkasRayQueryTerminate(VkasRayQuery* q);
VKAS_API void vkasRayQueryGenerateIntersection(VkasRayQuery* q, float tHit);
VKAS_API void vkasRayQueryConfirmIntersection(VkasRayQuery* q);
VKAS_API uint32_t vkasRayQueryGetIntersectionType(const VkasRayQuery* q, VkBool32 committed);
VKAS_API float vkasRayQueryGetRayTMin(const VkasRayQuery* q);
VKAS_API uint32_t vkasRayQueryGetRayFlags(const VkasRayQuery* q);
VKAS_API void vkasRayQueryGetWorldRayOrigin(const VkasRayQuery* q, float out[3]);
VKAS_API void vkasRayQueryGetWorldRayDirection(const VkasRayQuery* q, float out[3]);
VKAS_API float vkasRayQueryGetIntersectionT(const VkasRayQuery* q, VkBool32 committed);
VKAS_API int32_t vkasRayQueryGetIntersectionInstanceCustomIndex(const VkasRayQuery* q, VkBool32 committed);
VKAS_API int32_t vkasRayQueryGetIntersectionInstanceId(const VkasRayQuery* q, VkBool32 committed);
VKAS_API uint32_t vkasRayQueryGetIntersectionInstanceShaderBindingTableRecordOffset(const VkasRayQuery* q,
                                                                                    VkBool32 committed);
VKAS_API int32_t vkasRayQueryGetIntersectionGeometryIndex(const VkasRayQuery* q, VkBool32 committed);
VKAS_API int32_t vkasRayQueryGetIntersectionPrimitiveIndex(const VkasRayQuery* q, VkBool32 committed);
VKAS_API void vkasRayQueryGetIntersectionBarycentrics(const VkasRayQuery* q, VkBool32 committed, float out[2]);
VKAS_API VkBool32 vkasRayQueryGetIntersectionFrontFace(const VkasRayQuery* q, VkBool32 committed);
VKAS_API VkBool32 vkasRayQueryGetIntersectionCandidateAABBOpaque(const VkasRayQuery* q);
VKAS_API void vkasRayQueryGetIntersectionObjectRayOrigin(const VkasRayQuery* q, VkBool32 committed, float out[3]);
VKAS_API void vkasRayQueryGetIntersectionObjectRayDirection(const VkasRayQuery* q, VkBool32 committed,
                                                            float out[3]);
VKAS_API void vkasRayQueryGetIntersectionObjectToWorld(const VkasRayQuery* q, VkBool32 committed, float out[3][4]);
VKAS_API void vkasRayQueryGetIntersectionWorldToObject(const VkasRayQuery* q, VkBool32 committed, float out[3][4]);
VKAS_API void vkasRayQueryGetIntersectionTriangleVertexPositions(const VkasRayQuery* q, VkBool32 committed,
                                                                 float out[3][3]);

/*
 * [VK_NV_ray_tracing_linear_swept_spheres] Spheres and linear swept spheres (LSS) are built-in primitives: their
 * candidates and hits report the TRIANGLE intersection types (candidate 0, committed 1), as SPIR-V's
 * SPV_NV_linear_swept_spheres does (it adds no intersection type values); opaque ones are committed during
 * Proceed, non-opaque ones come back as candidates for vkasRayQueryConfirmIntersection. These functions tell
 * them apart and return their data, one per SPIR-V instruction (OpRayQueryIsSphereHitNV, OpRayQueryIsLSSHitNV,
 * OpRayQueryGetIntersectionSpherePositionNV, ...SphereRadiusNV, ...LSSPositionsNV, ...LSSRadiiNV,
 * ...LSSHitValueNV). Positions are object-space (as decoded, rounded to float); radii as given. For any other kind
 * of intersection (or none) the getters return zeros and the Is* functions VK_FALSE. Barycentrics and FrontFace
 * are 0 / VK_FALSE for sphere and LSS intersections.
 */
VKAS_API VkBool32 vkasRayQueryIsSphereHit(const VkasRayQuery* q, VkBool32 committed);
VKAS_API VkBool32 vkasRayQueryIsLssHit(const VkasRayQuery* q, VkBool32 committed);
VKAS_API void vkasRayQueryGetIntersectionSpherePosition(const VkasRayQuery* q, VkBool32 committed, float out[3]);
VKAS_API float vkasRayQueryGetIntersectionSphereRadius(const VkasRayQuery* q, VkBool32 committed);
/* The two endpoints (out[0], out[1]) and their radii, in application order. */
VKAS_API void vkasRayQueryGetIntersectionLssPositions(const VkasRayQuery* q, VkBool32 committed, float out[2][3]);
VKAS_API void vkasRayQueryGetIntersectionLssRadii(const VkasRayQuery* q, VkBool32 committed, float out[2]);
/* The hit value u in [0, 1]: the parameter along the segment of the swept sphere the hit point lies on; 0 or 1
 * when the ray enters through an end cap. */
VKAS_API float vkasRayQueryGetIntersectionLssHitValue(const VkasRayQuery* q, VkBool32 committed);

/*
 * The intersection's primitive type, vkas-specific: the SPIR-V intersection types above cannot tell spheres and
 * LSS from triangles, this can. For the committed intersection: NONE when there is none, AABB for a generated hit.
 * For the candidate: TRIANGLE, AABB, SPHERE or LSS while Proceed's last call returned VK_TRUE, NONE otherwise.
 */
#define VKAS_INTERSECTION_PRIMITIVE_NONE 0u
#define VKAS_INTERSECTION_PRIMITIVE_TRIANGLE 1u
#define VKAS_INTERSECTION_PRIMITIVE_AABB 2u
#define VKAS_INTERSECTION_PRIMITIVE_SPHERE 3u
#define VKAS_INTERSECTION_PRIMITIVE_LSS 4u
VKAS_API uint32_t vkasRayQueryGetIntersectionPrimitiveType(const VkasRayQuery* q, VkBool32 committed);

/* ---------------------------------------------------------------------------------------------------------- */
/* Batch tracing: many rays at once, spread over the device's worker threads                                  */
/* ---------------------------------------------------------------------------------------------------------- */

typedef struct VkasRay {
    float origin[3];
    float tMin;
    float direction[3];
    float tMax;
} VkasRay;

typedef struct VkasHit {
    uint32_t type; /* VKAS_COMMITTED_INTERSECTION_*: NONE for a miss (indices -1, t = tMax, the rest 0) */
    float t;
    int32_t instanceId;
    int32_t instanceCustomIndex;
    int32_t geometryIndex;
    int32_t primitiveIndex;
    float barycentrics[2];
    uint32_t instanceShaderBindingTableRecordOffset;
    VkBool32 frontFace;
} VkasHit;

typedef enum VkasTraceMode {
    VKAS_TRACE_MODE_CLOSEST_HIT = 0, /* the committed hit after full traversal */
    VKAS_TRACE_MODE_ANY_HIT = 1,     /* traversal ends at the first hit (adds TERMINATE_ON_FIRST_HIT): shadow rays */
    VKAS_TRACE_MODE_MAX_ENUM = 0x7FFFFFFF /* as in Vulkan: the enum holds any 32-bit value, so invalid ones are
                                             reported (VUID-vkasTraceRays-mode-parameter) rather than undefined */
} VkasTraceMode;

/*
 * Traces rayCount rays as if each ran a ray query to completion, confirming every non-opaque triangle candidate
 * (the behaviour of a pipeline whose any-hit shader is unused), and writes pHits[i] for pRays[i]. AABBs never
 * produce hits here (there is no intersection shader): use vkasTraceRaysProcedural, or a ray query and
 * vkasRayQueryGenerateIntersection. Spheres and linear swept spheres are confirmed like triangles: their hits have
 * type TRIANGLE, the ids and t, barycentrics 0 and frontFace VK_FALSE.
 * Returns VK_SUCCESS, or VK_ERROR_VALIDATION_FAILED_EXT (nothing written) when validation finds bad parameters.
 */
VKAS_API VkResult vkasTraceRays(VkDevice device, VkAccelerationStructureKHR topLevel, VkasTraceMode mode,
                                uint32_t rayFlags, uint32_t cullMask, uint32_t rayCount, const VkasRay* pRays,
                                VkasHit* pHits);

/* An AABB candidate met by vkasTraceRaysProcedural: what an intersection shader would be given. */
typedef struct VkasAabbCandidate {
    uint32_t rayIndex; /* index of the ray in pRays */
    int32_t instanceId;
    int32_t instanceCustomIndex;
    int32_t geometryIndex;
    int32_t primitiveIndex;
    float objectRayOrigin[3];    /* the ray in the instance's object space */
    float objectRayDirection[3];
    float tMin;                  /* the ray's tMin */
    float tMax;                  /* the current tMax: the closest t committed so far, or the ray's tMax */
    VkBool32 opaque;             /* the resolved opacity (geometry, instance and ray flags) */
} VkasAabbCandidate;

/*
 * The intersection step for AABB primitives: return VK_TRUE and set *pTHit to report an intersection at *pTHit.
 * A reported t outside [tMin, tMax] is ignored (as OpReportIntersectionKHR rejects it). Called concurrently from the
 * device's worker threads, possibly more than once for the same candidate.
 */
typedef VkBool32(VKAPI_PTR* PFN_vkasIntersectAabb)(void* pUserData, const VkasAabbCandidate* pCandidate,
                                                    float* pTHit);

/*
 * vkasTraceRays with procedural primitives: every AABB candidate goes to pfnIntersect, and an intersection it
 * reports is committed as a GENERATED hit (there is no any-hit step, so non-opaque ones are accepted too).
 * pfnIntersect may be NULL: AABBs then never produce hits, as in vkasTraceRays.
 */
VKAS_API VkResult vkasTraceRaysProcedural(VkDevice device, VkAccelerationStructureKHR topLevel, VkasTraceMode mode,
                                          uint32_t rayFlags, uint32_t cullMask, uint32_t rayCount,
                                          const VkasRay* pRays, VkasHit* pHits, PFN_vkasIntersectAabb pfnIntersect,
                                          void* pUserData);

#ifdef __cplusplus
}
#endif

#endif /* VKAS_H_ */
