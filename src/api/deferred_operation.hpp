// VkDeferredOperationKHR: work a deferrable host command hands to the threads the application joins
// (VK_KHR_deferred_host_operations). The work is a list of tasks plus a finishing step; a task may spread work over
// the joined threads through parallelFor(), and the thread that waits there helps run it, so a lone joined thread
// always completes the operation.
//
// Host memory: the operation's state (its task list, queue, the deferred command's captured work and results) comes
// from the operation's VkAllocationCallbacks, else the device's, with scope OBJECT (it lasts while the operation is
// pending, across commands); what the tasks allocate while a joined thread runs them, from the same callbacks with
// scope COMMAND (it is freed before that vkDeferredOperationJoinKHR returns).
#pragma once

#include <vulkan/vulkan_core.h>

#include <condition_variable>
#include <exception>
#include <memory_resource>
#include <mutex>

#include "api/host_allocator.hpp"
#include "api/objects.hpp"
#include "engine/util/function_ref.hpp"
#include "engine/util/host_memory.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

class DeferredOperation {
public:
    using Task = HostFunction<void()>;
    using Finish = HostFunction<VkResult()>;

    ObjectMagic magic = ObjectMagic::DeferredOperation;
    Device* device = nullptr;
    VkAllocationCallbacks allocator{};  // the pAllocator of vkCreateDeferredOperationKHR (zero: none)
    VkAllocationCallbacks memoryCallbacks{};  // what this object's memory came from (createObject)

    // The callbacks the operation allocates through (its own, else the device's; zeroed: operator new). Called once,
    // at creation, before anything is queued.
    void setHostMemory(const VkAllocationCallbacks& callbacks);
    std::pmr::memory_resource* stateMemory() { return state_.orElse(std::pmr::new_delete_resource()); }
    std::pmr::memory_resource* workMemory() { return work_.orElse(std::pmr::new_delete_resource()); }

    // Makes the operation pending: nothing runs until a thread joins. `finish` runs once, after every task (and
    // everything they spread), on the thread that completes the operation; its result becomes the operation's.
    // `concurrencyHint` is how many threads the work can use, for vkGetDeferredOperationMaxConcurrencyKHR. The
    // tasks and finish must have been made with stateMemory() current. Throws (out of memory) before any change.
    void start(HostVector<Task> tasks, Finish finish, uint32_t concurrencyHint);

    VkResult join();               // VK_SUCCESS, VK_THREAD_DONE_KHR or VK_THREAD_IDLE_KHR
    uint32_t maxConcurrency();     // 0 once complete
    VkResult result();             // VK_NOT_READY while pending
    bool pending();

    // Runs fn(0..count) on the joined threads; the calling thread (a task of this operation) helps until all ran.
    const ParallelFor& parallelFor() const { return parallelFor_; }

private:
    // What parallelFor spreads: fn(0..count) for one caller, which waits on its own stack until all ran. `parent` is
    // the batch whose item the caller was running when it spread this one (nullptr: a task of start()).
    struct Batch {
        FunctionRef<void(uint32_t)> fn;
        uint32_t count;
        uint32_t next = 0;  // fn(next..count) are not handed out yet
        uint32_t left;      // not finished yet
        Batch* parent;
        std::exception_ptr error;
    };
    // A piece of work handed out: task `index` of start() (batch == nullptr) or fn(index) of a batch.
    struct Item {
        Batch* batch;
        uint32_t index;
    };

    void spread(uint32_t count, FunctionRef<void(uint32_t)> fn);
    bool hasWork() const { return nextTask_ < tasks_.size() || !open_.empty(); }
    // Hands out the next item for a thread that waits on `waiting` (nullptr: a joined thread that waits on nothing).
    bool take(const Batch* waiting, Item& item);
    // Runs the item with the lock released. Returns with the lock held.
    void run(Item item, std::unique_lock<std::mutex>& lock);

    CallbacksResource state_, work_;
    std::mutex mutex_;
    std::condition_variable changed_;
    HostVector<Task> tasks_;
    size_t nextTask_ = 0;        // tasks_[nextTask_..] are not handed out yet
    HostVector<Batch*> open_;    // the batches with items not handed out, oldest first
    uint32_t running_ = 0;       // items being run right now
    uint32_t topLevelLeft_ = 0;  // tasks given to start() not finished yet: they may still spread work
    bool pending_ = false;
    bool finishing_ = false;
    uint32_t concurrencyHint_ = 1;
    VkResult result_ = VK_SUCCESS;  // a new operation is complete with VK_SUCCESS
    VkResult failure_ = VK_SUCCESS;  // a task that threw (out of memory): the operation's result instead of finish's
    Finish finish_;
    ParallelFor parallelFor_;

public:
    DeferredOperation();
};

// Makes runOne(i, &op.parallelFor()) for i in [0, count) the tasks of `op` (run by the threads that join it, `hint`
// its concurrency hint; each task a copy of runOne, which must own what it reads) and returns
// VK_OPERATION_DEFERRED_KHR. The operation's result is VK_SUCCESS, or the first failure in task order. The
// per-info commands (vkBuildAccelerationStructuresKHR, vkBuildMicromapsEXT) defer through this.
template <class RunOne>
VkResult deferEach(DeferredOperation& op, uint32_t count, uint32_t hint, const RunOne& runOne) {
    ScopedHostMemory memory(op.stateMemory());  // the captured work lasts while the operation is pending
    HostVector<VkResult> results(count, VK_SUCCESS);
    VkResult* out = results.data();  // stays where it is when `results` moves into the finishing step
    HostVector<DeferredOperation::Task> tasks;
    tasks.reserve(count);
    DeferredOperation* o = &op;
    for (uint32_t i = 0; i < count; ++i) tasks.emplace_back([=] { out[i] = runOne(i, &o->parallelFor()); });
    op.start(std::move(tasks), [results = std::move(results)] {
        for (VkResult r : results)
            if (r != VK_SUCCESS) return r;
        return VK_SUCCESS;
    }, hint);
    return VK_OPERATION_DEFERRED_KHR;
}

// Runs `work` now when operation is VK_NULL_HANDLE and returns its result; otherwise makes it the operation's one
// task (its result becomes the operation's) and returns VK_OPERATION_DEFERRED_KHR.
template <class Work>
VkResult runOrDefer(VkDeferredOperationKHR operation, Work&& work) {
    if (operation == VK_NULL_HANDLE) return work();
    auto* op = fromHandle<DeferredOperation>(operation);
    ScopedHostMemory memory(op->stateMemory());
    HostVector<VkResult> result(1, VK_SUCCESS);
    VkResult* out = result.data();  // stays where it is when `result` moves into the finishing step
    HostVector<DeferredOperation::Task> tasks;
    tasks.emplace_back([out, work = std::forward<Work>(work)] { *out = work(); });
    op->start(std::move(tasks), [result = std::move(result)] { return result[0]; }, 1);
    return VK_OPERATION_DEFERRED_KHR;
}

}  // namespace vkas
