#include "api/deferred_operation.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/exception_result.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/deferred_calls.hpp"

namespace vkas {

namespace {
// The batch whose item this thread is running (nullptr: none, or a task of start()): the parent of what it spreads.
thread_local void* tCurrentBatch = nullptr;
}  // namespace

DeferredOperation::DeferredOperation() {
    parallelFor_ = [this](uint32_t count, FunctionRef<void(uint32_t)> fn) { spread(count, fn); };
}

void DeferredOperation::setHostMemory(const VkAllocationCallbacks& callbacks) {
    state_ = CallbacksResource(callbacks, VK_SYSTEM_ALLOCATION_SCOPE_OBJECT);
    work_ = CallbacksResource(callbacks, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND);
    tasks_ = HostVector<Task>(HostAllocator<Task>(stateMemory()));
    open_ = HostVector<Batch*>(HostAllocator<Batch*>(stateMemory()));
}

void DeferredOperation::spread(uint32_t count, FunctionRef<void(uint32_t)> fn) {
    if (count == 0) return;
    // A call that throws (out of memory), or queueing that fails, is recorded and rethrown here, on the calling
    // thread, once every queued call has finished: nothing queued is left referring to the batch (on this stack).
    Batch batch{fn, count, 0, count, static_cast<Batch*>(tCurrentBatch), nullptr};
    std::unique_lock<std::mutex> lock(mutex_);
    try {
        open_.push_back(&batch);
    } catch (...) {
        batch.left = 0;  // nothing queued
        batch.error = std::current_exception();
    }
    changed_.notify_all();
    // Help until all of ours have run, but only with our own items and those spread below them: an unrelated item
    // (another part of the build, which may be long) would hold up the rest of the work that waits for this batch,
    // which is on the critical path when the batch is the top of a tree.
    Item item;
    while (batch.left > 0) {
        if (take(&batch, item))
            run(item, lock);
        else
            changed_.wait(lock);
    }
    if (batch.error) {
        std::exception_ptr error = batch.error;
        lock.unlock();
        std::rethrow_exception(error);
    }
}

void DeferredOperation::start(HostVector<Task> tasks, Finish finish, uint32_t concurrencyHint) {
    // Everything that allocates comes first: a start that throws (out of memory) leaves the operation as it was.
    // A task that throws makes the operation's result VK_ERROR_OUT_OF_HOST_MEMORY (currentExceptionResult).
    std::lock_guard<std::mutex> lock(mutex_);
    open_.clear();  // the operation was complete: nothing is queued
    nextTask_ = 0;
    tasks_ = std::move(tasks);
    pending_ = true;
    finishing_ = false;
    result_ = VK_NOT_READY;
    failure_ = VK_SUCCESS;
    finish_ = std::move(finish);
    concurrencyHint_ = std::max(1u, concurrencyHint);
    topLevelLeft_ = uint32_t(tasks_.size());
}

bool DeferredOperation::take(const Batch* waiting, Item& item) {
    if (!waiting && nextTask_ < tasks_.size()) {
        item = Item{nullptr, uint32_t(nextTask_++)};
        return true;
    }
    for (size_t k = 0; k < open_.size(); ++k) {
        Batch* b = open_[k];
        bool below = waiting == nullptr;  // a joined thread takes anything; a waiting one, only its batch's descendants
        for (const Batch* a = b; a && !below; a = a->parent) below = a == waiting;
        if (!below) continue;
        item = Item{b, b->next++};
        if (b->next == b->count) open_.erase(open_.begin() + ptrdiff_t(k));
        return true;
    }
    return false;
}

void DeferredOperation::run(Item item, std::unique_lock<std::mutex>& lock) {
    ++running_;
    lock.unlock();
    std::exception_ptr error;
    VkResult failure = VK_SUCCESS;
    void* const outer = tCurrentBatch;
    tCurrentBatch = item.batch;
    {
        ScopedHostMemory memory(workMemory());  // the engine's temporaries while this thread works for the operation
        try {
            if (item.batch)
                item.batch->fn(item.index);
            else
                tasks_[item.index]();
        } catch (...) {
            if (item.batch)
                error = std::current_exception();
            else
                failure = currentExceptionResult();
        }
    }
    tCurrentBatch = outer;
    lock.lock();
    if (item.batch) {
        if (error && !item.batch->error) item.batch->error = error;
        --item.batch->left;
    } else {
        if (failure != VK_SUCCESS && failure_ == VK_SUCCESS) failure_ = failure;
        --topLevelLeft_;
    }
    --running_;
    changed_.notify_all();
}

VkResult DeferredOperation::join() {
    std::unique_lock<std::mutex> lock(mutex_);
    bool waited = false;
    Item item;
    for (;;) {
        if (!pending_) return VK_SUCCESS;
        if (take(nullptr, item)) {
            run(item, lock);
            continue;
        }
        if (running_ == 0 && topLevelLeft_ == 0 && !finishing_) {
            // Everything ran: this thread completes the operation.
            finishing_ = true;
            lock.unlock();
            VkResult r;
            try {
                ScopedHostMemory memory(workMemory());
                r = finish_ ? finish_() : VK_SUCCESS;
            } catch (...) {
                r = currentExceptionResult();
            }
            lock.lock();
            result_ = failure_ != VK_SUCCESS ? failure_ : r;
            pending_ = false;
            finish_ = nullptr;
            tasks_.clear();  // the command's captured work, freed (the list keeps its capacity)
            nextTask_ = 0;
            changed_.notify_all();
            return VK_SUCCESS;
        }
        // Nothing to hand out now. Tasks that may still spread work are running: more may come. Wait a little for
        // it before answering IDLE: applications call join again at once, and many threads doing so would contend
        // with the workers for the lock. Otherwise the remaining work belongs to other threads (DONE).
        if (topLevelLeft_ > 0 && !waited) {
            waited = true;
            changed_.wait_for(lock, std::chrono::milliseconds(1), [this] {
                return !pending_ || hasWork() || (running_ == 0 && topLevelLeft_ == 0);
            });
            continue;
        }
        return topLevelLeft_ > 0 ? VK_THREAD_IDLE_KHR : VK_THREAD_DONE_KHR;
    }
}

uint32_t DeferredOperation::maxConcurrency() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pending_) return 0;
    uint32_t waiting = uint32_t(tasks_.size() - nextTask_);
    for (const Batch* b : open_) waiting += b->count - b->next;
    return std::max({1u, concurrencyHint_, waiting + running_});
}

