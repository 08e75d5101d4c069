// vkCreate/DestroyAccelerationStructureKHR, vkGetAccelerationStructureDeviceAddressKHR and
// vkGetAccelerationStructureBuildSizesKHR: valid-usage checks first (api/validate/; nothing is written when one
// fails), then the object or the answer.
#include "api/build_geometry_info.hpp"
#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/structure_calls.hpp"
#include "engine/assemble/opacity_section_build.hpp"
#include "engine/assemble/size_query.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/format/sizes.hpp"
#include "engine/input/build_inputs.hpp"

namespace vkas::entry {

VKAPI_ATTR void VKAPI_CALL GetAccelerationStructureBuildSizesKHR(
    VkDevice device, VkAccelerationStructureBuildTypeKHR buildType,
    const VkAccelerationStructureBuildGeometryInfoKHR* pBuildInfo, const uint32_t* pMaxPrimitiveCounts,
    VkAccelerationStructureBuildSizesInfoKHR* pSizeInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetAccelerationStructureBuildSizesKHR");
    if (!checkGetAccelerationStructureBuildSizes(v, dev, buildType, pBuildInfo, pMaxPrimitiveCounts, pSizeInfo))
        return;
    uint64_t primitives = 0;
    for (uint32_t g = 0; g < pBuildInfo->geometryCount; ++g) primitives += pMaxPrimitiveCounts[g];
    StructureSizes s = structureSizes(*pBuildInfo, primitives);
    // [EXT-OMM] The room for the geometries' opacity micromaps (engine/format/opacity_section.hpp).
    if (allGeometriesPresent(*pBuildInfo))
        s.structureSize += opacitySectionBound(*pBuildInfo, [&](uint32_t g) { return pMaxPrimitiveCounts[g]; });
    pSizeInfo->accelerationStructureSize = s.structureSize;
    pSizeInfo->buildScratchSize = s.buildScratchSize;
    pSizeInfo->updateScratchSize = s.updateScratchSize;
}

VKAPI_ATTR VkResult VKAPI_CALL CreateAccelerationStructureKHR(VkDevice device,
                                                              const VkAccelerationStructureCreateInfoKHR* pCreateInfo,
                                                              const VkAllocationCallbacks* pAllocator,
                                                              VkAccelerationStructureKHR* pAccelerationStructure) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateAccelerationStructureKHR");
    if (!checkCreateAccelerationStructure(v, dev, pCreateInfo, pAccelerationStructure))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    auto* as = createObject<AccelerationStructure>(pAllocator, dev->allocator());
    if (!as) return VK_ERROR_OUT_OF_HOST_MEMORY;
    as->device = dev;
    as->buffer = fromHandle<Buffer>(pCreateInfo->buffer);
    as->offset = pCreateInfo->offset;
    as->size = pCreateInfo->size;
    as->type = pCreateInfo->type;
    as->createFlags = pCreateInfo->createFlags;
    if (!dev->track(as)) {
        destroyObject(as);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pAccelerationStructure = toHandle<VkAccelerationStructureKHR>(as);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyAccelerationStructureKHR(VkDevice device,
                                                           VkAccelerationStructureKHR accelerationStructure,
                                                           const VkAllocationCallbacks* pAllocator) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyAccelerationStructureKHR");
    if (!checkDestroyAccelerationStructure(v, dev, accelerationStructure, pAllocator)) return;
    auto* as = fromHandle<AccelerationStructure>(accelerationStructure);
    if (dev) dev->untrack(as);
    destroyObject(as);
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL
GetAccelerationStructureDeviceAddressKHR(VkDevice device, const VkAccelerationStructureDeviceAddressInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetAccelerationStructureDeviceAddressKHR");
    if (!checkGetAccelerationStructureDeviceAddress(v, dev, pInfo)) return 0;
    return reinterpret_cast<VkDeviceAddress>(fromHandle<AccelerationStructure>(pInfo->accelerationStructure)->block());
}

}  // namespace vkas::entry
