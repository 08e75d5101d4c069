// VkDeferredOperationKHR: work a deferrable host command hands to the threads the application joins
// (VK_KHR_deferred_host_operations). The work is a list of tasks plus a finishing step; a task may spread work over
// the joined threads through parallelFor(), and the thread that waits there helps run it, so a lone joined thread
// always completes the operation.
#pragma once

#include <vulkan/vulkan_core.h>

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <vector>

#include "api/objects.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

class DeferredOperation {
public:
    using Task = std::function<void()>;

    ObjectMagic magic = ObjectMagic::DeferredOperation;
    Device* device = nullptr;
    VkAllocationCallbacks allocator{};  // the pAllocator of vkCreateDeferredOperationKHR (zero: none)

    // Makes the operation pending: nothing runs until a thread joins. `finish` runs once, after every task (and
    // everything they spread), on the thread that completes the operation; its result becomes the operation's.
    // `concurrencyHint` is how many threads the work can use, for vkGetDeferredOperationMaxConcurrencyKHR.
    void start(std::vector<Task> tasks, std::function<VkResult()> finish, uint32_t concurrencyHint);

    VkResult join();               // VK_SUCCESS, VK_THREAD_DONE_KHR or VK_THREAD_IDLE_KHR
    uint32_t maxConcurrency();     // 0 once complete
    VkResult result();             // VK_NOT_READY while pending
    bool pending();

    // Runs fn(0..count) on the joined threads; the calling thread (a task of this operation) helps until all ran.
    const ParallelFor& parallelFor() const { return parallelFor_; }

private:
    // Runs one queued task with the lock released. Returns with the lock held.
    void runOne(std::unique_lock<std::mutex>& lock);

    std::mutex mutex_;
    std::condition_variable changed_;
    std::deque<Task> queue_;
    uint32_t running_ = 0;       // tasks being run right now
    uint32_t topLevelLeft_ = 0;  // tasks given to start() not finished yet: they may still spread work
    bool pending_ = false;
    bool finishing_ = false;
    uint32_t concurrencyHint_ = 1;
    VkResult result_ = VK_SUCCESS;  // a new operation is complete with VK_SUCCESS
    VkResult failure_ = VK_SUCCESS;  // a task that threw (out of memory): the operation's result instead of finish's
    std::function<VkResult()> finish_;
    ParallelFor parallelFor_;

public:
    DeferredOperation();
};

// Runs `work` now when operation is VK_NULL_HANDLE and returns its result; otherwise makes it the operation's one
// task (its result becomes the operation's) and returns VK_OPERATION_DEFERRED_KHR.
VkResult runOrDefer(VkDeferredOperationKHR operation, std::function<VkResult()> work);

}  // namespace vkas
