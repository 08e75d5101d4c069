// Exception safety at the API boundary: no C++ exception ever leaves vkas. A failing allocation (std::bad_alloc, or
// std::length_error from a container sized by input) becomes VK_ERROR_OUT_OF_HOST_MEMORY; anything else (an
// exception thrown by an application callback, a thread that could not start) VK_ERROR_UNKNOWN. Every command of the
// proc table (guarded_command.hpp) and every exported function that may allocate runs through guarded(); work run on
// joined or worker threads catches with the same mapping (deferred_operation.cpp, thread_pool.cpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include <exception>
#include <new>
#include <stdexcept>
#include <type_traits>

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

}  // namespace vkas
