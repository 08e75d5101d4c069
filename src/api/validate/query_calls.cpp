#include "api/validate/query_calls.hpp"

#include "api/validate/properties_query.hpp"

namespace vkas {

bool checkWriteAccelerationStructuresPropertiesCall(Validator& v, const Device* dev,
                                                    uint32_t accelerationStructureCount,
                                                    const VkAccelerationStructureKHR* pAccelerationStructures,
                                                    VkQueryType queryType, size_t dataSize, void* pData, size_t stride) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return false;
    checkWriteAccelerationStructuresProperties(v, *dev, accelerationStructureCount, pAccelerationStructures, queryType,
                                               dataSize, pData, stride);
    return !v.failed();
}

bool checkGetDeviceAccelerationStructureCompatibility(Validator& v, const Device* dev,
                                                      const VkAccelerationStructureVersionInfoKHR* pVersionInfo,
                                                      const VkAccelerationStructureCompatibilityKHR* pCompatibility) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return false;
    v.check(pCompatibility != nullptr, "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pCompatibility-parameter",
            "pCompatibility is NULL.");
    if (v.check(pVersionInfo != nullptr, "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pVersionInfo-parameter",
                "pVersionInfo is NULL.")) {
        v.check(pVersionInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR,
                "VUID-VkAccelerationStructureVersionInfoKHR-sType-sType", "pVersionInfo->sType is %d.",
                int(pVersionInfo->sType));
        v.check(pVersionInfo->pNext == nullptr, "VUID-VkAccelerationStructureVersionInfoKHR-pNext-pNext",
                "pVersionInfo->pNext is not NULL.");
        v.check(pVersionInfo->pVersionData != nullptr, "VUID-VkAccelerationStructureVersionInfoKHR-pVersionData-parameter",
                "pVersionInfo->pVersionData is NULL.");
    }
    return !v.failed();
}

}  // namespace vkas
