// The vkas device: the dispatchable VkDevice handle, its settings, its live objects and its worker threads.
#pragma once

#include <vulkan/vulkan_core.h>

#include <memory>
#include <memory_resource>
#include <mutex>
#include <unordered_set>

#include "api/host_allocator.hpp"
#include "api/objects.hpp"
#include "api/thread_pool.hpp"
#include "engine/util/host_memory.hpp"
#include "vkas/vkas.h"

namespace vkas {

class Device {
public:
    // `allocator`: the VkAllocationCallbacks of vkasCreateDeviceWithAllocator (zeroed: none). The Device itself
    // lives in memory from them (scope DEVICE) when there are some.
    Device(const VkasDeviceCreateInfo& info, const VkAllocationCallbacks& allocator);
    ~Device();

    // The device's VkAllocationCallbacks (zeroed: none) and the resources over them, one per scope; without
    // callbacks each is std::pmr::new_delete_resource(). commandMemory() is made current for every command of the
    // device that has no pAllocator of its own (api/command_memory.hpp, CommandHostMemory).
    const VkAllocationCallbacks& allocator() const { return allocator_; }
    std::pmr::memory_resource* commandMemory() { return command_.orElse(std::pmr::new_delete_resource()); }
    std::pmr::memory_resource* objectMemory() { return object_.orElse(std::pmr::new_delete_resource()); }
    std::pmr::memory_resource* deviceMemory() { return device_.orElse(std::pmr::new_delete_resource()); }

    // The live device `device` is, or nullptr (unknown or destroyed handles are never dereferenced).
    static Device* fromHandle(VkDevice device);
    // The device that owns the live object `object` (any type), or nullptr when no live object has that handle.
    static Device* ownerOf(const void* object);
    // A number that changes whenever an object or device is registered or unregistered (see ownerOf).
    static uint64_t registryGeneration();
    VkDevice handle() { return reinterpret_cast<VkDevice>(this); }

    bool validationEnabled() const { return !info_.disableValidation; }
    const VkasDeviceCreateInfo& createInfo() const { return info_; }
    ThreadPool& workers();

    // This device's live objects, so validation can recognise unknown, destroyed or wrong-type handles (no
    // process-wide registry: ownerOf asks each live device). track() returns false when the set cannot grow (out of
    // memory): the object is not registered.
    bool track(const void* object) noexcept;
    void untrack(const void* object);
    bool isLive(const void* object) const;
    // Frees every object still alive (destroying a device with live children is invalid usage; reported by
    // vkasDestroyDevice) and returns how many there were.
    size_t releaseAll();

    // The live acceleration structures of this device that can be a top level's bottom levels (created as
    // BOTTOM_LEVEL or GENERIC, bound to memory), by device address (the host address of their block), for
    // deserialization to map handle-array entries to them. Where several alias one address, a BOTTOM_LEVEL one is
    // preferred (they share their bytes, so any of them traces alike).
    // Allocated from the thread's current resource (the command's).
    HostUnorderedMap<uint64_t, const AccelerationStructure*> bottomLevelsByAddress() const;

    template <class T>
    T* live(const void* handle, ObjectMagic magic) const {
        if (!handle || !isLive(handle)) return nullptr;
        T* object = static_cast<T*>(const_cast<void*>(handle));
        return object->magic == magic ? object : nullptr;
    }

private:
    static constexpr uint64_t kMagic = 0x564B41534445564Full;  // "VKASDEVO"
    uint64_t magic_ = kMagic;  // first: the dispatchable handle points here
    VkasDeviceCreateInfo info_;
    VkAllocationCallbacks allocator_{};
    CallbacksResource command_, object_, device_;
    mutable std::mutex mutex_;
    HostUnorderedSet<const void*> objects_;  // from deviceMemory()
    std::mutex workersMutex_;  // not std::call_once: a pool that failed to start (out of memory) is retried
    HostUnique<ThreadPool> workers_;  // from deviceMemory()
    Device* nextDevice_ = nullptr;    // the process's list of live devices (device.cpp)
};

// The block of the bottom-level structure an instance's accelerationStructureReference names (or nullptr).
const std::byte* resolveAccelerationStructure(uint64_t reference);


}  // namespace vkas
