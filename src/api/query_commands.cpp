// vkWriteAccelerationStructuresPropertiesKHR and vkGetDeviceAccelerationStructureCompatibilityKHR.
#include <cstdio>
#include <cinttypes>
#include <cstring>

#include "api/copy_commands.hpp"
#include "api/entry_points.hpp"
#include "api/validation.hpp"
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

namespace {
using ull = unsigned long long;

// The stride and pointer VUIDs of each query type.
struct QueryRules {
    VkQueryType type;
    const char* name;
    const char* strideVuid;
    const char* pointerVuid;
};
constexpr QueryRules kQueryRules[] = {
    {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, "ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03448",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03449"},
    {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR, "ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03450",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03451"},
    {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR, "ACCELERATION_STRUCTURE_SIZE_KHR",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06731",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06732"},
    {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR,
     "ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06733",
     "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06734"},
};
}  // namespace

VKAPI_ATTR VkResult VKAPI_CALL WriteAccelerationStructuresPropertiesKHR(
    VkDevice device, uint32_t accelerationStructureCount, const VkAccelerationStructureKHR* pAccelerationStructures,
    VkQueryType queryType, size_t dataSize, void* pData, size_t stride) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkWriteAccelerationStructuresPropertiesKHR");
    if (v.enabled()) {
        if (!v.check(dev != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-device-parameter",
                     "device is not a valid VkDevice."))
            return VK_ERROR_VALIDATION_FAILED_EXT;
        v.check(accelerationStructureCount > 0,
                "VUID-vkWriteAccelerationStructuresPropertiesKHR-accelerationStructureCount-arraylength",
                "accelerationStructureCount is 0.");
        v.check(pAccelerationStructures != nullptr || accelerationStructureCount == 0,
                "VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parameter",
                "pAccelerationStructures is NULL.");
        v.check(dataSize > 0, "VUID-vkWriteAccelerationStructuresPropertiesKHR-dataSize-arraylength", "dataSize is 0.");
        v.check(pData != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-pData-parameter", "pData is NULL.");
        const QueryRules* rules = nullptr;
        for (const QueryRules& r : kQueryRules)
            if (r.type == queryType) rules = &r;
        // The query types of other extensions are valid VkQueryType values but not allowed here (06742).
        const bool knownEnum = (queryType >= VK_QUERY_TYPE_OCCLUSION && queryType <= VK_QUERY_TYPE_TIMESTAMP) ||
                               queryType >= 1000000000;
        if (v.check(knownEnum, "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-parameter",
                    "queryType %d is not a VkQueryType.", int(queryType)))
            v.check(rules != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06742",
                    "queryType %d is not one of the acceleration-structure size queries.", int(queryType));
        if (rules) {
            v.check(stride % sizeof(VkDeviceSize) == 0, rules->strideVuid,
                    "queryType is %s and stride %zu is not a multiple of sizeof(VkDeviceSize).", rules->name, stride);
            if (pData)
                v.check(reinterpret_cast<uintptr_t>(pData) % alignof(VkDeviceSize) == 0, rules->pointerVuid,
                        "queryType is %s and pData %p is not aligned for a VkDeviceSize.", rules->name, pData);
        }
        v.check(uint64_t(accelerationStructureCount) * stride <= dataSize,
                "VUID-vkWriteAccelerationStructuresPropertiesKHR-dataSize-03452",
                "dataSize %zu is less than accelerationStructureCount %u * stride %zu.", dataSize,
                accelerationStructureCount, stride);
        for (uint32_t i = 0; pAccelerationStructures && i < accelerationStructureCount; ++i) {
            char name[48];
            std::snprintf(name, sizeof name, "pAccelerationStructures[%u]", i);
            const auto* as = checkHandle<AccelerationStructure>(
                v, *dev, pAccelerationStructures[i], ObjectMagic::AccelerationStructure,
                "VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parameter",
                "VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parent", name);
            if (!as) continue;
            if (!v.check(as->buffer->memory != nullptr, "VUID-vkWriteAccelerationStructuresPropertiesKHR-buffer-03736",
                         "the buffer of pAccelerationStructures[%u] is not bound to memory.", i))
                continue;
            const std::byte* block = constructedBlock(*as);
            if (!v.check(block != nullptr,
                         "VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-11591",
                         "pAccelerationStructures[%u] has not been constructed.", i))
                continue;
            const format::Header* h = format::header(block);
            if (queryType == VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                v.check(h->buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR,
                        "VUID-vkWriteAccelerationStructuresPropertiesKHR-accelerationStructures-03431",
                        "queryType is ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR but pAccelerationStructures[%u] was "
                        "not built with ALLOW_COMPACTION.",
                        i);
            if (queryType == VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR)
                v.check(h->type == uint32_t(format::StructureType::TopLevel),
                        "VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-12425",
                        "queryType is ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR but "
                        "pAccelerationStructures[%u] is a bottom-level structure.",
                        i);
            if (v.failureCount() > 16) break;  // enough said
        }
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
