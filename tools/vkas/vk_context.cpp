#include "vk_context.hpp"

#include <cstdio>

#include "vk_strings.hpp"

namespace vkas_tool {

VkError::VkError(const std::string& what, VkResult result)
    : std::runtime_error(what + " failed: " + resultName(result)), result_(result) {}

void check(VkResult result, const char* what) {
    if (result != VK_SUCCESS) throw VkError(what, result);
}

VKAPI_ATTR VkBool32 VKAPI_CALL VkContext::messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT, 
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                    void* userData) {
    auto* self = static_cast<VkContext*>(userData);
    const char* level = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)     ? "error"
                        : (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) ? "warning"
                                                                                      : "info";
    if (severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT))
        ++self->validationMessages_;
    if (self->collectMessages_) {
        self->lastMessage_ = data && data->pMessage ? data->pMessage : "(no message)";
        return VK_FALSE;
    }
    // vkas's pMessage already names the VUID and the command ("Validation Error: [ VUID-... ] | vkCmd(): ...").
    std::fprintf(stderr, "vkas (%s): %s\n", level, data && data->pMessage ? data->pMessage : "(no message)");
    return VK_FALSE;
}

template <typename Pfn>
void VkContext::load(Pfn& pfn, const char* name) {
    pfn = reinterpret_cast<Pfn>(vkasGetDeviceProcAddr(device_, name));
    if (!pfn) throw VkError(std::string("vkasGetDeviceProcAddr(\"") + name + "\")", VK_ERROR_FEATURE_NOT_PRESENT);
}

VkContext::VkContext(const DeviceOptions& options) : collectMessages_(options.collectMessages) {
    VkasDeviceCreateInfo info{};
    info.disableValidation = options.validation ? VK_FALSE : VK_TRUE;
    info.pfnMessenger = &VkContext::messenger;
    info.pMessengerUserData = this;
    info.workerThreadCount = options.workerThreads;
    check(vkasCreateDevice(&info, &device_), "vkasCreateDevice");
    try {
        load(vkCreateBuffer, "vkCreateBuffer");
        load(vkDestroyBuffer, "vkDestroyBuffer");
        load(vkGetBufferMemoryRequirements, "vkGetBufferMemoryRequirements");
        load(vkAllocateMemory, "vkAllocateMemory");
        load(vkFreeMemory, "vkFreeMemory");
        load(vkBindBufferMemory, "vkBindBufferMemory");
        load(vkMapMemory, "vkMapMemory");
        load(vkUnmapMemory, "vkUnmapMemory");
        load(vkGetBufferDeviceAddress, "vkGetBufferDeviceAddress");
        load(vkGetAccelerationStructureBuildSizesKHR, "vkGetAccelerationStructureBuildSizesKHR");
        load(vkCreateAccelerationStructureKHR, "vkCreateAccelerationStructureKHR");
        load(vkDestroyAccelerationStructureKHR, "vkDestroyAccelerationStructureKHR");
        load(vkGetAccelerationStructureDeviceAddressKHR, "vkGetAccelerationStructureDeviceAddressKHR");
        load(vkBuildAccelerationStructuresKHR, "vkBuildAccelerationStructuresKHR");
        load(vkWriteAccelerationStructuresPropertiesKHR, "vkWriteAccelerationStructuresPropertiesKHR");
        load(vkCopyAccelerationStructureKHR, "vkCopyAccelerationStructureKHR");
        load(vkCopyAccelerationStructureToMemoryKHR, "vkCopyAccelerationStructureToMemoryKHR");
        load(vkCopyMemoryToAccelerationStructureKHR, "vkCopyMemoryToAccelerationStructureKHR");
        load(vkGetDeviceAccelerationStructureCompatibilityKHR, "vkGetDeviceAccelerationStructureCompatibilityKHR");
    } catch (...) {
        vkasDestroyDevice(device_);
        throw;
    }
}

VkContext::~VkContext() {
    if (device_ != VK_NULL_HANDLE) vkasDestroyDevice(device_);
}

}  // namespace vkas_tool
