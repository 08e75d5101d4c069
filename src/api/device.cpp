#include "api/device.hpp"

#include "engine/format.hpp"

#include <new>
#include <thread>

namespace vkas {

Device::Device(const VkasDeviceCreateInfo& info) : info_(info) {}

Device* Device::fromHandle(VkDevice device) {
    auto* d = reinterpret_cast<Device*>(device);
    return (d && d->magic_ == kMagic) ? d : nullptr;
}

ThreadPool& Device::workers() {
    std::call_once(workersOnce_, [&] {
        uint32_t n = info_.workerThreadCount;
        if (n == 0) n = std::max(1u, std::thread::hardware_concurrency());
        workers_ = std::make_unique<ThreadPool>(n);
    });
    return *workers_;
}

void Device::track(const void* object) {
    std::lock_guard lock(mutex_);
    objects_.insert(object);
}

void Device::untrack(const void* object) {
    std::lock_guard lock(mutex_);
    objects_.erase(object);
}

bool Device::isLive(const void* object) const {
    std::lock_guard lock(mutex_);
    return objects_.count(object) != 0;
}

const std::byte* resolveAccelerationStructure(uint64_t reference) {
    auto* as = reinterpret_cast<const AccelerationStructure*>(reference);
    if (!as || as->magic != ObjectMagic::AccelerationStructure) return nullptr;
    const std::byte* block = as->block();
    if (!block || format::header(block)->magic != format::kMagic) return nullptr;  // never built
    return block;
}

}  // namespace vkas

using vkas::Device;

extern "C" VKAS_API VkResult vkasCreateDevice(const VkasDeviceCreateInfo* pCreateInfo, VkDevice* pDevice) {
    if (!pDevice) return VK_ERROR_INITIALIZATION_FAILED;
    VkasDeviceCreateInfo info{};
    if (pCreateInfo) info = *pCreateInfo;
    auto* device = new (std::nothrow) Device(info);
    if (!device) return VK_ERROR_OUT_OF_HOST_MEMORY;
    *pDevice = device->handle();
    return VK_SUCCESS;
}

extern "C" VKAS_API void vkasDestroyDevice(VkDevice device) {
    delete Device::fromHandle(device);
}
