#include "api/device.hpp"

#include "api/deferred_operation.hpp"
#include "api/command_memory.hpp"
#include "api/exception_result.hpp"
#include "api/object_lifetime.hpp"

#include "api/validate/device_calls.hpp"
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
// The live devices of the process, a list through the devices themselves (registering one allocates nothing). Each
// device keeps the set of its live objects (Device::objects_, in the device's memory); a handle is looked up there
// before it is dereferenced, so an unknown, destroyed or foreign handle is recognised without touching the memory it
// points to.
std::shared_mutex gRegistryMutex;  // guards the list; taken before any device's mutex_, never after
Device* gDevices = nullptr;
// Counts the changes of the devices and their live sets: a lookup cached at one value is still the registry's answer
// while the count has not moved (ray_query_api.cpp caches its last top-level lookup per thread).
std::atomic<uint64_t> gRegistryGeneration{0};
}  // namespace

Device::Device(const VkasDeviceCreateInfo& info, const VkAllocationCallbacks& allocator)
    : info_(info),
      allocator_(allocator),
      command_(allocator, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND),
      object_(allocator, VK_SYSTEM_ALLOCATION_SCOPE_OBJECT),
      device_(allocator, VK_SYSTEM_ALLOCATION_SCOPE_DEVICE),
      objects_(HostAllocator<const void*>(deviceMemory())) {
    std::unique_lock lock(gRegistryMutex);
    nextDevice_ = gDevices;
    gDevices = this;
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
}

Device::~Device() {
    magic_ = 0;
    std::unique_lock lock(gRegistryMutex);
    for (Device** d = &gDevices; *d; d = &(*d)->nextDevice_)
        if (*d == this) {
            *d = nextDevice_;
            break;
        }
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
}

Device* Device::fromHandle(VkDevice device) {
    if (!device) return nullptr;
    std::shared_lock lock(gRegistryMutex);
    for (Device* d = gDevices; d; d = d->nextDevice_)
        if (static_cast<const void*>(d) == static_cast<const void*>(device)) return d;
    return nullptr;
}

uint64_t Device::registryGeneration() { return gRegistryGeneration.load(std::memory_order_acquire); }

Device* Device::ownerOf(const void* object) {
    if (!object) return nullptr;
    std::shared_lock lock(gRegistryMutex);
    for (Device* d = gDevices; d; d = d->nextDevice_)
        if (d->isLive(object)) return d;
    return nullptr;
}

ThreadPool& Device::workers() {
    std::lock_guard lock(workersMutex_);
    if (!workers_) {
        uint32_t n = info_.workerThreadCount;
        if (n == 0) n = std::max(1u, std::thread::hardware_concurrency());
        ScopedHostMemory scope(deviceMemory());  // the pool and its thread list live as long as the device
        workers_ = makeHostUnique<ThreadPool>(n);
    }
    return *workers_;
}

bool Device::track(const void* object) noexcept {
    // Out of memory leaves the set as it was.
    try {
        std::lock_guard lock(mutex_);
        objects_.insert(object);
        gRegistryGeneration.fetch_add(1, std::memory_order_release);
    } catch (...) {
        return false;
    }
    return true;
}

void Device::untrack(const void* object) {
    std::lock_guard lock(mutex_);
    objects_.erase(object);
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
}

bool Device::isLive(const void* object) const {
    std::lock_guard lock(mutex_);
    return objects_.count(object) != 0;
}

HostUnorderedMap<uint64_t, const AccelerationStructure*> Device::bottomLevelsByAddress() const {
    HostUnorderedMap<uint64_t, const AccelerationStructure*> byAddress;
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
    gRegistryGeneration.fetch_add(1, std::memory_order_release);
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

std::pmr::memory_resource* deviceCommandMemory(VkDevice device) noexcept {
    Device* dev = Device::fromHandle(device);
    return dev ? dev->commandMemory() : nullptr;
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

namespace {
VkResult createDevice(const VkasDeviceCreateInfo* pCreateInfo, const VkAllocationCallbacks* pAllocator,
                      VkDevice* pDevice) {
    if (!pDevice) return VK_ERROR_INITIALIZATION_FAILED;
    VkasDeviceCreateInfo info{};
    if (pCreateInfo) info = *pCreateInfo;
    VkAllocationCallbacks callbacks{};
    if (pAllocator && pAllocator->pfnAllocation && pAllocator->pfnFree) callbacks = *pAllocator;
    vkas::CallbacksResource memory(callbacks, VK_SYSTEM_ALLOCATION_SCOPE_DEVICE);
    std::pmr::memory_resource* r = memory.orElse(std::pmr::new_delete_resource());
    void* p = r->allocate(sizeof(Device), alignof(Device));  // throws bad_alloc: VK_ERROR_OUT_OF_HOST_MEMORY
    Device* device;
    try {
        device = new (p) Device(info, callbacks);
    } catch (...) {
        r->deallocate(p, sizeof(Device), alignof(Device));
        throw;
    }
    *pDevice = device->handle();
    return VK_SUCCESS;
}
}  // namespace

extern "C" VKAS_API VkResult vkasCreateDevice(const VkasDeviceCreateInfo* pCreateInfo, VkDevice* pDevice) {
    return vkas::guarded([&] { return createDevice(pCreateInfo, nullptr, pDevice); });
}

extern "C" VKAS_API VkResult vkasCreateDeviceWithAllocator(const VkasDeviceCreateInfo* pCreateInfo,
                                                           const VkAllocationCallbacks* pAllocator,
                                                           VkDevice* pDevice) {
    return vkas::guarded([&] { return createDevice(pCreateInfo, pAllocator, pDevice); });
}

extern "C" VKAS_API void vkasDestroyDevice(VkDevice device) {
    Device* dev = Device::fromHandle(device);
    if (!dev) return;
    vkas::ScopedHostMemory scope(dev->commandMemory());
    size_t leaked = dev->releaseAll();
    if (leaked != 0 && dev->validationEnabled()) try {
        vkas::Validator v(dev, "vkDestroyDevice");
        vkas::reportLeakedObjects(v, leaked);
    } catch (...) {  // the message could not be allocated: the device is destroyed all the same
    }
    const VkAllocationCallbacks callbacks = dev->allocator();
    dev->~Device();
    vkas::CallbacksResource memory(callbacks, VK_SYSTEM_ALLOCATION_SCOPE_DEVICE);
    memory.orElse(std::pmr::new_delete_resource())->deallocate(dev, sizeof(Device), alignof(Device));
}
