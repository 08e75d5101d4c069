// vkCreateMicromapEXT, vkDestroyMicromapEXT, vkGetMicromapBuildSizesEXT and vkBuildMicromapsEXT
// (VK_EXT_opacity_micromap): valid-usage checks first (api/validate/micromap_*; nothing is written when one fails),
// then the object, the answer or the engine's build on plain memory (engine/assemble/micromap_build.hpp), now or as
// tasks of a deferred operation.
#include <cstring>
#include <memory>
#include <vector>

#include "api/deferred_operation.hpp"
#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/micromap.hpp"
#include "api/validate/micromap_calls.hpp"
#include "engine/assemble/micromap_build.hpp"
#include "engine/format/micromap_layout.hpp"

namespace vkas {

const std::byte* constructedMicromapBlock(const Micromap& micromap) {
    const std::byte* block = micromap.block();
    if (!micromap.constructed || !block || micromap.size < sizeof(format::MicromapHeader)) return nullptr;
    format::MicromapHeader h;
    std::memcpy(&h, block, sizeof h);
    if (h.magic != format::kMicromapMagic || h.usedSize < sizeof h || h.usedSize > micromap.size) return nullptr;
    return block;
}

void markMicromapUnconstructed(Micromap& micromap) noexcept {
    micromap.constructed = false;
    if (std::byte* block = micromap.block(); block && micromap.size >= sizeof(format::MicromapHeader))
        std::memset(block + offsetof(format::MicromapHeader, magic), 0, sizeof(format::MicromapHeader::magic));
}

const std::byte* resolveMicromap(uint64_t handle) {
    const void* object = reinterpret_cast<const void*>(handle);
    const Device* owner = Device::ownerOf(object);
    const Micromap* micromap = owner ? owner->live<Micromap>(object, ObjectMagic::Micromap) : nullptr;
    return micromap ? constructedMicromapBlock(*micromap) : nullptr;
}

}  // namespace vkas

namespace vkas::entry {

VKAPI_ATTR VkResult VKAPI_CALL CreateMicromapEXT(VkDevice device, const VkMicromapCreateInfoEXT* pCreateInfo,
                                                 const VkAllocationCallbacks* pAllocator, VkMicromapEXT* pMicromap) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateMicromapEXT");
    if (!checkCreateMicromap(v, dev, pCreateInfo, pMicromap)) return VK_ERROR_VALIDATION_FAILED_EXT;
    auto* micromap = createObject<Micromap>(pAllocator, dev->allocator());
    if (!micromap) return VK_ERROR_OUT_OF_HOST_MEMORY;
    micromap->device = dev;
    micromap->buffer = fromHandle<Buffer>(pCreateInfo->buffer);
    micromap->offset = pCreateInfo->offset;
    micromap->size = pCreateInfo->size;
    micromap->type = pCreateInfo->type;
    micromap->createFlags = pCreateInfo->createFlags;
    if (!dev->track(micromap)) {
        destroyObject(micromap);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pMicromap = toHandle<VkMicromapEXT>(micromap);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyMicromapEXT(VkDevice device, VkMicromapEXT micromap,
                                              const VkAllocationCallbacks* pAllocator) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyMicromapEXT");
    if (!checkDestroyMicromap(v, dev, micromap, pAllocator)) return;
    auto* m = fromHandle<Micromap>(micromap);
    dev->untrack(m);
    destroyObject(m);
}

VKAPI_ATTR void VKAPI_CALL GetMicromapBuildSizesEXT(VkDevice device, VkAccelerationStructureBuildTypeKHR buildType,
                                                    const VkMicromapBuildInfoEXT* pBuildInfo,
                                                    VkMicromapBuildSizesInfoEXT* pSizeInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetMicromapBuildSizesEXT");
    if (!checkGetMicromapBuildSizes(v, dev, buildType, pBuildInfo, pSizeInfo)) return;
    if (!pBuildInfo || !pSizeInfo) return;
    pSizeInfo->micromapSize = micromapSizeForUsage(*pBuildInfo);
    pSizeInfo->buildScratchSize = 0;  // the build needs no scratch memory
    // Spec: "A true value means that the information in the micromap will be copied by value into the acceleration
    // structure, and the micromap can be destroyed after the acceleration structure build concludes." vkas's
    // bottom-level builds copy the states they use.
    pSizeInfo->discardable = VK_TRUE;
}

VKAPI_ATTR VkResult VKAPI_CALL BuildMicromapsEXT(VkDevice device, VkDeferredOperationKHR deferredOperation,
                                                 uint32_t infoCount, const VkMicromapBuildInfoEXT* pInfos) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBuildMicromapsEXT");
    if (!checkBuildMicromapsCall(v, dev, deferredOperation, infoCount, pInfos)) return VK_ERROR_VALIDATION_FAILED_EXT;
    // One info's work; a build that fails leaves its destination unconstructed.
    auto runInfo = [pInfos](uint32_t i) {
        auto* dst = fromHandle<Micromap>(pInfos[i].dstMicromap);
        std::byte* block = dst ? dst->block() : nullptr;
        if (!block) return VK_ERROR_UNKNOWN;
        const VkResult r = buildMicromap(pInfos[i], block, dst->size);
        if (r == VK_SUCCESS)
            dst->constructed = true;
        else
            markMicromapUnconstructed(*dst);
        return r;
    };
    if (deferredOperation != VK_NULL_HANDLE) {
        // Nothing runs now: each info becomes a task of the operation, run by the threads that join it. The inputs
        // are read when the tasks run ("Pointer parameters must not be modified" while the operation is pending).
        auto* op = fromHandle<DeferredOperation>(deferredOperation);
        // The spec has no rule for this command against a pending operation (03678 is not among its rules), so
        // nothing is reported; starting it again would drop the pending work.
        if (op->pending()) return VK_ERROR_UNKNOWN;
        return deferEach(*op, infoCount, std::min<uint32_t>(infoCount, 256),
                         [runInfo](uint32_t i, const ParallelFor*) { return runInfo(i); });
    }
    VkResult result = VK_SUCCESS;
    for (uint32_t i = 0; i < infoCount; ++i)
        if (VkResult r = runInfo(i); r != VK_SUCCESS) result = r;
    return result;
}

}  // namespace vkas::entry
