// vkCopyMicromapEXT (CLONE, COMPACT), vkCopyMicromapToMemoryEXT (SERIALIZE), vkCopyMemoryToMicromapEXT
// (DESERIALIZE), vkWriteMicromapsPropertiesEXT and vkGetDeviceMicromapCompatibilityEXT: valid-usage checks first
// (api/validate/micromap_copy_calls.hpp; nothing is written when one fails), then the work on plain memory
// (engine/format/micromap_serialize.hpp), now or as the task of a deferred operation. Each work function checks what
// it must to stay inside the memory it was given (validation on or off) and returns VK_ERROR_UNKNOWN, with nothing
// written, when it cannot proceed; deserialization checks its input completely (engine/format/micromap_check.hpp).
#include <algorithm>
#include <cstring>

#include "api/copy_commands.hpp"
#include "api/deferred_operation.hpp"
#include "api/entry_points.hpp"
#include "api/micromap.hpp"
#include "api/validate/micromap_copy_calls.hpp"
#include "engine/format/micromap_check.hpp"
#include "engine/format/micromap_serialize.hpp"

namespace vkas {

namespace {

// CLONE and COMPACT both copy [0, usedSize): usedSize is exact, so the clone is already compact.
VkResult copyMicromap(const Micromap& src, Micromap& dst) {
    const std::byte* from = constructedMicromapBlock(src);
    std::byte* to = dst.block();
    if (!from || !to || serial::micromapCompactedSize(from) > dst.size) return VK_ERROR_UNKNOWN;
    serial::copyMicromapBlock(from, to);
    dst.constructed = true;
    return VK_SUCCESS;
}

VkResult serializeMicromap(const Micromap& src, void* dst) {
    const std::byte* block = constructedMicromapBlock(src);
    if (!block || !dst) return VK_ERROR_UNKNOWN;
    if (rangesOverlap(reinterpret_cast<uintptr_t>(dst), serial::micromapSerializedSize(block),
                      reinterpret_cast<uintptr_t>(block), serial::micromapCompactedSize(block)))
        return VK_ERROR_UNKNOWN;
    serial::serializeMicromapBlock(block, static_cast<std::byte*>(dst));
    return VK_SUCCESS;
}

VkResult deserializeMicromap(const void* src, Micromap& dst) {
    // Whatever fails below, dst ends holding no micromap; nothing is copied before the checks pass.
    const auto fail = [&dst](VkResult result) {
        if (constructedMicromapBlock(dst)) markMicromapUnconstructed(dst);
        dst.constructed = false;
        return result;
    };
    if (!src) return fail(VK_ERROR_UNKNOWN);
    const auto* data = static_cast<const std::byte*>(src);
    serial::SerializedMicromapView view;
    // Always checked, validation on or off: the UUIDs, sizes, the integrity hash and the block.
    const format::CheckResult check =
        format::checkSerializedMicromap(data, std::max<uint64_t>(serial::kMicromapBlockOffset, blobExtent(src)), &view);
    if (check.status == format::CheckStatus::Incompatible) return fail(VK_ERROR_INCOMPATIBLE_VERSION_KHR);
    if (!check.ok()) return fail(VK_ERROR_UNKNOWN);
    std::byte* to = dst.block();
    if (!to || dst.size < view.deserializedSize) return fail(VK_ERROR_UNKNOWN);
    if (rangesOverlap(reinterpret_cast<uintptr_t>(src), view.serializedSize, reinterpret_cast<uintptr_t>(to),
                      view.deserializedSize)) {
        dst.constructed = false;  // its memory is the blob's: not written
        return VK_ERROR_UNKNOWN;
    }
    std::memcpy(to, view.block, view.deserializedSize);
    dst.constructed = true;
    return VK_SUCCESS;
}

}  // namespace

}  // namespace vkas

