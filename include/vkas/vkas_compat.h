/*
 * vkas_compat.h - Vulkan items newer than the system's <vulkan/vulkan_core.h>.
 *
 * Debian 12's libvulkan-dev ships header version 239, which predates some extensions vkas supports.
 * Every definition here is guarded so that it is used only when the system header lacks it; the values are
 * taken from the Vulkan specification (vk.xml).
 */
#ifndef VKAS_COMPAT_H_
#define VKAS_COMPAT_H_

#include <vulkan/vulkan_core.h>

/* VK_KHR_ray_tracing_position_fetch (header 1.3.253). */
#ifndef VK_KHR_ray_tracing_position_fetch
#define VK_KHR_ray_tracing_position_fetch 1
#define VK_KHR_RAY_TRACING_POSITION_FETCH_SPEC_VERSION 1
#define VK_KHR_RAY_TRACING_POSITION_FETCH_EXTENSION_NAME "VK_KHR_ray_tracing_position_fetch"
#define VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR ((VkBuildAccelerationStructureFlagBitsKHR)0x00000800)
#define VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_POSITION_FETCH_FEATURES_KHR ((VkStructureType)1000481000)
typedef struct VkPhysicalDeviceRayTracingPositionFetchFeaturesKHR {
    VkStructureType sType;
    void*           pNext;
    VkBool32        rayTracingPositionFetch;
} VkPhysicalDeviceRayTracingPositionFetchFeaturesKHR;
#endif

/* VK_NV_ray_tracing_linear_swept_spheres (header 1.4.306). The geometry data structures go in the pNext chain of
 * VkAccelerationStructureGeometryKHR; its geometry union is unused for these types. */
#ifndef VK_NV_ray_tracing_linear_swept_spheres
#define VK_NV_ray_tracing_linear_swept_spheres 1
#define VK_NV_RAY_TRACING_LINEAR_SWEPT_SPHERES_SPEC_VERSION 1
#define VK_NV_RAY_TRACING_LINEAR_SWEPT_SPHERES_EXTENSION_NAME "VK_NV_ray_tracing_linear_swept_spheres"
#define VK_GEOMETRY_TYPE_SPHERES_NV ((VkGeometryTypeKHR)1000429004)
#define VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV ((VkGeometryTypeKHR)1000429005)
#define VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_LINEAR_SWEPT_SPHERES_FEATURES_NV ((VkStructureType)1000429008)
#define VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV ((VkStructureType)1000429009)
#define VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV ((VkStructureType)1000429010)
#define VK_FORMAT_FEATURE_2_ACCELERATION_STRUCTURE_RADIUS_BUFFER_BIT_NV 0x0008000000000000ULL
typedef enum VkRayTracingLssIndexingModeNV {
    VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV = 0,
    VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV = 1,
    VK_RAY_TRACING_LSS_INDEXING_MODE_MAX_ENUM_NV = 0x7FFFFFFF
} VkRayTracingLssIndexingModeNV;
typedef enum VkRayTracingLssPrimitiveEndCapsModeNV {
    VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV = 0,
    VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV = 1,
    VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_MAX_ENUM_NV = 0x7FFFFFFF
} VkRayTracingLssPrimitiveEndCapsModeNV;
typedef struct VkPhysicalDeviceRayTracingLinearSweptSpheresFeaturesNV {
    VkStructureType sType;
    void*           pNext;
    VkBool32        spheres;
    VkBool32        linearSweptSpheres;
} VkPhysicalDeviceRayTracingLinearSweptSpheresFeaturesNV;
typedef struct VkAccelerationStructureGeometryLinearSweptSpheresDataNV {
    VkStructureType                       sType;
    const void*                           pNext;
    VkFormat                              vertexFormat;
    VkDeviceOrHostAddressConstKHR         vertexData;
    VkDeviceSize                          vertexStride;
    VkFormat                              radiusFormat;
    VkDeviceOrHostAddressConstKHR         radiusData;
    VkDeviceSize                          radiusStride;
    VkIndexType                           indexType;
    VkDeviceOrHostAddressConstKHR         indexData;
    VkDeviceSize                          indexStride;
    VkRayTracingLssIndexingModeNV         indexingMode;
    VkRayTracingLssPrimitiveEndCapsModeNV endCapsMode;
} VkAccelerationStructureGeometryLinearSweptSpheresDataNV;
typedef struct VkAccelerationStructureGeometrySpheresDataNV {
    VkStructureType               sType;
    const void*                   pNext;
    VkFormat                      vertexFormat;
    VkDeviceOrHostAddressConstKHR vertexData;
    VkDeviceSize                  vertexStride;
    VkFormat                      radiusFormat;
    VkDeviceOrHostAddressConstKHR radiusData;
    VkDeviceSize                  radiusStride;
    VkIndexType                   indexType;
    VkDeviceOrHostAddressConstKHR indexData;
    VkDeviceSize                  indexStride;
} VkAccelerationStructureGeometrySpheresDataNV;
#endif

/* VK_KHR_ray_tracing_maintenance1 (header 1.3.213): the two acceleration-structure query types vkas answers in
 * vkWriteAccelerationStructuresPropertiesKHR. */
#ifndef VK_KHR_ray_tracing_maintenance1
#define VK_KHR_ray_tracing_maintenance1 1
#define VK_KHR_RAY_TRACING_MAINTENANCE_1_SPEC_VERSION 1
#define VK_KHR_RAY_TRACING_MAINTENANCE_1_EXTENSION_NAME "VK_KHR_ray_tracing_maintenance1"
#define VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR ((VkQueryType)1000386000)
#define VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR ((VkQueryType)1000386001)
#endif

/* VK_ERROR_INCOMPATIBLE_VERSION_KHR: the result the provisional VK_KHR_ray_tracing (v8/v9) gave for serialized
 * acceleration-structure data of an incompatible version. The final extension dropped it (loading incompatible data
 * is invalid usage, VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pInfo-03414); vkas still returns it from
 * vkCopyMemoryToAccelerationStructureKHR for data whose UUIDs it does not load (docs/API.md). */
#ifndef VK_ERROR_INCOMPATIBLE_VERSION_KHR
#define VK_ERROR_INCOMPATIBLE_VERSION_KHR ((VkResult)-1000150000)
#endif

/* The provisional name of VkAccelerationStructureBuildRangeInfoKHR (VK_KHR_ray_tracing v8/v9, 2020): same four
 * uint32_t members in the same order. vkas follows the final rules for it (docs/API.md, "The provisional name"). */
#ifndef VKAS_NO_PROVISIONAL_NAMES
typedef VkAccelerationStructureBuildRangeInfoKHR VkAccelerationStructureBuildOffsetInfoKHR;
#endif

#endif /* VKAS_COMPAT_H_ */
