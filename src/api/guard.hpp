// Exception safety at the API boundary: no C++ exception ever leaves vkas. A failing allocation (std::bad_alloc, or
// std::length_error from a container sized by input) becomes VK_ERROR_OUT_OF_HOST_MEMORY; anything else (an
// exception thrown by an application callback, a thread that could not start) VK_ERROR_UNKNOWN. Every command of the
// proc table and every exported function that may allocate runs through guarded(); work run on joined or worker
// threads catches with the same mapping (deferred_operation.cpp, thread_pool.cpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstring>
#include <exception>
#include <new>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include "api/host_allocator.hpp"
#include "api/objects.hpp"
#include "engine/format/layout.hpp"
#include "engine/util/host_memory.hpp"

namespace vkas {

// The VkResult for the exception being handled; call inside a catch block only.
inline VkResult currentExceptionResult() noexcept {
    try {
        throw;
    } catch (const std::bad_alloc&) {
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    } catch (const std::length_error&) {
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    } catch (...) {
        return VK_ERROR_UNKNOWN;
    }
}

// What a command returns when it failed with an exception: the VkResult above, nothing for void commands, 0 for a
// VkDeviceAddress, a count or a VkBool32.
template <class R>
R failureValue(VkResult result) noexcept {
    if constexpr (std::is_same_v<R, VkResult>)
        return result;
    else if constexpr (!std::is_void_v<R>)
        return R{};
}

// Runs fn() and returns its result, or failureValue() when it throws.
template <class Fn>
auto guarded(Fn&& fn) noexcept -> decltype(fn()) {
    using R = decltype(fn());
    try {
        return fn();
    } catch (...) {
        return failureValue<R>(currentExceptionResult());
    }
}

// The host memory of a command's temporaries (scope COMMAND): its own pAllocator when it has one (its last
// `const VkAllocationCallbacks*` parameter, not NULL), otherwise its device's (vkasCreateDeviceWithAllocator),
// otherwise operator new. Made the thread's current resource (engine/util/host_memory.hpp) for the whole command.
std::pmr::memory_resource* deviceCommandMemory(VkDevice device) noexcept;  // device.cpp; nullptr: none

template <class... A>
class CommandHostMemory {
  public:
    explicit CommandHostMemory(const A&... args) noexcept {
        std::pmr::memory_resource* r = nullptr;
        const VkAllocationCallbacks* given = nullptr;
        VkDevice device = VK_NULL_HANDLE;
        (take(args, given, device), ...);
        if (given && given->pfnAllocation && given->pfnFree) {
            own_ = CallbacksResource(*given, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND);
            r = &own_;
        } else if (device) {
            r = deviceCommandMemory(device);
        }
        scope_.emplace(r);
    }

  private:
    template <class T>
    static void take(const T& arg, const VkAllocationCallbacks*& given, VkDevice& device) {
        if constexpr (std::is_same_v<T, const VkAllocationCallbacks*>)
            given = arg;
        else if constexpr (std::is_same_v<T, VkDevice>)
            if (!device) device = arg;
    }
    CallbacksResource own_;
    std::optional<ScopedHostMemory> scope_;
};

// Guarded<&F>::call has F's exact signature and runs F through guarded() with the command's host memory current:
// the proc table hands these out.
template <auto F>
struct Guarded;
template <class R, class... A, R(VKAPI_PTR* F)(A...)>
struct Guarded<F> {
    static VKAPI_ATTR R VKAPI_CALL call(A... args) noexcept {
        CommandHostMemory<A...> memory(args...);
        return guarded([&]() -> R { return F(args...); });
    }
};

// A build, copy or deserialization that failed part-way leaves its destination unconstructed: the header no longer
// names a structure, so nothing (instances referring to it, copies, traversal) reads the half-written contents.
inline void markUnconstructed(AccelerationStructure& as) noexcept {
    as.constructed = false;
    if (std::byte* block = as.block(); block && as.size >= sizeof(format::Header))
        std::memset(block + offsetof(format::Header, magic), 0, sizeof(format::Header::magic));
}

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

}  // namespace vkas
