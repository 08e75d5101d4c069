// The tool's vkas device and the Vulkan commands it fetched with vkasGetDeviceProcAddr (both from vkas_kit, kit/).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include <vkas/vkas.h>

#include "device.hpp"  // kit/

namespace vkas_tool {

// A failed Vulkan or vkas call: what was called and what it returned. main() reports it and exits non-zero.
class VkError : public std::runtime_error {
public:
    VkError(const std::string& what, VkResult result);
    VkResult result() const { return result_; }

private:
    VkResult result_;
};

// Throws VkError when result is not VK_SUCCESS.
void check(VkResult result, const char* what);

struct DeviceOptions {
    bool validation = true;       // vkas checks every command's valid usage (the default)
    uint32_t workerThreads = 0;   // threads for vkasTraceRays; 0 = all cores
    bool collectMessages = false; // keep validation messages (lastMessage()) instead of printing them: a command that
                                  // reports a bad file in one message of its own
};

// Owns a vkas device and its command table (the members vkCreateBuffer etc., vkas_kit::Commands). Not copyable.
class VkContext : public vkas_kit::Commands {
public:
    explicit VkContext(const DeviceOptions& options);
    ~VkContext();
    VkContext(const VkContext&) = delete;
    VkContext& operator=(const VkContext&) = delete;

    VkDevice device() const { return device_->handle(); }
    // Validation messages reported through the messenger so far.
    uint32_t validationMessages() const { return validationMessages_; }
    // The last message when DeviceOptions::collectMessages is set ("" when none).
    const std::string& lastMessage() const { return lastMessage_; }

private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                    void* userData);
    uint32_t validationMessages_ = 0;
    bool collectMessages_ = false;
    std::string lastMessage_;
    std::optional<vkas_kit::Device> device_;  // created last: the messenger may run while it is created
};

}  // namespace vkas_tool
