#include "api/validate/structure_calls.hpp"

#include "api/limits.hpp"
#include "api/validate/geometry_info.hpp"
#include "api/validate/parameters.hpp"
#include "api/validate/structure_create_info.hpp"

namespace vkas {

bool checkGetAccelerationStructureBuildSizes(Validator& v, const Device* dev,
                                             VkAccelerationStructureBuildTypeKHR buildType,
                                             const VkAccelerationStructureBuildGeometryInfoKHR* pBuildInfo,
                                             const uint32_t* pMaxPrimitiveCounts,
                                             const VkAccelerationStructureBuildSizesInfoKHR* pSizeInfo) {
    if (!v.enabled()) return true;
    v.check(dev != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-device-parameter",
            "device is not a valid VkDevice.");
    v.check(buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR ||
                buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR ||
                buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_OR_DEVICE_KHR,
            "VUID-vkGetAccelerationStructureBuildSizesKHR-buildType-parameter", "buildType %d is not valid.",
            int(buildType));
    if (v.check(pBuildInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-parameter",
                "pBuildInfo is NULL.")) {
        checkGeometryInfo(v, *pBuildInfo, "pBuildInfo");
        if (pBuildInfo->geometryCount != 0)
            v.check(pMaxPrimitiveCounts != nullptr,
                    "VUID-vkGetAccelerationStructureBuildSizesKHR-pMaxPrimitiveCounts-11612",
                    "pMaxPrimitiveCounts is NULL but pBuildInfo->geometryCount is %u.", pBuildInfo->geometryCount);
        if (pMaxPrimitiveCounts && pBuildInfo->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR &&
            pBuildInfo->geometryCount == 1)
            v.check(pMaxPrimitiveCounts[0] <= limits::kMaxInstanceCount,
                    "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-03785",
                    "pMaxPrimitiveCounts[0] %u exceeds maxInstanceCount.", pMaxPrimitiveCounts[0]);
        // The sizes of a bottom level of more primitives than maxPrimitiveCount would describe a structure that
        // no build may make (and whose counts the format does not hold): reported as the build reports it.
        if (pMaxPrimitiveCounts && pBuildInfo->geometryCount <= limits::kMaxGeometryCount) {
            uint64_t total = 0;
            for (uint32_t g = 0; g < pBuildInfo->geometryCount; ++g) total += pMaxPrimitiveCounts[g];
            checkPrimitiveTotal(v, *pBuildInfo, total, "pBuildInfo");
        }
    }
    if (v.check(pSizeInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pSizeInfo-parameter",
                "pSizeInfo is NULL.")) {
        v.check(pSizeInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR,
                "VUID-VkAccelerationStructureBuildSizesInfoKHR-sType-sType", "pSizeInfo->sType is %d.",
                int(pSizeInfo->sType));
        v.check(pSizeInfo->pNext == nullptr, "VUID-VkAccelerationStructureBuildSizesInfoKHR-pNext-pNext",
                "pSizeInfo->pNext is not NULL.");
    }
    return !v.failed();
}

bool checkCreateAccelerationStructure(Validator& v, const Device* dev,
                                      const VkAccelerationStructureCreateInfoKHR* pCreateInfo,
                                      const VkAccelerationStructureKHR* pAccelerationStructure) {
    if (!dev) {
        v.fail("VUID-vkCreateAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    if (v.check(pCreateInfo != nullptr, "VUID-vkCreateAccelerationStructureKHR-pCreateInfo-parameter",
                "pCreateInfo is NULL."))
        checkAccelerationStructureCreateInfo(v, *dev, *pCreateInfo);
    v.check(pAccelerationStructure != nullptr, "VUID-vkCreateAccelerationStructureKHR-pAccelerationStructure-parameter",
            "pAccelerationStructure is NULL.");
    return !v.failed();
}

bool checkDestroyAccelerationStructure(Validator& v, const Device* dev,
                                       VkAccelerationStructureKHR accelerationStructure,
                                       const VkAllocationCallbacks* pAllocator) {
    if (!dev) {
        v.fail("VUID-vkDestroyAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (accelerationStructure == VK_NULL_HANDLE) return false;
    if (!v.enabled()) return true;
    const auto* as = checkHandle<AccelerationStructure>(
        v, *dev, accelerationStructure, ObjectMagic::AccelerationStructure,
        "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parameter",
        "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parent", "accelerationStructure");
    if (!as) return false;
    checkDestroyAllocator(v, as->allocator, pAllocator, "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02443",
                          "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02444");
    return !v.failed();
}

bool checkGetAccelerationStructureDeviceAddress(Validator& v, const Device* dev,
                                                const VkAccelerationStructureDeviceAddressInfoKHR* pInfo) {
    if (!dev) {
        v.fail("VUID-vkGetAccelerationStructureDeviceAddressKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    if (v.check(pInfo != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-parameter", "pInfo is NULL.")) {
        v.check(pInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                "VUID-VkAccelerationStructureDeviceAddressInfoKHR-sType-sType", "pInfo->sType is %d.",
                int(pInfo->sType));
        v.check(pInfo->pNext == nullptr, "VUID-VkAccelerationStructureDeviceAddressInfoKHR-pNext-pNext",
                "pInfo->pNext is not NULL.");
        if (const auto* as = checkHandle<AccelerationStructure>(
                v, *dev, pInfo->accelerationStructure, ObjectMagic::AccelerationStructure,
                "VUID-VkAccelerationStructureDeviceAddressInfoKHR-accelerationStructure-parameter", nullptr,
                "pInfo->accelerationStructure")) {
            v.check(as->buffer->memory != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09541",
                    "the buffer of pInfo->accelerationStructure is not bound to memory.");
            v.check(as->buffer->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                    "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09542",
                    "the buffer of pInfo->accelerationStructure lacks SHADER_DEVICE_ADDRESS usage.");
        }
    }
    return !v.failed();
}

}  // namespace vkas
