#include "api/validate/copy_infos.hpp"

#include "api/structure_bytes.hpp"
#include "api/validate/parameters.hpp"
#include "engine/util/byte_io.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/check.hpp"
#include "engine/format/serialize.hpp"

namespace vkas {

namespace {
using ull = unsigned long long;
}  // namespace

void checkCopyAccelerationStructureInfo(Validator& v, const Device& dev,
                                        const VkCopyAccelerationStructureInfoKHR* pInfo) {
    v.check(pInfo->sType == VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR,
            "VUID-VkCopyAccelerationStructureInfoKHR-sType-sType", "pInfo->sType is %d.", int(pInfo->sType));
    v.check(pInfo->pNext == nullptr, "VUID-VkCopyAccelerationStructureInfoKHR-pNext-pNext",
            "pInfo->pNext is not NULL.");
    const bool modeKnown = pInfo->mode >= VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR &&
                           pInfo->mode <= VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    v.check(modeKnown, "VUID-VkCopyAccelerationStructureInfoKHR-mode-parameter",
            "pInfo->mode %d is not a VkCopyAccelerationStructureModeKHR.", int(pInfo->mode));
    const bool compact = pInfo->mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
    if (modeKnown)
        v.check(compact || pInfo->mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR,
                "VUID-VkCopyAccelerationStructureInfoKHR-mode-03410", "pInfo->mode is %d, not CLONE or COMPACT.",
                int(pInfo->mode));
    const auto* src = checkHandle<AccelerationStructure>(
        v, dev, pInfo->src, ObjectMagic::AccelerationStructure, "VUID-VkCopyAccelerationStructureInfoKHR-src-parameter",
        "VUID-VkCopyAccelerationStructureInfoKHR-commonparent", "pInfo->src");
    const auto* dst = checkHandle<AccelerationStructure>(
        v, dev, pInfo->dst, ObjectMagic::AccelerationStructure, "VUID-VkCopyAccelerationStructureInfoKHR-dst-parameter",
        "VUID-VkCopyAccelerationStructureInfoKHR-commonparent", "pInfo->dst");
    const std::byte* block = nullptr;
    if (src && v.check(src->buffer->memory != nullptr, "VUID-VkCopyAccelerationStructureInfoKHR-buffer-03718",
                       "the buffer of pInfo->src is not bound to memory.")) {
        block = constructedBlock(*src);
        v.check(block != nullptr, "VUID-vkCopyAccelerationStructureKHR-src-11586",
                "pInfo->src has not been constructed (built, copied or deserialized).");
    }
    if (dst)
        v.check(dst->buffer->memory != nullptr, "VUID-VkCopyAccelerationStructureInfoKHR-buffer-03719",
                "the buffer of pInfo->dst is not bound to memory.");
    if (block) {
        const format::Header* h = format::header(block);
        if (compact)
            v.check(h->buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR,
                    "VUID-VkCopyAccelerationStructureInfoKHR-src-03411",
                    "pInfo->mode is COMPACT but pInfo->src was not built with ALLOW_COMPACTION.");
        if (dst && dst->buffer->memory) {
            const uint64_t need = serial::compactedSize(block);
            v.check(dst->size >= need,
                    compact ? "VUID-VkCopyAccelerationStructureInfoKHR-mode-12419"
                            : "VUID-VkCopyAccelerationStructureInfoKHR-mode-12418",
                    "pInfo->dst has size %llu but the %s needs %llu bytes (the %s query of pInfo->src).",
                    (ull)dst->size, compact ? "compacted copy" : "clone", (ull)need,
                    compact ? "ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR" : "ACCELERATION_STRUCTURE_SIZE_KHR");
            v.check(!rangesOverlap(reinterpret_cast<uintptr_t>(dst->block()), need,
                                   reinterpret_cast<uintptr_t>(block), need),
                    "VUID-VkCopyAccelerationStructureInfoKHR-dst-07791",
                    "the memory pInfo->dst would be written overlaps the memory of pInfo->src.");
        }
    }
}

void checkCopyAccelerationStructureToMemoryInfo(Validator& v, const Device& dev,
                                                const VkCopyAccelerationStructureToMemoryInfoKHR* pInfo) {
    v.check(pInfo->sType == VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR,
            "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-sType-sType", "pInfo->sType is %d.",
            int(pInfo->sType));
    v.check(pInfo->pNext == nullptr, "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-pNext-pNext",
            "pInfo->pNext is not NULL.");
    const bool modeKnown = pInfo->mode >= VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR &&
                           pInfo->mode <= VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    if (v.check(modeKnown, "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-parameter",
                "pInfo->mode %d is not a VkCopyAccelerationStructureModeKHR.", int(pInfo->mode)))
        v.check(pInfo->mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR,
                "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-03412", "pInfo->mode is %d, not SERIALIZE.",
                int(pInfo->mode));
    const auto* src = checkHandle<AccelerationStructure>(
        v, dev, pInfo->src, ObjectMagic::AccelerationStructure,
        "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-parameter", nullptr, "pInfo->src");
    if (src &&
        v.check(src->buffer->memory != nullptr, "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-11714",
                "the buffer of pInfo->src is not bound to memory."))
        v.check(constructedBlock(*src) != nullptr, "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-04959",
                "pInfo->src has not been constructed (built, copied or deserialized).");
    const auto dstAddress = reinterpret_cast<uintptr_t>(pInfo->dst.hostAddress);
    if (v.check(dstAddress != 0, "VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03732",
                "pInfo->dst.hostAddress is NULL."))
        v.check(dstAddress % 16 == 0, "VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03751",
                "pInfo->dst.hostAddress %p is not a multiple of 16.", pInfo->dst.hostAddress);
}

bool checkCopyMemoryToAccelerationStructureInfo(Validator& v, const Device& dev,
                                                const VkCopyMemoryToAccelerationStructureInfoKHR* pInfo) {
    bool incompatible = false;
    v.check(pInfo->sType == VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR,
            "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-sType-sType", "pInfo->sType is %d.",
            int(pInfo->sType));
    v.check(pInfo->pNext == nullptr, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pNext-pNext",
            "pInfo->pNext is not NULL.");
    const bool modeKnown = pInfo->mode >= VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR &&
                           pInfo->mode <= VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    if (v.check(modeKnown, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-mode-parameter",
                "pInfo->mode %d is not a VkCopyAccelerationStructureModeKHR.", int(pInfo->mode)))
        v.check(pInfo->mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR,
                "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-mode-03413",
                "pInfo->mode is %d, not DESERIALIZE.", int(pInfo->mode));
    const auto* dst = checkHandle<AccelerationStructure>(
        v, dev, pInfo->dst, ObjectMagic::AccelerationStructure,
        "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-parameter", nullptr, "pInfo->dst");
    if (dst)
        v.check(dst->buffer->memory != nullptr, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-11717",
                "the buffer of pInfo->dst is not bound to memory.");
    const void* src = pInfo->src.hostAddress;
    if (v.check(src != nullptr, "VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03729",
                "pInfo->src.hostAddress is NULL.") &&
        v.check(reinterpret_cast<uintptr_t>(src) % 16 == 0, "VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03750",
                "pInfo->src.hostAddress %p is not a multiple of 16.", src)) {
        serial::SerializedView view;
        const format::CheckResult check =
            format::checkSerialized(static_cast<const std::byte*>(src), blobExtent(src), &view);
        if (check.status == format::CheckStatus::Incompatible) {
            incompatible = true;
            v.fail("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pInfo-03414",
                   "the data at pInfo->src is not compatible with this device "
                   "(vkGetDeviceAccelerationStructureCompatibilityKHR returns INCOMPATIBLE): %s.",
                   check.reason);
        } else if (!v.check(check.ok(), "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960",
                            "the data at pInfo->src is not a serialized acceleration structure: %s.",
                            check.reason)) {
        } else {
            if (dst && dst->buffer->memory)
                v.check(dst->size >= view.deserializedSize, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-03746",
                        "pInfo->dst has size %llu but the serialized data's deserialized size is %llu.",
                        (ull)dst->size, (ull)view.deserializedSize);
            SerializedReferences references(dev, view.layout);
            for (uint64_t k = 0; k < view.handleCount; ++k) {
                const uint64_t value = load64(view.handles + 8 * k);
                if (!v.check(value == 0 || references.toReference(value) != 0,
                             "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960",
                             view.layout == serial::Layout::V1
                                 ? "entry %llu of the handle array, 0x%llx, is neither the device address of a "
                                   "bottom-level acceleration structure of this device nor the handle of one."
                                 : "entry %llu of the handle array, 0x%llx, is not the device address "
                                   "(vkGetAccelerationStructureDeviceAddressKHR) of a bottom-level acceleration "
                                   "structure of this device.",
                             (ull)k, (ull)value))
                    break;
            }
        }
    }
    return incompatible;
}

}  // namespace vkas
