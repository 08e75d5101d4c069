#include "api/device.hpp"

#include "api/deferred_operation.hpp"
#include "api/guard.hpp"

#include "api/validate/validator.hpp"
#include "engine/format/layout.hpp"

#include <atomic>
#include <cstdlib>
#include <shared_mutex>
#include <unordered_map>
#include <new>
#include <vector>
#include <thread>

namespace vkas {

namespace {
// Every live device and object of the process, with the device that owns it (a device owns itself). Handles are
// looked up here before they are dereferenced, so an unknown, destroyed or foreign handle is recognised without
// touching the memory it points to.
std::shared_mutex gRegistryMutex;
// Counts the registry's changes (under the writer lock): a lookup cached at one value is still the registry's answer
// while the count has not moved (ray_query_api.cpp caches its last top-level lookup per thread).
std::atomic<uint64_t> gRegistryGeneration{0};
std::unordered_map<const void*, Device*>& registry() {
    static auto* objects = new std::unordered_map<const void*, Device*>;  // never destroyed: used until exit
    return *objects;
}
}  // namespace

Device::Device(const VkasDeviceCreateInfo& info) : info_(info) {
    std::unique_lock lock(gRegistryMutex);
    registry().emplace(this, this);
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
}

Device::~Device() {
    magic_ = 0;
    std::unique_lock lock(gRegistryMutex);
    registry().erase(this);
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
}

Device* Device::fromHandle(VkDevice device) {
    if (!device) return nullptr;
    std::shared_lock lock(gRegistryMutex);
    auto it = registry().find(device);
    return it != registry().end() && it->second == static_cast<const void*>(device) ? it->second : nullptr;
}

uint64_t Device::registryGeneration() { return gRegistryGeneration.load(std::memory_order_acquire); }

Device* Device::ownerOf(const void* object) {
    if (!object) return nullptr;
    std::shared_lock lock(gRegistryMutex);
    auto it = registry().find(object);
    return it != registry().end() && it->second != object ? it->second : nullptr;
}

ThreadPool& Device::workers() {
    std::lock_guard lock(workersMutex_);
    if (!workers_) {
        uint32_t n = info_.workerThreadCount;
        if (n == 0) n = std::max(1u, std::thread::hardware_concurrency());
        workers_ = std::make_unique<ThreadPool>(n);
    }
    return *workers_;
}

bool Device::track(const void* object) noexcept {
    // Out of memory in either set leaves both as they were.
    try {
        std::unique_lock lock(gRegistryMutex);
        registry()[object] = this;
        gRegistryGeneration.fetch_add(1, std::memory_order_release);
    } catch (...) {
        return false;
    }
    try {
        std::lock_guard lock(mutex_);
        objects_.insert(object);
    } catch (...) {
        std::unique_lock lock(gRegistryMutex);
        registry().erase(object);
        gRegistryGeneration.fetch_add(1, std::memory_order_release);
        return false;
    }
    return true;
}

void Device::untrack(const void* object) {
    {
        std::unique_lock lock(gRegistryMutex);
        registry().erase(object);
        gRegistryGeneration.fetch_add(1, std::memory_order_release);
    }
    std::lock_guard lock(mutex_);
    objects_.erase(object);
}

bool Device::isLive(const void* object) const {
    std::lock_guard lock(mutex_);
    return objects_.count(object) != 0;
}

std::unordered_map<uint64_t, const AccelerationStructure*> Device::bottomLevelsByAddress() const {
    std::unordered_map<uint64_t, const AccelerationStructure*> byAddress;
    std::lock_guard lock(mutex_);
    for (const void* o : objects_) {
        if (*static_cast<const ObjectMagic*>(o) != ObjectMagic::AccelerationStructure) continue;
        const auto* as = static_cast<const AccelerationStructure*>(o);
        const uint64_t address = reinterpret_cast<uintptr_t>(as->block());
        if (address == 0 || as->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) continue;
        auto [it, inserted] = byAddress.emplace(address, as);
        if (!inserted && as->type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR) it->second = as;
    }
    return byAddress;
}

size_t Device::releaseAll() {
    std::lock_guard lock(mutex_);
    {
        std::unique_lock registryLock(gRegistryMutex);
        for (const void* o : objects_) registry().erase(o);
        gRegistryGeneration.fetch_add(1, std::memory_order_release);
    }
    // One pass per type, in dependency order, erasing as it goes; allocates nothing (vkasDestroyDevice cannot
    // fail). Each object is freed the way it was allocated (destroyObject: through its VkAllocationCallbacks, if any).
    const size_t n = objects_.size();
    for (ObjectMagic type : {ObjectMagic::DeferredOperation, ObjectMagic::AccelerationStructure, ObjectMagic::Micromap,
                             ObjectMagic::Buffer, ObjectMagic::Memory}) {
        for (auto it = objects_.begin(); it != objects_.end();) {
            auto* p = const_cast<void*>(*it);
            if (*static_cast<ObjectMagic*>(p) != type) {
                ++it;
                continue;
            }
            it = objects_.erase(it);
            switch (type) {
                case ObjectMagic::DeferredOperation: destroyObject(static_cast<DeferredOperation*>(p)); break;
                case ObjectMagic::AccelerationStructure: destroyObject(static_cast<AccelerationStructure*>(p)); break;
                case ObjectMagic::Micromap: destroyObject(static_cast<Micromap*>(p)); break;
                case ObjectMagic::Buffer: destroyObject(static_cast<Buffer*>(p)); break;
                case ObjectMagic::Memory:
                    std::free(static_cast<Memory*>(p)->data);
                    destroyObject(static_cast<Memory*>(p));
                    break;
                default: break;
            }
        }
    }
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
    return vkas::guarded([&] {
    if (!pDevice) return VK_ERROR_INITIALIZATION_FAILED;
    VkasDeviceCreateInfo info{};
    if (pCreateInfo) info = *pCreateInfo;
    auto* device = new (std::nothrow) Device(info);
    if (!device) return VK_ERROR_OUT_OF_HOST_MEMORY;
    *pDevice = device->handle();
    return VK_SUCCESS;
    });
}

extern "C" VKAS_API void vkasDestroyDevice(VkDevice device) {
    Device* dev = Device::fromHandle(device);
    if (!dev) return;
    size_t leaked = dev->releaseAll();
    if (leaked != 0 && dev->validationEnabled()) {
        vkas::Validator v(dev, "vkDestroyDevice");
        v.fail("VUID-vkDestroyDevice-device-05137",
               "%zu objects (buffers, memory, acceleration structures or micromaps) created from device were not destroyed; "
               "vkas freed them.",
               leaked);
    }
    delete dev;
}
