// vkasGetDeviceProcAddr and the physical-device style queries.
#include <cstring>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/guarded_command.hpp"
#include "api/limits.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/input/vertex_format.hpp"
#include "engine/util/pnext_chain.hpp"

namespace {

struct ProcEntry {
    const char* name;
    PFN_vkVoidFunction function;
};

// Every command runs through Guarded (api/guarded_command.hpp): out of memory becomes VK_ERROR_OUT_OF_HOST_MEMORY, never an
// exception.
#define VKAS_PROC(name, fn) {name, reinterpret_cast<PFN_vkVoidFunction>(&vkas::Guarded<&vkas::entry::fn>::call)}
const ProcEntry kProcs[] = {
    VKAS_PROC("vkCreateBuffer", CreateBuffer),
    VKAS_PROC("vkDestroyBuffer", DestroyBuffer),
    VKAS_PROC("vkGetBufferMemoryRequirements", GetBufferMemoryRequirements),
    VKAS_PROC("vkAllocateMemory", AllocateMemory),
    VKAS_PROC("vkFreeMemory", FreeMemory),
    VKAS_PROC("vkBindBufferMemory", BindBufferMemory),
    VKAS_PROC("vkMapMemory", MapMemory),
    VKAS_PROC("vkUnmapMemory", UnmapMemory),
    VKAS_PROC("vkGetBufferDeviceAddress", GetBufferDeviceAddress),
    VKAS_PROC("vkGetBufferDeviceAddressKHR", GetBufferDeviceAddress),
    VKAS_PROC("vkDestroyDevice", DestroyDevice),
    VKAS_PROC("vkCreateDeferredOperationKHR", CreateDeferredOperationKHR),
    VKAS_PROC("vkDestroyDeferredOperationKHR", DestroyDeferredOperationKHR),
    VKAS_PROC("vkGetDeferredOperationMaxConcurrencyKHR", GetDeferredOperationMaxConcurrencyKHR),
    VKAS_PROC("vkGetDeferredOperationResultKHR", GetDeferredOperationResultKHR),
    VKAS_PROC("vkDeferredOperationJoinKHR", DeferredOperationJoinKHR),
    VKAS_PROC("vkGetAccelerationStructureBuildSizesKHR", GetAccelerationStructureBuildSizesKHR),
    VKAS_PROC("vkCreateAccelerationStructureKHR", CreateAccelerationStructureKHR),
    VKAS_PROC("vkDestroyAccelerationStructureKHR", DestroyAccelerationStructureKHR),
    VKAS_PROC("vkGetAccelerationStructureDeviceAddressKHR", GetAccelerationStructureDeviceAddressKHR),
    VKAS_PROC("vkBuildAccelerationStructuresKHR", BuildAccelerationStructuresKHR),
    VKAS_PROC("vkCopyAccelerationStructureKHR", CopyAccelerationStructureKHR),
    VKAS_PROC("vkCopyAccelerationStructureToMemoryKHR", CopyAccelerationStructureToMemoryKHR),
    VKAS_PROC("vkCopyMemoryToAccelerationStructureKHR", CopyMemoryToAccelerationStructureKHR),
    VKAS_PROC("vkWriteAccelerationStructuresPropertiesKHR", WriteAccelerationStructuresPropertiesKHR),
    VKAS_PROC("vkGetDeviceAccelerationStructureCompatibilityKHR", GetDeviceAccelerationStructureCompatibilityKHR),
    // VK_EXT_opacity_micromap: the host commands (the vkCmd* ones need a device, like the structures' vkCmd*).
    VKAS_PROC("vkCreateMicromapEXT", CreateMicromapEXT),
    VKAS_PROC("vkDestroyMicromapEXT", DestroyMicromapEXT),
    VKAS_PROC("vkGetMicromapBuildSizesEXT", GetMicromapBuildSizesEXT),
    VKAS_PROC("vkBuildMicromapsEXT", BuildMicromapsEXT),
    VKAS_PROC("vkCopyMicromapEXT", CopyMicromapEXT),
    VKAS_PROC("vkCopyMicromapToMemoryEXT", CopyMicromapToMemoryEXT),
    VKAS_PROC("vkCopyMemoryToMicromapEXT", CopyMemoryToMicromapEXT),
    VKAS_PROC("vkWriteMicromapsPropertiesEXT", WriteMicromapsPropertiesEXT),
    VKAS_PROC("vkGetDeviceMicromapCompatibilityEXT", GetDeviceMicromapCompatibilityEXT),
};
#undef VKAS_PROC

}  // namespace

