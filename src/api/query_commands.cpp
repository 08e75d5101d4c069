// vkWriteAccelerationStructuresPropertiesKHR and vkGetDeviceAccelerationStructureCompatibilityKHR: valid-usage checks
// first (api/validate/query_calls.hpp), then the answer.
#include <cstdio>
#include <cinttypes>
#include <cstring>

#include "api/copy_commands.hpp"
#include "api/entry_points.hpp"
#include "api/validate/query_calls.hpp"
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
    if (!checkWriteAccelerationStructuresPropertiesCall(v, dev, accelerationStructureCount, pAccelerationStructures,
                                                        queryType, dataSize, pData, stride))
        return VK_ERROR_VALIDATION_FAILED_EXT;
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
    if (!checkGetDeviceAccelerationStructureCompatibility(v, dev, pVersionInfo, pCompatibility)) return;
    if (!pCompatibility) return;
    const bool ok = pVersionInfo && pVersionInfo->pVersionData && serial::compatibleVersion(pVersionInfo->pVersionData);
    *pCompatibility = ok ? VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR
                         : VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR;
}

}  // namespace vkas::entry
