// vkas_kit::Device: vkasCreateDevice from DeviceOptions, the command table loaded, vkasDestroyDevice.
#include "device.hpp"

#include <string>

namespace vkas_kit {

DeviceError::DeviceError(VkResult result)
    : std::runtime_error("vkasCreateDevice failed (VkResult " + std::to_string(int(result)) + ")"), result_(result) {}

Device::Device(const DeviceOptions& options) {
    VkasDeviceCreateInfo info{};
    info.disableValidation = options.validation ? VK_FALSE : VK_TRUE;
    info.pfnMessenger = options.messenger;
    info.pMessengerUserData = options.messengerUserData;
    info.workerThreadCount = options.workerThreads;
    const VkResult result = vkasCreateDevice(&info, &device_);
    if (result != VK_SUCCESS) throw DeviceError(result);
    try {
        commands_.load(device_);
    } catch (...) {
        vkasDestroyDevice(device_);
        throw;
    }
}

Device::~Device() { vkasDestroyDevice(device_); }

}  // namespace vkas_kit