extern "C" VKAS_API PFN_vkVoidFunction vkasGetDeviceProcAddr(VkDevice device, const char* pName) {
    if (!vkas::Device::fromHandle(device) || !pName) return nullptr;
    if (std::strcmp(pName, "vkGetDeviceProcAddr") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(&vkasGetDeviceProcAddr);
    for (const ProcEntry& e : kProcs)
        if (std::strcmp(pName, e.name) == 0) return e.function;
    return nullptr;
}

extern "C" VKAS_API void vkasGetAccelerationStructureFeatures(
    VkDevice, VkPhysicalDeviceAccelerationStructureFeaturesKHR* pFeatures) {
    if (!pFeatures) return;
    pFeatures->accelerationStructure = VK_TRUE;
    pFeatures->accelerationStructureCaptureReplay = VK_FALSE;
    pFeatures->accelerationStructureIndirectBuild = VK_FALSE;
    pFeatures->accelerationStructureHostCommands = VK_TRUE;
    pFeatures->descriptorBindingAccelerationStructureUpdateAfterBind = VK_FALSE;
    // Extension feature structures the application chained, as vkGetPhysicalDeviceFeatures2 would fill them.
    vkas::forEachInChain<VkBaseOutStructure>(pFeatures->pNext, [](VkBaseOutStructure* s) {
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_LINEAR_SWEPT_SPHERES_FEATURES_NV) {
            auto* f = reinterpret_cast<VkPhysicalDeviceRayTracingLinearSweptSpheresFeaturesNV*>(s);
            f->spheres = VK_TRUE;
            f->linearSweptSpheres = VK_TRUE;
        }
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_FEATURES_EXT) {
            auto* f = reinterpret_cast<VkPhysicalDeviceOpacityMicromapFeaturesEXT*>(s);
            f->micromap = VK_TRUE;
            f->micromapCaptureReplay = VK_FALSE;
            f->micromapHostCommands = VK_TRUE;
        }
    });
}

extern "C" VKAS_API void vkasGetAccelerationStructureProperties(
    VkDevice, VkPhysicalDeviceAccelerationStructurePropertiesKHR* pProperties) {
    if (!pProperties) return;
    namespace l = vkas::limits;
    pProperties->maxGeometryCount = l::kMaxGeometryCount;
    pProperties->maxInstanceCount = l::kMaxInstanceCount;
    pProperties->maxPrimitiveCount = l::kMaxPrimitiveCount;
    pProperties->maxPerStageDescriptorAccelerationStructures = l::kMaxPerStageDescriptorAccelerationStructures;
    pProperties->maxPerStageDescriptorUpdateAfterBindAccelerationStructures = 0;
    pProperties->maxDescriptorSetAccelerationStructures = l::kMaxDescriptorSetAccelerationStructures;
    pProperties->maxDescriptorSetUpdateAfterBindAccelerationStructures = 0;
    pProperties->minAccelerationStructureScratchOffsetAlignment = l::kMinScratchOffsetAlignment;
    // Extension property structures the application chained, as vkGetPhysicalDeviceProperties2 would fill them.
    vkas::forEachInChain<VkBaseOutStructure>(pProperties->pNext, [](VkBaseOutStructure* s) {
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_PROPERTIES_EXT) {
            auto* p = reinterpret_cast<VkPhysicalDeviceOpacityMicromapPropertiesEXT*>(s);
            p->maxOpacity2StateSubdivisionLevel = vkas::format::kMaxOpacity2StateSubdivisionLevel;
            p->maxOpacity4StateSubdivisionLevel = vkas::format::kMaxOpacity4StateSubdivisionLevel;
        }
    });
}

extern "C" VKAS_API void vkasGetFormatProperties(VkDevice, VkFormat format, VkFormatProperties* pFormatProperties) {
    if (!pFormatProperties) return;
    std::memset(pFormatProperties, 0, sizeof *pFormatProperties);
    if (vkas::vertexFormatInfo(format))
        pFormatProperties->bufferFeatures = VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR;
}
