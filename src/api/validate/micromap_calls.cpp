#include "api/validate/micromap_calls.hpp"

#include "api/micromap.hpp"
#include "api/validate/micromap_build_infos.hpp"
#include "api/validate/micromap_create_info.hpp"
#include "api/validate/parameters.hpp"

namespace vkas {

bool checkCreateMicromap(Validator& v, const Device* dev, const VkMicromapCreateInfoEXT* pCreateInfo,
                         const VkMicromapEXT* pMicromap) {
    if (!dev) {
        v.fail("VUID-vkCreateMicromapEXT-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    if (v.check(pCreateInfo != nullptr, "VUID-vkCreateMicromapEXT-pCreateInfo-parameter", "pCreateInfo is NULL."))
        checkMicromapCreateInfo(v, *dev, *pCreateInfo);
    v.check(pMicromap != nullptr, "VUID-vkCreateMicromapEXT-pMicromap-parameter", "pMicromap is NULL.");
    return !v.failed();
}

bool checkDestroyMicromap(Validator& v, const Device* dev, VkMicromapEXT micromap,
                          const VkAllocationCallbacks* pAllocator) {
    if (!dev) {
        v.fail("VUID-vkDestroyMicromapEXT-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (micromap == VK_NULL_HANDLE) return false;
    if (!v.enabled()) return true;
    const auto* m = checkHandle<Micromap>(v, *dev, micromap, ObjectMagic::Micromap,
                                          "VUID-vkDestroyMicromapEXT-micromap-parameter",
                                          "VUID-vkDestroyMicromapEXT-micromap-parent", "micromap");
    if (!m) return false;
    checkDestroyAllocator(v, m->allocator, pAllocator, "VUID-vkDestroyMicromapEXT-micromap-07442",
                          "VUID-vkDestroyMicromapEXT-micromap-07443");
    return !v.failed();
}

bool checkGetMicromapBuildSizes(Validator& v, const Device* dev, VkAccelerationStructureBuildTypeKHR buildType,
                                const VkMicromapBuildInfoEXT* pBuildInfo, const VkMicromapBuildSizesInfoEXT* pSizeInfo) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkGetMicromapBuildSizesEXT-device-parameter", "device is not a valid VkDevice."))
        return false;
    v.check(buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR ||
                buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR ||
                buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_OR_DEVICE_KHR,
            "VUID-vkGetMicromapBuildSizesEXT-buildType-parameter", "buildType %d is not valid.", int(buildType));
    // Spec: "The dstMicromap, mode, data, scratchData, and triangleArray members of pBuildInfo are ignored by
    // this command."
    if (v.check(pBuildInfo != nullptr, "VUID-vkGetMicromapBuildSizesEXT-pBuildInfo-parameter", "pBuildInfo is NULL."))
        checkMicromapBuildInfoUsage(v, *pBuildInfo, "pBuildInfo");
    if (v.check(pSizeInfo != nullptr, "VUID-vkGetMicromapBuildSizesEXT-pSizeInfo-parameter", "pSizeInfo is NULL.")) {
        v.check(pSizeInfo->sType == VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT,
                "VUID-VkMicromapBuildSizesInfoEXT-sType-sType", "pSizeInfo->sType is %d.", int(pSizeInfo->sType));
        v.check(pSizeInfo->pNext == nullptr, "VUID-VkMicromapBuildSizesInfoEXT-pNext-pNext",
                "pSizeInfo->pNext is not NULL.");
    }
    return !v.failed();
}

bool checkBuildMicromapsCall(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                             uint32_t infoCount, const VkMicromapBuildInfoEXT* pInfos) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkBuildMicromapsEXT-device-parameter", "device is not a valid VkDevice."))
        return false;
    checkBuildMicromaps(v, *dev, deferredOperation, infoCount, pInfos);
    return !v.failed();
}

}  // namespace vkas
