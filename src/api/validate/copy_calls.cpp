#include "api/validate/copy_calls.hpp"

#include "api/validate/copy_infos.hpp"
#include "api/validate/parameters.hpp"

namespace vkas {

VkResult checkCopyAccelerationStructure(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                        const VkCopyAccelerationStructureInfoKHR* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyAccelerationStructureKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyAccelerationStructureKHR-deferredOperation-parameter",
                            "VUID-vkCopyAccelerationStructureKHR-deferredOperation-parent",
                            "VUID-vkCopyAccelerationStructureKHR-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyAccelerationStructureKHR-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkCopyAccelerationStructureInfo(v, *dev, pInfo);
    return v.failed() ? VK_ERROR_VALIDATION_FAILED_EXT : VK_SUCCESS;
}

VkResult checkCopyAccelerationStructureToMemory(Validator& v, const Device* dev,
                                                VkDeferredOperationKHR deferredOperation,
                                                const VkCopyAccelerationStructureToMemoryInfoKHR* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyAccelerationStructureToMemoryKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-parameter",
                            "VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-parent",
                            "VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkCopyAccelerationStructureToMemoryInfo(v, *dev, pInfo);
    return v.failed() ? VK_ERROR_VALIDATION_FAILED_EXT : VK_SUCCESS;
}

VkResult checkCopyMemoryToAccelerationStructure(Validator& v, const Device* dev,
                                                VkDeferredOperationKHR deferredOperation,
                                                const VkCopyMemoryToAccelerationStructureInfoKHR* pInfo) {
    if (!v.enabled()) return VK_SUCCESS;
    if (!v.check(dev != nullptr, "VUID-vkCopyMemoryToAccelerationStructureKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    checkDeferredOperation(v, *dev, deferredOperation,
                           {"VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-parameter",
                            "VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-parent",
                            "VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-03678"});
    if (!v.check(pInfo != nullptr, "VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-parameter", "pInfo is NULL."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    const bool incompatible = checkCopyMemoryToAccelerationStructureInfo(v, *dev, pInfo);
    if (v.failed()) return incompatible ? VK_ERROR_INCOMPATIBLE_VERSION_KHR : VK_ERROR_VALIDATION_FAILED_EXT;
    return VK_SUCCESS;
}

}  // namespace vkas
