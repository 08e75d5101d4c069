// The lifetime of the objects behind the handles (objects.hpp): their own host allocation (VK_SYSTEM_ALLOCATION_SCOPE_OBJECT)
// and its release, and the state a structure is left in when a command that writes it fails part-way.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstring>
#include <new>

#include "api/objects.hpp"
#include "engine/format/layout.hpp"

namespace vkas {

// The object's own host allocation (scope OBJECT): through the application's VkAllocationCallbacks when it gives
// them, otherwise through its device's (vkasCreateDeviceWithAllocator), otherwise operator new. `allocator` keeps
// what the application gave (for the destroy command's checks, 03434/03435 and the like); `memoryCallbacks` what
// the object's memory came from, so that it is freed the same way, by vkDestroy* or vkasDestroyDevice.
// Returns nullptr when the allocation fails (VK_ERROR_OUT_OF_HOST_MEMORY).
template <class T>
T* createObject(const VkAllocationCallbacks* allocator, const VkAllocationCallbacks& deviceCallbacks) {
    VkAllocationCallbacks callbacks{};
    if (allocator && allocator->pfnAllocation)
        callbacks = *allocator;
    else if (deviceCallbacks.pfnAllocation)
        callbacks = deviceCallbacks;
    void* p = nullptr;
    if (callbacks.pfnAllocation)
        p = callbacks.pfnAllocation(callbacks.pUserData, sizeof(T), alignof(T), VK_SYSTEM_ALLOCATION_SCOPE_OBJECT);
    else
        p = ::operator new(sizeof(T), std::nothrow);
    if (!p) return nullptr;
    T* object;
    try {
        object = new (p) T;
    } catch (...) {
        if (callbacks.pfnAllocation)
            callbacks.pfnFree(callbacks.pUserData, p);
        else
            ::operator delete(p);
        throw;
    }
    if (allocator && allocator->pfnAllocation) object->allocator = *allocator;
    object->memoryCallbacks = callbacks;
    return object;
}

template <class T>
void destroyObject(T* object) noexcept {
    if (!object) return;
    const VkAllocationCallbacks callbacks = object->memoryCallbacks;
    object->magic = ObjectMagic::Dead;
    object->~T();
    if (callbacks.pfnFree)
        callbacks.pfnFree(callbacks.pUserData, object);
    else
        ::operator delete(object);
}

// A build, copy or deserialization that failed part-way leaves its destination unconstructed: the header no longer
// names a structure, so nothing (instances referring to it, copies, traversal) reads the half-written contents.
inline void markUnconstructed(AccelerationStructure& as) noexcept {
    as.constructed = false;
    if (std::byte* block = as.block(); block && as.size >= sizeof(format::Header))
        std::memset(block + offsetof(format::Header, magic), 0, sizeof(format::Header::magic));
}

}  // namespace vkas
