// vkWriteAccelerationStructuresPropertiesKHR and vkGetDeviceAccelerationStructureCompatibilityKHR: valid-usage checks
// first (the properties query's in api/validate/properties_query.hpp), then the answer.
#include <cstdio>
#include <cinttypes>
#include <cstring>

#include "api/copy_commands.hpp"
#include "api/entry_points.hpp"
#include "api/validate/properties_query.hpp"
#include "api/validate/validator.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/serialize.hpp"

namespace vkas {

void writeAccelerationStructureProperties(const AccelerationStructure* const* structures, uint32_t count,
                                          VkQueryType queryType, size_t dataSize, void* pData, size_t stride) {
    auto* out = static_cast<std::byte*>(pData);
    for (uint32_t i = 0; i < count; ++i) {
        const uint64_t at = uint64_t(i) * stride;
        if (!out || at > dataSize || dataSize - at < sizeof(uint64_t)) return;
        const std::byte* block = structures[i] ? constructedBlock(*structures[i]) : nullptr;
        uint64_t value = 0;
        if (block) {
            switch (queryType) {
                case VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR:
                case VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR: value = serial::compactedSize(block); break;
                case VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR:
                    value = serial::serializedSize(block);
                    break;
                case VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR:
                    value = serial::handleCount(block);
                    break;
                default: break;
            }
        }
        std::memcpy(out + at, &value, sizeof value);
    }
}

}  // namespace vkas

namespace vkas::entry {

VKAPI_ATTR VkResult VKAPI_CALL WriteAccelerationStructuresPropertiesKHR(
    VkDevice device, uint32_t accelerationStructureCount, const VkAccelerationStructureKHR* pAccelerationStructures,
    VkQueryType queryType, size_t dataSize, void* pData, size_t stride) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkWriteAccelerationStructuresPropertiesKHR");
    if (v.enabled()) {
        if (!v.check(dev != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-device-parameter",
                     "device is not a valid VkDevice."))
            return VK_ERROR_VALIDATION_FAILED_EXT;
        checkWriteAccelerationStructuresProperties(v, *dev, accelerationStructureCount, pAccelerationStructures,
                                                   queryType, dataSize, pData, stride);
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (!dev || !pAccelerationStructures) return VK_SUCCESS;
    // Objects are looked up again (validation off: unknown handles give 0, never a dereference of garbage).
    constexpr uint32_t kChunk = 64;
    const AccelerationStructure* list[kChunk];
    for (uint32_t first = 0; first < accelerationStructureCount; first += kChunk) {
        const uint32_t n = std::min(kChunk, accelerationStructureCount - first);
        for (uint32_t i = 0; i < n; ++i)
            list[i] = dev->live<AccelerationStructure>(pAccelerationStructures[first + i],
                                                       ObjectMagic::AccelerationStructure);
        const uint64_t at = uint64_t(first) * stride;
        if (at >= dataSize) break;
        writeAccelerationStructureProperties(list, n, queryType, dataSize - at, static_cast<std::byte*>(pData) + at,
                                             stride);
    }
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL GetDeviceAccelerationStructureCompatibilityKHR(
    VkDevice device, const VkAccelerationStructureVersionInfoKHR* pVersionInfo,
    VkAccelerationStructureCompatibilityKHR* pCompatibility) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeviceAccelerationStructureCompatibilityKHR");
    if (v.enabled()) {
        if (!v.check(dev != nullptr, "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-device-parameter",
                     "device is not a valid VkDevice."))
            return;
        v.check(pCompatibility != nullptr,
                "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pCompatibility-parameter",
                "pCompatibility is NULL.");
        if (v.check(pVersionInfo != nullptr,
                    "VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pVersionInfo-parameter",
                    "pVersionInfo is NULL.")) {
            v.check(pVersionInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR,
                    "VUID-VkAccelerationStructureVersionInfoKHR-sType-sType", "pVersionInfo->sType is %d.",
                    int(pVersionInfo->sType));
            v.check(pVersionInfo->pNext == nullptr, "VUID-VkAccelerationStructureVersionInfoKHR-pNext-pNext",
                    "pVersionInfo->pNext is not NULL.");
            v.check(pVersionInfo->pVersionData != nullptr,
                    "VUID-VkAccelerationStructureVersionInfoKHR-pVersionData-parameter",
                    "pVersionInfo->pVersionData is NULL.");
        }
        if (v.failed()) return;
    }
    if (!pCompatibility) return;
    const bool ok = pVersionInfo && pVersionInfo->pVersionData && serial::compatibleVersion(pVersionInfo->pVersionData);
    *pCompatibility = ok ? VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR
                         : VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR;
}

}  // namespace vkas::entry