namespace vkas::entry {

VKAPI_ATTR VkResult VKAPI_CALL CopyMicromapEXT(VkDevice device, VkDeferredOperationKHR deferredOperation,
                                               const VkCopyMicromapInfoEXT* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyMicromapEXT");
    if (const VkResult r = checkCopyMicromap(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* src = fromHandle<Micromap>(pInfo->src);
    auto* dst = fromHandle<Micromap>(pInfo->dst);
    return runOrDefer(deferredOperation, [src, dst] { return copyMicromap(*src, *dst); });
}

VKAPI_ATTR VkResult VKAPI_CALL CopyMicromapToMemoryEXT(VkDevice device, VkDeferredOperationKHR deferredOperation,
                                                       const VkCopyMicromapToMemoryInfoEXT* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyMicromapToMemoryEXT");
    if (const VkResult r = checkCopyMicromapToMemory(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* src = fromHandle<Micromap>(pInfo->src);
    void* out = pInfo->dst.hostAddress;
    return runOrDefer(deferredOperation, [src, out] { return serializeMicromap(*src, out); });
}

VKAPI_ATTR VkResult VKAPI_CALL CopyMemoryToMicromapEXT(VkDevice device, VkDeferredOperationKHR deferredOperation,
                                                       const VkCopyMemoryToMicromapInfoEXT* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCopyMemoryToMicromapEXT");
    if (const VkResult r = checkCopyMemoryToMicromap(v, dev, deferredOperation, pInfo); r != VK_SUCCESS) return r;
    if (!dev || !pInfo) return VK_ERROR_UNKNOWN;
    auto* dst = fromHandle<Micromap>(pInfo->dst);
    const void* blob = pInfo->src.hostAddress;
    return runOrDefer(deferredOperation, [blob, dst] { return deserializeMicromap(blob, *dst); });
}

VKAPI_ATTR VkResult VKAPI_CALL WriteMicromapsPropertiesEXT(VkDevice device, uint32_t micromapCount,
                                                           const VkMicromapEXT* pMicromaps, VkQueryType queryType,
                                                           size_t dataSize, void* pData, size_t stride) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkWriteMicromapsPropertiesEXT");
    if (const VkResult r = checkWriteMicromapsPropertiesCall(v, dev, micromapCount, pMicromaps, queryType, dataSize,
                                                             pData, stride);
        r != VK_SUCCESS)
        return r;
    if (!dev || !pMicromaps || !pData) return VK_SUCCESS;
    auto* out = static_cast<std::byte*>(pData);
    for (uint32_t i = 0; i < micromapCount; ++i) {
        const uint64_t at = uint64_t(i) * stride;
        if (at > dataSize || dataSize - at < sizeof(uint64_t)) break;
        // Looked up again (validation off: an unknown handle gives 0, never a dereference of garbage).
        const auto* m = dev->live<Micromap>(pMicromaps[i], ObjectMagic::Micromap);
        const std::byte* block = m ? constructedMicromapBlock(*m) : nullptr;
        uint64_t value = 0;
        if (block && queryType == VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT) value = serial::micromapCompactedSize(block);
        if (block && queryType == VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT)
            value = serial::micromapSerializedSize(block);
        std::memcpy(out + at, &value, sizeof value);
    }
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL GetDeviceMicromapCompatibilityEXT(VkDevice device,
                                                             const VkMicromapVersionInfoEXT* pVersionInfo,
                                                             VkAccelerationStructureCompatibilityKHR* pCompatibility) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeviceMicromapCompatibilityEXT");
    if (!checkGetDeviceMicromapCompatibility(v, dev, pVersionInfo, pCompatibility)) return;
    if (!pCompatibility) return;
    // The driverUUID and compatibility UUID of the version header are compared with the pair vkas writes.
    const bool ok =
        pVersionInfo && pVersionInfo->pVersionData && serial::compatibleMicromapVersion(pVersionInfo->pVersionData);
    *pCompatibility = ok ? VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR
                         : VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR;
}

}  // namespace vkas::entry
