// vkas_kit::Device: a vkas device (vkasCreateDevice) with its command table (device_commands.hpp), destroyed with it.
#pragma once

#include <cstdint>
#include <stdexcept>

#include "device_commands.hpp"

namespace vkas_kit {

struct DeviceOptions {
    bool validation = true;     // VkasDeviceCreateInfo::disableValidation is its negation
    uint32_t workerThreads = 0; // VkasDeviceCreateInfo::workerThreadCount (0: all cores)
    PFN_vkDebugUtilsMessengerCallbackEXT messenger = nullptr;  // NULL: vkas prints its messages to stderr
    void* messengerUserData = nullptr;
};

// vkasCreateDevice failed: result() is what it returned. what(): "vkasCreateDevice failed (VkResult N)".
class DeviceError : public std::runtime_error {
public:
    explicit DeviceError(VkResult result);
    VkResult result() const { return result_; }

private:
    VkResult result_;
};

// Owns a vkas device and its commands. Not copyable. The constructor throws DeviceError or MissingCommand (the
// device is then destroyed).
class Device {
public:
    explicit Device(const DeviceOptions& options);
    ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    VkDevice handle() const { return device_; }
    const Commands& commands() const { return commands_; }

private:
    VkDevice device_ = VK_NULL_HANDLE;
    Commands commands_;
};

}  // namespace vkas_kit