VkResult DeferredOperation::result() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pending_ ? VK_NOT_READY : result_;
}

bool DeferredOperation::pending() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pending_;
}

}  // namespace vkas

namespace vkas::entry {

namespace {
DeferredOperation* liveOperation(Device* dev, VkDeferredOperationKHR op) {
    if (!dev) return nullptr;
    return dev->validationEnabled() ? dev->live<DeferredOperation>(op, ObjectMagic::DeferredOperation)
                                    : fromHandle<DeferredOperation>(op);
}
}  // namespace

VKAPI_ATTR VkResult VKAPI_CALL CreateDeferredOperationKHR(VkDevice device, const VkAllocationCallbacks* pAllocator,
                                                          VkDeferredOperationKHR* pDeferredOperation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateDeferredOperationKHR");
    if (!checkCreateDeferredOperation(v, dev, pDeferredOperation)) return VK_ERROR_VALIDATION_FAILED_EXT;
    auto* op = createObject<DeferredOperation>(pAllocator, dev->allocator());
    if (!op) return VK_ERROR_OUT_OF_HOST_MEMORY;
    op->device = dev;
    op->setHostMemory(hasCallbacks(op->allocator) ? op->allocator : dev->allocator());
    if (!dev->track(op)) {
        destroyObject(op);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pDeferredOperation = toHandle<VkDeferredOperationKHR>(op);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyDeferredOperationKHR(VkDevice device, VkDeferredOperationKHR operation,
                                                       const VkAllocationCallbacks* pAllocator) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyDeferredOperationKHR");
    DeferredOperation* op = liveOperation(dev, operation);
    if (!checkDestroyDeferredOperation(v, dev, operation, pAllocator, op)) return;
    if (!op) return;
    dev->untrack(op);
    destroyObject(op);
}

VKAPI_ATTR uint32_t VKAPI_CALL GetDeferredOperationMaxConcurrencyKHR(VkDevice device,
                                                                    VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationMaxConcurrencyKHR");
    if (!checkGetDeferredOperationMaxConcurrency(v, dev, operation)) return 0;
    DeferredOperation* op = liveOperation(dev, operation);
    return op ? op->maxConcurrency() : 0;
}

VKAPI_ATTR VkResult VKAPI_CALL GetDeferredOperationResultKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationResultKHR");
    if (!checkGetDeferredOperationResult(v, dev, operation)) return VK_ERROR_VALIDATION_FAILED_EXT;
    DeferredOperation* op = liveOperation(dev, operation);
    return op ? op->result() : VK_ERROR_UNKNOWN;
}

VKAPI_ATTR VkResult VKAPI_CALL DeferredOperationJoinKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDeferredOperationJoinKHR");
    if (!checkDeferredOperationJoin(v, dev, operation)) return VK_ERROR_VALIDATION_FAILED_EXT;
    DeferredOperation* op = liveOperation(dev, operation);
    return op ? op->join() : VK_ERROR_UNKNOWN;
}

}  // namespace vkas::entry
