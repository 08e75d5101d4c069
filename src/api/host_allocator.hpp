// The application's VkAllocationCallbacks as a std::pmr::memory_resource (engine/util/host_memory.hpp): every
// allocation is one pfnAllocation call with the requested alignment and this resource's VkSystemAllocationScope,
// every deallocation one pfnFree. A NULL from pfnAllocation throws std::bad_alloc, which guarded() (api/exception_result.hpp)
// and the deferred-operation and worker threads turn into VK_ERROR_OUT_OF_HOST_MEMORY. docs/API.md "Host memory"
// says which allocation takes which callbacks and scope.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <memory_resource>
#include <new>

namespace vkas {

// Whether `callbacks` are some (vkas keeps "none" as a zeroed VkAllocationCallbacks).
inline bool hasCallbacks(const VkAllocationCallbacks& callbacks) { return callbacks.pfnAllocation != nullptr; }

class CallbacksResource final : public std::pmr::memory_resource {
  public:
    CallbacksResource() = default;
    CallbacksResource(const VkAllocationCallbacks& callbacks, VkSystemAllocationScope scope)
        : callbacks_(callbacks), scope_(scope) {}

    const VkAllocationCallbacks& callbacks() const { return callbacks_; }
    VkSystemAllocationScope scope() const { return scope_; }
    // This resource when it has callbacks, otherwise `fallback`.
    std::pmr::memory_resource* orElse(std::pmr::memory_resource* fallback) {
        return hasCallbacks(callbacks_) ? this : fallback;
    }

  private:
    void* do_allocate(std::size_t bytes, std::size_t alignment) override {
        void* p = callbacks_.pfnAllocation(callbacks_.pUserData, bytes ? bytes : 1, alignment, scope_);
        if (!p) throw std::bad_alloc();
        return p;
    }
    void do_deallocate(void* p, std::size_t, std::size_t) override { callbacks_.pfnFree(callbacks_.pUserData, p); }
    bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
        auto* o = dynamic_cast<const CallbacksResource*>(&other);
        return o && o->callbacks_.pfnAllocation == callbacks_.pfnAllocation &&
               o->callbacks_.pfnFree == callbacks_.pfnFree && o->callbacks_.pUserData == callbacks_.pUserData;
    }

    VkAllocationCallbacks callbacks_{};
    VkSystemAllocationScope scope_ = VK_SYSTEM_ALLOCATION_SCOPE_COMMAND;
};

}  // namespace vkas
