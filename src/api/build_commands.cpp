// vkBuildAccelerationStructuresKHR: valid-usage checks first (api/validate/build_calls.hpp; nothing is written when
// one fails), then the engine builds or refits each info on plain memory, now or as tasks of a deferred operation.
#include <algorithm>
#include <memory>
#include <vector>

#include "api/deferred_operation.hpp"
#include "api/device.hpp"
#include "api/micromap.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/build_calls.hpp"
#include "engine/assemble/refit.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/input/build_inputs.hpp"

namespace vkas::entry {

VKAPI_ATTR VkResult VKAPI_CALL BuildAccelerationStructuresKHR(
    VkDevice device, VkDeferredOperationKHR deferredOperation, uint32_t infoCount,
    const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
    const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBuildAccelerationStructuresKHR");
    if (!checkBuildAccelerationStructuresCall(v, dev, deferredOperation, infoCount, pInfos, ppBuildRangeInfos))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    // One info's work; `parallel` spreads a build over the threads joined to a deferred operation.
    auto runInfo = [pInfos, ppBuildRangeInfos](uint32_t i, const ParallelFor* parallel) {
        auto* dst = fromHandle<AccelerationStructure>(pInfos[i].dstAccelerationStructure);
        VkResult r;
        if (pInfos[i].mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) {
            // A refit of the source's tree (engine/assemble/refit.hpp); src == dst refits in place.
            const auto* src = fromHandle<AccelerationStructure>(pInfos[i].srcAccelerationStructure);
            const std::byte* srcBlock = src ? src->block() : nullptr;
            RefitJob job{&pInfos[i], ppBuildRangeInfos[i], srcBlock, dst->block(), dst->size,
                         resolveAccelerationStructure, resolveMicromap};
            r = srcBlock && job.dst ? refitAccelerationStructure(job) : VK_ERROR_UNKNOWN;
        } else {
            BuildJob job{&pInfos[i], ppBuildRangeInfos[i], dst->block(), dst->size, resolveAccelerationStructure,
                         parallel, resolveMicromap};
            try {
                r = buildAccelerationStructure(job);
            } catch (...) {
                markUnconstructed(*dst);  // out of memory part-way: dst holds no structure (an update never allocates)
                throw;
            }
        }
        if (r == VK_SUCCESS) dst->constructed = true;
        return r;
    };
    if (deferredOperation != VK_NULL_HANDLE) {
        // Nothing runs now: each info becomes a task of the operation, run by the threads that join it, which a
        // large build spreads its work over (the hint: about one thread per 4,096 primitives).
        uint64_t primitives = 0;
        for (uint32_t i = 0; i < infoCount; ++i)
            for (uint32_t g = 0; g < pInfos[i].geometryCount; ++g) primitives += ppBuildRangeInfos[i][g].primitiveCount;
        const uint32_t hint = uint32_t(std::min<uint64_t>(infoCount + primitives / 4096, 256));
        return deferEach(*fromHandle<DeferredOperation>(deferredOperation), infoCount, hint, runInfo);
    }
    VkResult result = VK_SUCCESS;
    for (uint32_t i = 0; i < infoCount; ++i)
        if (VkResult r = runInfo(i, nullptr); r != VK_SUCCESS) result = r;
    return result;
}

}  // namespace vkas::entry
