#include "api/validate/properties_query.hpp"

#include <cstdio>

#include "api/structure_bytes.hpp"
#include "api/validate/parameters.hpp"
#include "engine/format/layout.hpp"

namespace vkas {

namespace {

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

void checkWriteAccelerationStructuresProperties(Validator& v, const Device& dev, uint32_t accelerationStructureCount,
                                                const VkAccelerationStructureKHR* pAccelerationStructures,
                                                VkQueryType queryType, size_t dataSize, void* pData, size_t stride) {
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
            v, dev, pAccelerationStructures[i], ObjectMagic::AccelerationStructure,
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
}

}  // namespace vkas
