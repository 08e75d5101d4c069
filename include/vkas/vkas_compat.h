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

#endif /* VKAS_COMPAT_H_ */
