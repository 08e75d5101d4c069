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

VkContext::VkContext(const DeviceOptions& options) : collectMessages_(options.collectMessages) {
    vkas_kit::DeviceOptions kit;
    kit.validation = options.validation;
    kit.workerThreads = options.workerThreads;
    kit.messenger = &VkContext::messenger;
    kit.messengerUserData = this;
    try {
        device_.emplace(kit);
    } catch (const vkas_kit::DeviceError& e) {
        throw VkError("vkasCreateDevice", e.result());
    } catch (const vkas_kit::MissingCommand& e) {
        throw VkError("vkasGetDeviceProcAddr(\"" + e.command() + "\")", VK_ERROR_FEATURE_NOT_PRESENT);
    }
    static_cast<vkas_kit::Commands&>(*this) = device_->commands();
}

VkContext::~VkContext() = default;

}  // namespace vkas_tool
