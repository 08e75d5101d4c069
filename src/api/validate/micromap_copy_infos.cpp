#include "api/validate/micromap_copy_infos.hpp"

#include <cstdio>

#include "api/structure_bytes.hpp"
#include "api/micromap.hpp"
#include "api/validate/parameters.hpp"
#include "engine/format/micromap_check.hpp"
#include "engine/format/micromap_serialize.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

bool knownCopyMode(VkCopyMicromapModeEXT mode) {
    return mode >= VK_COPY_MICROMAP_MODE_CLONE_EXT && mode <= VK_COPY_MICROMAP_MODE_COMPACT_EXT;
}

// The readable extent the application promises for a serialized micromap: its header's serialized size (at least
// the header itself).
uint64_t micromapBlobExtent(const void* src) {
    return std::max<uint64_t>(serial::kMicromapBlockOffset, blobExtent(src));
}

}  // namespace

void checkCopyMicromapInfo(Validator& v, const Device& dev, const VkCopyMicromapInfoEXT& info) {
    v.check(info.sType == VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT, "VUID-VkCopyMicromapInfoEXT-sType-sType",
            "pInfo->sType is %d.", int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkCopyMicromapInfoEXT-pNext-pNext", "pInfo->pNext is not NULL.");
    const bool compact = info.mode == VK_COPY_MICROMAP_MODE_COMPACT_EXT;
    // Spec: "mode must be VK_COPY_MICROMAP_MODE_COMPACT_EXT or VK_COPY_MICROMAP_MODE_CLONE_EXT"
    v.check(compact || info.mode == VK_COPY_MICROMAP_MODE_CLONE_EXT, "VUID-VkCopyMicromapInfoEXT-mode-07531",
            "pInfo->mode is %d, not CLONE or COMPACT.", int(info.mode));
    const auto* src = checkHandle<Micromap>(v, dev, info.src, ObjectMagic::Micromap,
                                            "VUID-VkCopyMicromapInfoEXT-src-parameter",
                                            "VUID-VkCopyMicromapInfoEXT-commonparent", "pInfo->src");
    const auto* dst = checkHandle<Micromap>(v, dev, info.dst, ObjectMagic::Micromap,
                                            "VUID-VkCopyMicromapInfoEXT-dst-parameter",
                                            "VUID-VkCopyMicromapInfoEXT-commonparent", "pInfo->dst");
    // Every vkas memory type is host-visible: bound is host-visible.
    if (src && v.check(src->buffer->memory != nullptr, "VUID-vkCopyMicromapEXT-buffer-07558",
                       "the buffer of pInfo->src is not bound to memory.")) {
        const std::byte* block = constructedMicromapBlock(*src);
        if (v.check(block != nullptr, "VUID-vkCopyMicromapEXT-src-11670",
                    "pInfo->src has not been constructed (built, copied or deserialized).") &&
            compact)
            v.check(format::micromapHeader(block)->buildFlags & VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT,
                    "VUID-VkCopyMicromapInfoEXT-mode-07533",
                    "pInfo->mode is COMPACT but pInfo->src was not built with ALLOW_COMPACTION.");
    }
    if (dst)
        v.check(dst->buffer->memory != nullptr, "VUID-vkCopyMicromapEXT-buffer-07559",
                "the buffer of pInfo->dst is not bound to memory.");
}

void checkCopyMicromapToMemoryInfo(Validator& v, const Device& dev, const VkCopyMicromapToMemoryInfoEXT& info) {
    v.check(info.sType == VK_STRUCTURE_TYPE_COPY_MICROMAP_TO_MEMORY_INFO_EXT,
            "VUID-VkCopyMicromapToMemoryInfoEXT-sType-sType", "pInfo->sType is %d.", int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkCopyMicromapToMemoryInfoEXT-pNext-pNext", "pInfo->pNext is not NULL.");
    if (v.check(knownCopyMode(info.mode), "VUID-VkCopyMicromapToMemoryInfoEXT-mode-parameter",
                "pInfo->mode %d is not a VkCopyMicromapModeEXT.", int(info.mode)))
        v.check(info.mode == VK_COPY_MICROMAP_MODE_SERIALIZE_EXT, "VUID-VkCopyMicromapToMemoryInfoEXT-mode-07542",
                "pInfo->mode is %d, not SERIALIZE.", int(info.mode));
    const auto* src = checkHandle<Micromap>(v, dev, info.src, ObjectMagic::Micromap,
                                            "VUID-VkCopyMicromapToMemoryInfoEXT-src-parameter", nullptr, "pInfo->src");
    if (src && v.check(src->buffer->memory != nullptr, "VUID-vkCopyMicromapToMemoryEXT-buffer-07568",
                       "the buffer of pInfo->src is not bound to memory."))
        v.check(constructedMicromapBlock(*src) != nullptr, "VUID-VkCopyMicromapToMemoryInfoEXT-src-07540",
                "pInfo->src has not been constructed (built, copied or deserialized).");
    const auto address = reinterpret_cast<uintptr_t>(info.dst.hostAddress);
    if (v.check(address != 0, "VUID-vkCopyMicromapToMemoryEXT-pInfo-07569", "pInfo->dst.hostAddress is NULL."))
        v.check(address % 16 == 0, "VUID-vkCopyMicromapToMemoryEXT-pInfo-07570",
                "pInfo->dst.hostAddress %p is not a multiple of 16.", info.dst.hostAddress);
}

bool checkCopyMemoryToMicromapInfo(Validator& v, const Device& dev, const VkCopyMemoryToMicromapInfoEXT& info) {
    bool incompatible = false;
    v.check(info.sType == VK_STRUCTURE_TYPE_COPY_MEMORY_TO_MICROMAP_INFO_EXT,
            "VUID-VkCopyMemoryToMicromapInfoEXT-sType-sType", "pInfo->sType is %d.", int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkCopyMemoryToMicromapInfoEXT-pNext-pNext", "pInfo->pNext is not NULL.");
    if (v.check(knownCopyMode(info.mode), "VUID-VkCopyMemoryToMicromapInfoEXT-mode-parameter",
                "pInfo->mode %d is not a VkCopyMicromapModeEXT.", int(info.mode)))
        v.check(info.mode == VK_COPY_MICROMAP_MODE_DESERIALIZE_EXT, "VUID-VkCopyMemoryToMicromapInfoEXT-mode-07548",
                "pInfo->mode is %d, not DESERIALIZE.", int(info.mode));
    const auto* dst = checkHandle<Micromap>(v, dev, info.dst, ObjectMagic::Micromap,
                                            "VUID-VkCopyMemoryToMicromapInfoEXT-dst-parameter", nullptr, "pInfo->dst");
    if (dst)
        v.check(dst->buffer->memory != nullptr, "VUID-vkCopyMemoryToMicromapEXT-buffer-07565",
                "the buffer of pInfo->dst is not bound to memory.");
    const void* src = info.src.hostAddress;
    if (v.check(src != nullptr, "VUID-vkCopyMemoryToMicromapEXT-pInfo-07563", "pInfo->src.hostAddress is NULL.") &&
        v.check(reinterpret_cast<uintptr_t>(src) % 16 == 0, "VUID-vkCopyMemoryToMicromapEXT-pInfo-07564",
                "pInfo->src.hostAddress %p is not a multiple of 16.", src)) {
        serial::SerializedMicromapView view;
        const format::CheckResult check =
            format::checkSerializedMicromap(static_cast<const std::byte*>(src), micromapBlobExtent(src), &view);
        if (check.status == format::CheckStatus::Incompatible) {
            incompatible = true;
            // Spec: "The data in src must have a format compatible with the destination physical device as
            // returned by vkGetDeviceMicromapCompatibilityEXT"
            v.fail("VUID-VkCopyMemoryToMicromapInfoEXT-src-07549",
                   "the data at pInfo->src is not compatible with this device "
                   "(vkGetDeviceMicromapCompatibilityEXT returns INCOMPATIBLE): %s.",
                   check.reason);
        } else if (v.check(check.ok(), "VUID-VkCopyMemoryToMicromapInfoEXT-src-07547",
                           "the data at pInfo->src is not a serialized micromap: %s.", check.reason) &&
                   dst && dst->buffer->memory) {
            v.check(dst->size >= view.deserializedSize, "VUID-VkCopyMemoryToMicromapInfoEXT-dst-07550",
                    "pInfo->dst has size %llu but the serialized data's deserialized size is %llu.",
                    (ull)dst->size, (ull)view.deserializedSize);
        }
    }
    return incompatible;
}

void checkWriteMicromapsProperties(Validator& v, const Device& dev, uint32_t micromapCount,
                                   const VkMicromapEXT* pMicromaps, VkQueryType queryType, size_t dataSize,
                                   void* pData, size_t stride) {
    v.check(micromapCount > 0, "VUID-vkWriteMicromapsPropertiesEXT-micromapCount-arraylength", "micromapCount is 0.");
    v.check(pMicromaps != nullptr || micromapCount == 0, "VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-parameter",
            "pMicromaps is NULL.");
    v.check(dataSize > 0, "VUID-vkWriteMicromapsPropertiesEXT-dataSize-arraylength", "dataSize is 0.");
    v.check(pData != nullptr, "VUID-vkWriteMicromapsPropertiesEXT-pData-parameter", "pData is NULL.");
    const bool compacted = queryType == VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT;
    const bool sizeQuery = compacted || queryType == VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT;
    // The query types of other extensions are valid VkQueryType values but not allowed here (07503).
    const bool knownEnum = (queryType >= VK_QUERY_TYPE_OCCLUSION && queryType <= VK_QUERY_TYPE_TIMESTAMP) ||
                           queryType >= 1000000000;
    if (v.check(knownEnum, "VUID-vkWriteMicromapsPropertiesEXT-queryType-parameter",
                "queryType %d is not a VkQueryType.", int(queryType)))
        v.check(sizeQuery, "VUID-vkWriteMicromapsPropertiesEXT-queryType-07503",
                "queryType %d is neither MICROMAP_COMPACTED_SIZE_EXT nor MICROMAP_SERIALIZATION_SIZE_EXT.",
                int(queryType));
    if (sizeQuery) {
        v.check(stride % sizeof(VkDeviceSize) == 0, "VUID-vkWriteMicromapsPropertiesEXT-queryType-10071",
                "stride %zu is not a multiple of sizeof(VkDeviceSize).", stride);
        if (pData)
            v.check(reinterpret_cast<uintptr_t>(pData) % alignof(VkDeviceSize) == 0,
                    "VUID-vkWriteMicromapsPropertiesEXT-queryType-10072", "pData %p is not aligned for a VkDeviceSize.",
                    pData);
    }
    v.check(uint64_t(micromapCount) * stride <= dataSize, "VUID-vkWriteMicromapsPropertiesEXT-dataSize-07576",
            "dataSize %zu is less than micromapCount %u * stride %zu.", dataSize, micromapCount, stride);
    for (uint32_t i = 0; pMicromaps && i < micromapCount; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "pMicromaps[%u]", i);
        const auto* m = checkHandle<Micromap>(v, dev, pMicromaps[i], ObjectMagic::Micromap,
                                              "VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-parameter",
                                              "VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-parent", name);
        if (!m) continue;
        if (!v.check(m->buffer->memory != nullptr, "VUID-vkWriteMicromapsPropertiesEXT-buffer-07577",
                     "the buffer of pMicromaps[%u] is not bound to memory.", i))
            continue;
        const std::byte* block = constructedMicromapBlock(*m);
        if (!v.check(block != nullptr, "VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-11671",
                     "pMicromaps[%u] has not been constructed.", i))
            continue;
        if (compacted)
            v.check(format::micromapHeader(block)->buildFlags & VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT,
                    "VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-07502",
                    "queryType is MICROMAP_COMPACTED_SIZE_EXT but pMicromaps[%u] was not built with "
                    "ALLOW_COMPACTION.",
                    i);
        if (v.failureCount() > 16) break;  // enough said
    }
}

}  // namespace vkas
