// The host memory of a command's temporaries (VK_SYSTEM_ALLOCATION_SCOPE_COMMAND), made current for the whole
// command (engine/util/host_memory.hpp), so that the engine's containers allocate through the application's
// callbacks: docs/API.md, "Host memory".
#pragma once

#include <vulkan/vulkan_core.h>

#include <memory_resource>
#include <optional>
#include <type_traits>

#include "api/host_allocator.hpp"
#include "engine/util/host_memory.hpp"

namespace vkas {

// A command's memory: its own pAllocator when it has one (its last
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

}  // namespace vkas
