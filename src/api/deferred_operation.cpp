#include "api/deferred_operation.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/guard.hpp"
#include "api/validate/parameters.hpp"

namespace vkas {

DeferredOperation::DeferredOperation() {
    parallelFor_ = [this](uint32_t count, const std::function<void(uint32_t)>& fn) {
        if (count == 0) return;
        // A call that throws (out of memory), or queueing that fails, is recorded and rethrown here, on the calling
        // thread, once every queued call has finished: nothing queued is left referring to fn.
        struct Batch {
            uint32_t left;
            std::exception_ptr error;
        };
        auto batch = std::make_shared<Batch>(Batch{count, nullptr});
        std::unique_lock<std::mutex> lock(mutex_);
        for (uint32_t i = 0; i < count; ++i) {
            try {
                queue_.push_back([this, i, &fn, batch] {
                    std::exception_ptr error;
                    try {
                        fn(i);
                    } catch (...) {
                        error = std::current_exception();
                    }
                    std::lock_guard<std::mutex> guard(mutex_);
                    if (error && !batch->error) batch->error = error;
                    if (--batch->left == 0) changed_.notify_all();
                });
            } catch (...) {
                batch->left -= count - i;  // never queued: they will not run
                if (!batch->error) batch->error = std::current_exception();
                break;
            }
        }
        changed_.notify_all();
        // Help: run queued tasks (ours or others') until all of ours have run.
        while (batch->left > 0) {
            if (!queue_.empty())
                runOne(lock);
            else
                changed_.wait(lock);
        }
        if (batch->error) {
            std::exception_ptr error = batch->error;
            lock.unlock();
            std::rethrow_exception(error);
        }
    };
}

void DeferredOperation::start(std::vector<Task> tasks, std::function<VkResult()> finish, uint32_t concurrencyHint) {
    // Everything that allocates comes first: a start that throws (out of memory) leaves the operation as it was.
    // A task that throws makes the operation's result VK_ERROR_OUT_OF_HOST_MEMORY (currentExceptionResult).
    std::deque<Task> queue;
    for (Task& t : tasks)
        queue.push_back([this, t = std::move(t)] {
            VkResult failure = VK_SUCCESS;
            try {
                t();
            } catch (...) {
                failure = currentExceptionResult();
            }
            std::lock_guard<std::mutex> guard(mutex_);
            if (failure != VK_SUCCESS && failure_ == VK_SUCCESS) failure_ = failure;
            --topLevelLeft_;
        });
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = true;
    finishing_ = false;
    result_ = VK_NOT_READY;
    failure_ = VK_SUCCESS;
    finish_ = std::move(finish);
    concurrencyHint_ = std::max(1u, concurrencyHint);
    topLevelLeft_ = uint32_t(queue.size());
    queue_.swap(queue);  // queue_ is empty: the operation was complete
}

void DeferredOperation::runOne(std::unique_lock<std::mutex>& lock) {
    Task task = std::move(queue_.front());
    queue_.pop_front();
    ++running_;
    lock.unlock();
    task();
    lock.lock();
    --running_;
    changed_.notify_all();
}

VkResult DeferredOperation::join() {
    std::unique_lock<std::mutex> lock(mutex_);
    bool waited = false;
    for (;;) {
        if (!pending_) return VK_SUCCESS;
        if (!queue_.empty()) {
            runOne(lock);
            continue;
        }
        if (running_ == 0 && topLevelLeft_ == 0 && !finishing_) {
            // Everything ran: this thread completes the operation.
            finishing_ = true;
            lock.unlock();
            VkResult r;
            try {
                r = finish_ ? finish_() : VK_SUCCESS;
            } catch (...) {
                r = currentExceptionResult();
            }
            lock.lock();
            result_ = failure_ != VK_SUCCESS ? failure_ : r;
            pending_ = false;
            finish_ = nullptr;
            changed_.notify_all();
            return VK_SUCCESS;
        }
        // Nothing to hand out now. Tasks that may still spread work are running: more may come. Wait a little for
        // it before answering IDLE: applications call join again at once, and many threads doing so would contend
        // with the workers for the lock. Otherwise the remaining work belongs to other threads (DONE).
        if (topLevelLeft_ > 0 && !waited) {
            waited = true;
            changed_.wait_for(lock, std::chrono::milliseconds(1), [this] {
                return !pending_ || !queue_.empty() || (running_ == 0 && topLevelLeft_ == 0);
            });
            continue;
        }
        return topLevelLeft_ > 0 ? VK_THREAD_IDLE_KHR : VK_THREAD_DONE_KHR;
    }
}

uint32_t DeferredOperation::maxConcurrency() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pending_) return 0;
    return std::max({1u, concurrencyHint_, uint32_t(queue_.size()) + running_});
}

