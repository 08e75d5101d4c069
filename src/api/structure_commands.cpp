// vkCreate/DestroyAccelerationStructureKHR, vkGetAccelerationStructureDeviceAddressKHR and
// vkGetAccelerationStructureBuildSizesKHR: valid-usage checks first (api/validate/; nothing is written when one
// fails), then the object or the answer.
#include "api/build_geometry_info.hpp"
#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/limits.hpp"
#include "api/validate/geometry_info.hpp"
#include "api/validate/parameters.hpp"
#include "api/validate/structure_create_info.hpp"
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
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-device-parameter",
                "device is not a valid VkDevice.");
        v.check(buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR ||
                    buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR ||
                    buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_OR_DEVICE_KHR,
                "VUID-vkGetAccelerationStructureBuildSizesKHR-buildType-parameter", "buildType %d is not valid.",
                int(buildType));
        if (v.check(pBuildInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-parameter",
                    "pBuildInfo is NULL.")) {
            checkGeometryInfo(v, *pBuildInfo, "pBuildInfo");
            if (pBuildInfo->geometryCount != 0)
                v.check(pMaxPrimitiveCounts != nullptr,
                        "VUID-vkGetAccelerationStructureBuildSizesKHR-pMaxPrimitiveCounts-11612",
                        "pMaxPrimitiveCounts is NULL but pBuildInfo->geometryCount is %u.", pBuildInfo->geometryCount);
            if (pMaxPrimitiveCounts && pBuildInfo->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR &&
                pBuildInfo->geometryCount == 1)
                v.check(pMaxPrimitiveCounts[0] <= limits::kMaxInstanceCount,
                        "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-03785",
                        "pMaxPrimitiveCounts[0] %u exceeds maxInstanceCount.", pMaxPrimitiveCounts[0]);
            // The sizes of a bottom level of more primitives than maxPrimitiveCount would describe a structure that
            // no build may make (and whose counts the format does not hold): reported as the build reports it.
            if (pMaxPrimitiveCounts && pBuildInfo->geometryCount <= limits::kMaxGeometryCount) {
                uint64_t total = 0;
                for (uint32_t g = 0; g < pBuildInfo->geometryCount; ++g) total += pMaxPrimitiveCounts[g];
                checkPrimitiveTotal(v, *pBuildInfo, total, "pBuildInfo");
            }
        }
        if (v.check(pSizeInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pSizeInfo-parameter",
                    "pSizeInfo is NULL."))
        {
            v.check(pSizeInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR,
                    "VUID-VkAccelerationStructureBuildSizesInfoKHR-sType-sType", "pSizeInfo->sType is %d.",
                    int(pSizeInfo->sType));
            v.check(pSizeInfo->pNext == nullptr, "VUID-VkAccelerationStructureBuildSizesInfoKHR-pNext-pNext",
                    "pSizeInfo->pNext is not NULL.");
        }
        if (v.failed()) return;
    }
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
    if (!dev) {
        v.fail("VUID-vkCreateAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (v.enabled()) {
        if (v.check(pCreateInfo != nullptr, "VUID-vkCreateAccelerationStructureKHR-pCreateInfo-parameter",
                    "pCreateInfo is NULL."))
            checkAccelerationStructureCreateInfo(v, *dev, *pCreateInfo);
        v.check(pAccelerationStructure != nullptr,
                "VUID-vkCreateAccelerationStructureKHR-pAccelerationStructure-parameter",
                "pAccelerationStructure is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
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
    if (!dev)
        return v.fail("VUID-vkDestroyAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
    if (accelerationStructure == VK_NULL_HANDLE) return;
    if (v.enabled()) {
        const auto* as = checkHandle<AccelerationStructure>(
            v, *dev, accelerationStructure, ObjectMagic::AccelerationStructure,
            "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parameter",
            "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parent", "accelerationStructure");
        if (!as) return;
        checkDestroyAllocator(v, as->allocator, pAllocator,
                              "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02443",
                              "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02444");
        if (v.failed()) return;
    }
    auto* as = fromHandle<AccelerationStructure>(accelerationStructure);
    if (dev) dev->untrack(as);
    destroyObject(as);
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL
GetAccelerationStructureDeviceAddressKHR(VkDevice device, const VkAccelerationStructureDeviceAddressInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetAccelerationStructureDeviceAddressKHR");
    if (!dev) {
        v.fail("VUID-vkGetAccelerationStructureDeviceAddressKHR-device-parameter", "device is not a valid VkDevice.");
        return 0;
    }
    if (v.enabled()) {
        if (v.check(pInfo != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-parameter",
                    "pInfo is NULL.")) {
            v.check(pInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                    "VUID-VkAccelerationStructureDeviceAddressInfoKHR-sType-sType", "pInfo->sType is %d.",
                    int(pInfo->sType));
            v.check(pInfo->pNext == nullptr, "VUID-VkAccelerationStructureDeviceAddressInfoKHR-pNext-pNext",
                    "pInfo->pNext is not NULL.");
            if (const auto* as = checkHandle<AccelerationStructure>(
                    v, *dev, pInfo->accelerationStructure, ObjectMagic::AccelerationStructure,
                    "VUID-VkAccelerationStructureDeviceAddressInfoKHR-accelerationStructure-parameter", nullptr,
                    "pInfo->accelerationStructure")) {
                v.check(as->buffer->memory != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09541",
                        "the buffer of pInfo->accelerationStructure is not bound to memory.");
                v.check(as->buffer->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                        "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09542",
                        "the buffer of pInfo->accelerationStructure lacks SHADER_DEVICE_ADDRESS usage.");
            }
        }
        if (v.failed()) return 0;
    }
    return reinterpret_cast<VkDeviceAddress>(fromHandle<AccelerationStructure>(pInfo->accelerationStructure)->block());
}

}  // namespace vkas::entry
