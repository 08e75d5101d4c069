// The tool's vkas device and the Vulkan commands it fetched with vkasGetDeviceProcAddr.
#pragma once

#include <stdexcept>
#include <string>

#include <vkas/vkas.h>

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

// Owns a vkas device and its command table. Not copyable.
class VkContext {
public:
    explicit VkContext(const DeviceOptions& options);
    ~VkContext();
    VkContext(const VkContext&) = delete;
    VkContext& operator=(const VkContext&) = delete;

    VkDevice device() const { return device_; }
    // Validation messages reported through the messenger so far.
    uint32_t validationMessages() const { return validationMessages_; }
    // The last message when DeviceOptions::collectMessages is set ("" when none).
    const std::string& lastMessage() const { return lastMessage_; }

    PFN_vkCreateBuffer vkCreateBuffer = nullptr;
    PFN_vkDestroyBuffer vkDestroyBuffer = nullptr;
    PFN_vkGetBufferMemoryRequirements vkGetBufferMemoryRequirements = nullptr;
    PFN_vkAllocateMemory vkAllocateMemory = nullptr;
    PFN_vkFreeMemory vkFreeMemory = nullptr;
    PFN_vkBindBufferMemory vkBindBufferMemory = nullptr;
    PFN_vkMapMemory vkMapMemory = nullptr;
    PFN_vkUnmapMemory vkUnmapMemory = nullptr;
    PFN_vkGetBufferDeviceAddress vkGetBufferDeviceAddress = nullptr;
    PFN_vkGetAccelerationStructureBuildSizesKHR vkGetAccelerationStructureBuildSizesKHR = nullptr;
    PFN_vkCreateAccelerationStructureKHR vkCreateAccelerationStructureKHR = nullptr;
    PFN_vkDestroyAccelerationStructureKHR vkDestroyAccelerationStructureKHR = nullptr;
    PFN_vkGetAccelerationStructureDeviceAddressKHR vkGetAccelerationStructureDeviceAddressKHR = nullptr;
    PFN_vkBuildAccelerationStructuresKHR vkBuildAccelerationStructuresKHR = nullptr;
    PFN_vkWriteAccelerationStructuresPropertiesKHR vkWriteAccelerationStructuresPropertiesKHR = nullptr;
    PFN_vkCopyAccelerationStructureKHR vkCopyAccelerationStructureKHR = nullptr;
    PFN_vkCopyAccelerationStructureToMemoryKHR vkCopyAccelerationStructureToMemoryKHR = nullptr;
    PFN_vkCopyMemoryToAccelerationStructureKHR vkCopyMemoryToAccelerationStructureKHR = nullptr;
    PFN_vkGetDeviceAccelerationStructureCompatibilityKHR vkGetDeviceAccelerationStructureCompatibilityKHR = nullptr;

private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                    void* userData);
    template <typename Pfn>
    void load(Pfn& pfn, const char* name);

    VkDevice device_ = VK_NULL_HANDLE;
    uint32_t validationMessages_ = 0;
    bool collectMessages_ = false;
    std::string lastMessage_;
};

}  // namespace vkas_tool