VkResult DeferredOperation::result() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pending_ ? VK_NOT_READY : result_;
}

bool DeferredOperation::pending() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pending_;
}

VkResult runOrDefer(VkDeferredOperationKHR operation, std::function<VkResult()> work) {
    if (operation == VK_NULL_HANDLE) return work();
    auto result = std::make_shared<VkResult>(VK_SUCCESS);
    fromHandle<DeferredOperation>(operation)->start({[result, work = std::move(work)] { *result = work(); }},
                                                    [result] { return *result; }, 1);
    return VK_OPERATION_DEFERRED_KHR;
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
    if (!dev) {
        v.fail("VUID-vkCreateDeferredOperationKHR-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (v.enabled()) {
        v.check(pDeferredOperation != nullptr, "VUID-vkCreateDeferredOperationKHR-pDeferredOperation-parameter",
                "pDeferredOperation is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    auto* op = createObject<DeferredOperation>(pAllocator);
    if (!op) return VK_ERROR_OUT_OF_HOST_MEMORY;
    op->device = dev;
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
    if (!dev) return v.fail("VUID-vkDestroyDeferredOperationKHR-device-parameter", "device is not a valid VkDevice.");
    if (operation == VK_NULL_HANDLE) return;
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled()) {
        op = checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                            "VUID-vkDestroyDeferredOperationKHR-operation-parameter",
                                            "VUID-vkDestroyDeferredOperationKHR-operation-parent", "operation");
        if (!op) return;
        v.check(!op->pending(), "VUID-vkDestroyDeferredOperationKHR-operation-03436",
                "operation is not complete: join it until it completes before destroying it.");
        checkDestroyAllocator(v, op->allocator, pAllocator, "VUID-vkDestroyDeferredOperationKHR-operation-03434",
                              "VUID-vkDestroyDeferredOperationKHR-operation-03435");
        if (v.failed()) return;
    }
    if (!op) return;
    dev->untrack(op);
    destroyObject(op);
}

VKAPI_ATTR uint32_t VKAPI_CALL GetDeferredOperationMaxConcurrencyKHR(VkDevice device,
                                                                    VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationMaxConcurrencyKHR");
    if (!dev) {
        v.fail("VUID-vkGetDeferredOperationMaxConcurrencyKHR-device-parameter", "device is not a valid VkDevice.");
        return 0;
    }
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                       "VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parameter",
                                                       "VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parent", "operation"))
        return 0;
    return op ? op->maxConcurrency() : 0;
}

VKAPI_ATTR VkResult VKAPI_CALL GetDeferredOperationResultKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationResultKHR");
    if (!dev) {
        v.fail("VUID-vkGetDeferredOperationResultKHR-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                       "VUID-vkGetDeferredOperationResultKHR-operation-parameter",
                                                       "VUID-vkGetDeferredOperationResultKHR-operation-parent", "operation"))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    return op ? op->result() : VK_ERROR_UNKNOWN;
}

VKAPI_ATTR VkResult VKAPI_CALL DeferredOperationJoinKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDeferredOperationJoinKHR");
    if (!dev) {
        v.fail("VUID-vkDeferredOperationJoinKHR-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                       "VUID-vkDeferredOperationJoinKHR-operation-parameter",
                                                       "VUID-vkDeferredOperationJoinKHR-operation-parent", "operation"))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    return op ? op->join() : VK_ERROR_UNKNOWN;
}

}  // namespace vkas::entry
