// vkCopyAccelerationStructureKHR (CLONE, COMPACT), vkCopyAccelerationStructureToMemoryKHR (SERIALIZE) and
// vkCopyMemoryToAccelerationStructureKHR (DESERIALIZE): valid-usage checks first (api/validate/copy_calls.hpp;
// nothing is written when one fails), then the work functions of copy_commands.hpp on plain memory.
#include "engine/util/host_memory.hpp"
#include "api/copy_commands.hpp"

#include "api/deferred_operation.hpp"

#include <cinttypes>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/copy_calls.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/check.hpp"
#include "engine/format/convert.hpp"
#include "engine/format/serialize.hpp"

namespace vkas {

namespace {

uint64_t load64(const void* p) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
}

// Serialization's side of the handle array: a stored instance reference (a VkAccelerationStructureKHR handle) to
// the device address of its structure, looked up in the device's registry (a destroyed structure gives 0, never a
// dereference); consecutive instances mostly share a bottom level, so the last answer is kept.
struct AddressOfReference {
    const Device* device;
    uint64_t lastReference = 0, lastAddress = 0;
    static uint64_t map(const void* context, uint64_t reference) {
        auto* self = static_cast<AddressOfReference*>(const_cast<void*>(context));
        if (reference != self->lastReference) {
            const auto* as =
                self->device->live<AccelerationStructure>(reinterpret_cast<const void*>(reference),
                                                          ObjectMagic::AccelerationStructure);
            self->lastReference = reference;
            self->lastAddress = as ? reinterpret_cast<uintptr_t>(as->block()) : 0;
        }
        return self->lastAddress;
    }
};

}  // namespace


VkResult copyAccelerationStructure(const AccelerationStructure& src, AccelerationStructure& dst) {
    const std::byte* from = constructedBlock(src);
    std::byte* to = dst.block();
    if (!from || !to) return VK_ERROR_UNKNOWN;
    const uint64_t size = serial::compactedSize(from);
    if (size > dst.size) return VK_ERROR_UNKNOWN;
    serial::copyBlock(from, to);
    dst.constructed = true;
    return VK_SUCCESS;
}

VkResult serializeAccelerationStructure(const AccelerationStructure& src, void* dst) {
    const std::byte* block = constructedBlock(src);
    if (!block || !dst || !src.device) return VK_ERROR_UNKNOWN;
    if (rangesOverlap(reinterpret_cast<uintptr_t>(dst), serial::serializedSize(block),
                      reinterpret_cast<uintptr_t>(block), serial::compactedSize(block)))
        return VK_ERROR_UNKNOWN;
    AddressOfReference addresses{src.device};
    serial::serializeBlock(block, static_cast<std::byte*>(dst), &AddressOfReference::map, &addresses);
    return VK_SUCCESS;
}

VkResult deserializeAccelerationStructure(const Device& device, const void* src, AccelerationStructure& dst) {
    // Whatever fails below, dst ends holding no structure. Nothing is copied before the checks pass, so only a
    // structure dst held before needs undoing (its header's magic cleared); other memory is left as it was.
    const auto fail = [&dst](VkResult result) {
        const std::byte* block = dst.block();
        if (block && dst.size >= sizeof(format::Header) && format::header(block)->magic == format::kMagic)
            markUnconstructed(dst);
        dst.constructed = false;
        return result;
    };
    if (!src) return fail(VK_ERROR_UNKNOWN);
    serial::SerializedView view;
    // Always checked, validation on or off: the UUIDs, sizes, the integrity hash and the block's structure.
    const format::CheckResult check =
        format::checkSerialized(static_cast<const std::byte*>(src), blobExtent(src), &view);
    if (check.status == format::CheckStatus::Incompatible) return fail(VK_ERROR_INCOMPATIBLE_VERSION_KHR);
    if (!check.ok()) return fail(VK_ERROR_UNKNOWN);
    std::byte* to = dst.block();
    if (!to || dst.size < view.deserializedSize) return fail(VK_ERROR_UNKNOWN);
    if (rangesOverlap(reinterpret_cast<uintptr_t>(src), view.serializedSize, reinterpret_cast<uintptr_t>(to),
                      view.deserializedSize)) {
        dst.constructed = false;  // its memory is the blob's: not written
        return VK_ERROR_UNKNOWN;
    }
    // Every non-zero handle-array entry must name a bottom level before anything is copied.
    HostVector<uint64_t> referenceOfSlot;
    try {
        referenceOfSlot.resize(view.handleCount);
        SerializedReferences references(device, view.layout);
        for (uint64_t k = 0; k < view.handleCount; ++k) {
            const uint64_t value = load64(view.handles + 8 * k);
            referenceOfSlot[k] = references.toReference(value);
            if (value != 0 && referenceOfSlot[k] == 0) return fail(VK_ERROR_UNKNOWN);
        }
    } catch (...) {
        fail(VK_ERROR_OUT_OF_HOST_MEMORY);  // the slot table or the address index: dst holds no structure
        throw;
    }
    // A block of format 1 (an earlier release's) is written in format 2 (format/convert.hpp); it only shrinks.
    format::convertToCurrentFormat(view.block, to);
    serial::bindReferences(view, to, referenceOfSlot.data());
    dst.constructed = true;
    return VK_SUCCESS;
}

}  // namespace vkas

namespace vkas::entry {

VKAPI_ATTR VkResult VKAPI_CALL CopyAccelerationStructureKHR(VkDevice device, VkDeferredOperationKHR deferredOperation,
                                                            const VkCopyAccelerationStructureInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyAccelerationStructureKHR");
    if (const VkResult r = checkCopyAccelerationStructure(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* src = fromHandle<AccelerationStructure>(pInfo->src);
    auto* dst = fromHandle<AccelerationStructure>(pInfo->dst);
    return runOrDefer(deferredOperation, [src, dst] { return copyAccelerationStructure(*src, *dst); });
}

VKAPI_ATTR VkResult VKAPI_CALL CopyAccelerationStructureToMemoryKHR(
    VkDevice device, VkDeferredOperationKHR deferredOperation, const VkCopyAccelerationStructureToMemoryInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyAccelerationStructureToMemoryKHR");
    if (const VkResult r = checkCopyAccelerationStructureToMemory(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* src = fromHandle<AccelerationStructure>(pInfo->src);
    void* out = pInfo->dst.hostAddress;
    return runOrDefer(deferredOperation, [src, out] { return serializeAccelerationStructure(*src, out); });
}

VKAPI_ATTR VkResult VKAPI_CALL CopyMemoryToAccelerationStructureKHR(
    VkDevice device, VkDeferredOperationKHR deferredOperation, const VkCopyMemoryToAccelerationStructureInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyMemoryToAccelerationStructureKHR");
    if (const VkResult r = checkCopyMemoryToAccelerationStructure(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* dst = fromHandle<AccelerationStructure>(pInfo->dst);
    const void* blob = pInfo->src.hostAddress;
    return runOrDefer(deferredOperation,
                      [dev, blob, dst] { return deserializeAccelerationStructure(*dev, blob, *dst); });
}

}  // namespace vkas::entry
