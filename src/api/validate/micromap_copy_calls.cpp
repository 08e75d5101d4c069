#include "api/validate/micromap_copy_calls.hpp"

#include "api/validate/micromap_copy_infos.hpp"
#include "api/validate/parameters.hpp"

namespace vkas {

VkResult checkCopyMicromap(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                           const VkCopyMicromapInfoEXT* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyMicromapEXT-device-parameter", "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyMicromapEXT-deferredOperation-parameter",
                            "VUID-vkCopyMicromapEXT-deferredOperation-parent",
                            "VUID-vkCopyMicromapEXT-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyMicromapEXT-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkCopyMicromapInfo(v, *dev, *pInfo);
    return v.failed() ? VK_ERROR_VALIDATION_FAILED_EXT : VK_SUCCESS;
}

VkResult checkCopyMicromapToMemory(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                   const VkCopyMicromapToMemoryInfoEXT* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyMicromapToMemoryEXT-device-parameter", "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyMicromapToMemoryEXT-deferredOperation-parameter",
                            "VUID-vkCopyMicromapToMemoryEXT-deferredOperation-parent",
                            "VUID-vkCopyMicromapToMemoryEXT-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyMicromapToMemoryEXT-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkCopyMicromapToMemoryInfo(v, *dev, *pInfo);
    return v.failed() ? VK_ERROR_VALIDATION_FAILED_EXT : VK_SUCCESS;
}

VkResult checkCopyMemoryToMicromap(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                   const VkCopyMemoryToMicromapInfoEXT* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyMemoryToMicromapEXT-device-parameter", "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyMemoryToMicromapEXT-deferredOperation-parameter",
                            "VUID-vkCopyMemoryToMicromapEXT-deferredOperation-parent",
                            "VUID-vkCopyMemoryToMicromapEXT-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyMemoryToMicromapEXT-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    const bool incompatible = checkCopyMemoryToMicromapInfo(v, *dev, *pInfo);
    if (v.failed()) return incompatible ? VK_ERROR_INCOMPATIBLE_VERSION_KHR : VK_ERROR_VALIDATION_FAILED_EXT;
    return VK_SUCCESS;
}

VkResult checkWriteMicromapsPropertiesCall(Validator& v, const Device* dev, uint32_t micromapCount,
                                           const VkMicromapEXT* pMicromaps, VkQueryType queryType, size_t dataSize,
                                           void* pData, size_t stride) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkWriteMicromapsPropertiesEXT-device-parameter",
                 "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkWriteMicromapsProperties(v, *dev, micromapCount, pMicromaps, queryType, dataSize, pData, stride);
    return v.failed() ? VK_ERROR_VALIDATION_FAILED_EXT : VK_SUCCESS;
}

bool checkGetDeviceMicromapCompatibility(Validator& v, const Device* dev, const VkMicromapVersionInfoEXT* pVersionInfo,
                                         const VkAccelerationStructureCompatibilityKHR* pCompatibility) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkGetDeviceMicromapCompatibilityEXT-device-parameter",
                 "device is not a valid VkDevice."))
        return false;
    v.check(pCompatibility != nullptr, "VUID-vkGetDeviceMicromapCompatibilityEXT-pCompatibility-parameter",
            "pCompatibility is NULL.");
    if (v.check(pVersionInfo != nullptr, "VUID-vkGetDeviceMicromapCompatibilityEXT-pVersionInfo-parameter",
                "pVersionInfo is NULL.")) {
        v.check(pVersionInfo->sType == VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT,
                "VUID-VkMicromapVersionInfoEXT-sType-sType", "pVersionInfo->sType is %d.", int(pVersionInfo->sType));
        v.check(pVersionInfo->pNext == nullptr, "VUID-VkMicromapVersionInfoEXT-pNext-pNext",
                "pVersionInfo->pNext is not NULL.");
        v.check(pVersionInfo->pVersionData != nullptr, "VUID-VkMicromapVersionInfoEXT-pVersionData-parameter",
                "pVersionInfo->pVersionData is NULL.");
    }
    return !v.failed();
}

}  // namespace vkas
