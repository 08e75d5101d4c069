#include "api/device.hpp"

#include "api/deferred_operation.hpp"

#include "api/validation.hpp"
#include "engine/format.hpp"

#include <cstdlib>
#include <new>
#include <vector>
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

AccelerationStructure* Device::structureAtAddress(uint64_t address) const {
    if (address == 0) return nullptr;
    std::lock_guard lock(mutex_);
    for (const void* o : objects_) {
        auto* p = static_cast<AccelerationStructure*>(const_cast<void*>(o));
        if (*static_cast<const ObjectMagic*>(o) == ObjectMagic::AccelerationStructure &&
            reinterpret_cast<uintptr_t>(p->block()) == address)
            return p;
    }
    return nullptr;
}

size_t Device::releaseAll() {
    std::lock_guard lock(mutex_);
    std::vector<void*> structures, buffers, memories, operations;
    for (const void* o : objects_) {
        auto* p = const_cast<void*>(o);
        switch (*static_cast<ObjectMagic*>(p)) {
            case ObjectMagic::AccelerationStructure: structures.push_back(p); break;
            case ObjectMagic::Buffer: buffers.push_back(p); break;
            case ObjectMagic::Memory: memories.push_back(p); break;
            case ObjectMagic::DeferredOperation: operations.push_back(p); break;
            default: break;
        }
    }
    for (void* p : operations) {
        static_cast<DeferredOperation*>(p)->magic = ObjectMagic::Dead;
        delete static_cast<DeferredOperation*>(p);
    }
    for (void* p : structures) {
        static_cast<AccelerationStructure*>(p)->magic = ObjectMagic::Dead;
        delete static_cast<AccelerationStructure*>(p);
    }
    for (void* p : buffers) {
        static_cast<Buffer*>(p)->magic = ObjectMagic::Dead;
        delete static_cast<Buffer*>(p);
    }
    for (void* p : memories) {
        auto* m = static_cast<Memory*>(p);
        std::free(m->data);
        m->magic = ObjectMagic::Dead;
        delete m;
    }
    size_t n = objects_.size();
    objects_.clear();
    return n;
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
    Device* dev = Device::fromHandle(device);
    if (!dev) return;
    size_t leaked = dev->releaseAll();
    if (leaked != 0 && dev->validationEnabled()) {
        vkas::Validator v(dev, "vkDestroyDevice");
        v.fail("VUID-vkDestroyDevice-device-05137",
               "%zu objects (buffers, memory or acceleration structures) created from device were not destroyed; "
               "vkas freed them.",
               leaked);
    }
    delete dev;
}
