#include "info_command.hpp"

#include <cstdio>
#include <thread>

#include "vk_context.hpp"
#include "vk_strings.hpp"

namespace vkas_tool {
namespace {

const char* yesNo(VkBool32 b) { return b ? "yes" : "no"; }

// Vulkan commands of VK_KHR_acceleration_structure, VK_EXT_opacity_micromap, VK_KHR_deferred_host_operations and the memory commands an
// application needs with them: `vkas info` says which of them this vkas implements.
const char* const kCommands[] = {
    "vkGetDeviceProcAddr",
    "vkDestroyDevice",
    "vkCreateBuffer",
    "vkDestroyBuffer",
    "vkGetBufferMemoryRequirements",
    "vkAllocateMemory",
    "vkFreeMemory",
    "vkBindBufferMemory",
    "vkMapMemory",
    "vkUnmapMemory",
    "vkGetBufferDeviceAddress",
    "vkGetBufferDeviceAddressKHR",
    "vkGetAccelerationStructureBuildSizesKHR",
    "vkCreateAccelerationStructureKHR",
    "vkDestroyAccelerationStructureKHR",
    "vkGetAccelerationStructureDeviceAddressKHR",
    "vkBuildAccelerationStructuresKHR",
    "vkCopyAccelerationStructureKHR",
    "vkCopyAccelerationStructureToMemoryKHR",
    "vkCopyMemoryToAccelerationStructureKHR",
    "vkWriteAccelerationStructuresPropertiesKHR",
    "vkGetDeviceAccelerationStructureCompatibilityKHR",
    "vkCreateMicromapEXT",
    "vkDestroyMicromapEXT",
    "vkGetMicromapBuildSizesEXT",
    "vkBuildMicromapsEXT",
    "vkCopyMicromapEXT",
    "vkCopyMicromapToMemoryEXT",
    "vkCopyMemoryToMicromapEXT",
    "vkWriteMicromapsPropertiesEXT",
    "vkGetDeviceMicromapCompatibilityEXT",
    "vkCreateDeferredOperationKHR",
    "vkDestroyDeferredOperationKHR",
    "vkGetDeferredOperationMaxConcurrencyKHR",
    "vkGetDeferredOperationResultKHR",
    "vkDeferredOperationJoinKHR",
};

}  // namespace

int runInfo(const InfoOptions& options) {
    VkContext ctx(DeviceOptions{});
    VkDevice dev = ctx.device();

    std::printf("vkas %d.%d.%d (Vulkan headers 1.%d.%d)\n", VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR,
                VKAS_VERSION_PATCH, VK_API_VERSION_MINOR(VK_HEADER_VERSION_COMPLETE), VK_HEADER_VERSION);
    std::printf("host threads: %u hardware threads; ray query state: %d bytes\n",
                std::thread::hardware_concurrency(), VKAS_RAY_QUERY_SIZE);

    VkPhysicalDeviceOpacityMicromapFeaturesEXT omm{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_FEATURES_EXT};
    VkPhysicalDeviceRayTracingLinearSweptSpheresFeaturesNV lss{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_LINEAR_SWEPT_SPHERES_FEATURES_NV, &omm};
    VkPhysicalDeviceAccelerationStructureFeaturesKHR f{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &lss};
    vkasGetAccelerationStructureFeatures(dev, &f);
    std::printf("\nfeatures (VkPhysicalDeviceAccelerationStructureFeaturesKHR)\n");
    std::printf("  accelerationStructure                                  %s\n", yesNo(f.accelerationStructure));
    std::printf("  accelerationStructureCaptureReplay                     %s\n",
                yesNo(f.accelerationStructureCaptureReplay));
    std::printf("  accelerationStructureIndirectBuild                     %s\n",
                yesNo(f.accelerationStructureIndirectBuild));
    std::printf("  accelerationStructureHostCommands                      %s\n",
                yesNo(f.accelerationStructureHostCommands));
    std::printf("  descriptorBindingAccelerationStructureUpdateAfterBind  %s\n",
                yesNo(f.descriptorBindingAccelerationStructureUpdateAfterBind));

    VkPhysicalDeviceOpacityMicromapPropertiesEXT ommLimits{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_PROPERTIES_EXT};
    VkPhysicalDeviceAccelerationStructurePropertiesKHR p{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR, &ommLimits};
    vkasGetAccelerationStructureProperties(dev, &p);
    std::printf("\nfeatures (VkPhysicalDeviceRayTracingLinearSweptSpheresFeaturesNV)\n");
    std::printf("  spheres                                                %s\n", yesNo(lss.spheres));
    std::printf("  linearSweptSpheres                                     %s\n", yesNo(lss.linearSweptSpheres));
    std::printf("\nfeatures (VkPhysicalDeviceOpacityMicromapFeaturesEXT)\n");
    std::printf("  micromap                                               %s\n", yesNo(omm.micromap));
    std::printf("  micromapCaptureReplay                                  %s\n", yesNo(omm.micromapCaptureReplay));
    std::printf("  micromapHostCommands                                   %s\n", yesNo(omm.micromapHostCommands));
    std::printf("\ngeometry and structure kinds: triangles, AABBs (ray queries, vkasTraceRaysProcedural), spheres and "
                "linear swept spheres (VK_NV_ray_tracing_linear_swept_spheres), motion instances and motion triangles "
                "(VK_NV_ray_tracing_motion_blur, vkasRayQueryInitializeMotion), position fetch "
                "(VK_KHR_ray_tracing_position_fetch)\n");

    std::printf("\nlimits (VkPhysicalDeviceAccelerationStructurePropertiesKHR)\n");
    std::printf("  maxGeometryCount                                            %llu\n",
                static_cast<unsigned long long>(p.maxGeometryCount));
    std::printf("  maxInstanceCount                                            %llu\n",
                static_cast<unsigned long long>(p.maxInstanceCount));
    std::printf("  maxPrimitiveCount                                           %llu\n",
                static_cast<unsigned long long>(p.maxPrimitiveCount));
    std::printf("  maxPerStageDescriptorAccelerationStructures                 %u\n",
                p.maxPerStageDescriptorAccelerationStructures);
    std::printf("  maxPerStageDescriptorUpdateAfterBindAccelerationStructures  %u\n",
                p.maxPerStageDescriptorUpdateAfterBindAccelerationStructures);
    std::printf("  maxDescriptorSetAccelerationStructures                      %u\n",
                p.maxDescriptorSetAccelerationStructures);
    std::printf("  maxDescriptorSetUpdateAfterBindAccelerationStructures       %u\n",
                p.maxDescriptorSetUpdateAfterBindAccelerationStructures);
    std::printf("  minAccelerationStructureScratchOffsetAlignment              %u\n",
                p.minAccelerationStructureScratchOffsetAlignment);
    std::printf("\nlimits (VkPhysicalDeviceOpacityMicromapPropertiesEXT)\n");
    std::printf("  maxOpacity2StateSubdivisionLevel                            %u\n",
                ommLimits.maxOpacity2StateSubdivisionLevel);
    std::printf("  maxOpacity4StateSubdivisionLevel                            %u\n",
                ommLimits.maxOpacity4StateSubdivisionLevel);

    // Every core format (VK_FORMAT_R4G4_UNORM_PACK8 .. VK_FORMAT_ASTC_12x12_SRGB_BLOCK).
    std::printf("\nvertex formats (VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR)\n");
    unsigned supported = 0;
    for (int value = VK_FORMAT_R4G4_UNORM_PACK8; value <= VK_FORMAT_ASTC_12x12_SRGB_BLOCK; ++value) {
        VkFormat format = static_cast<VkFormat>(value);
        VkFormatProperties fp{};
        vkasGetFormatProperties(dev, format, &fp);
        bool ok = (fp.bufferFeatures & VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR) != 0;
        supported += ok;
        if (ok || options.allFormats)
            std::printf("  %-40s %s\n", formatName(format).c_str(), ok ? "supported" : "-");
    }
    std::printf("  %u supported\n", supported);

    std::printf("\ncommands (vkasGetDeviceProcAddr)\n");
    for (const char* name : kCommands)
        std::printf("  %-50s %s\n", name, vkasGetDeviceProcAddr(dev, name) ? "yes" : "-");
    return 0;
}

}  // namespace vkas_tool
