#include "api/deferred_operation.hpp"

#include <algorithm>
#include <memory>
#include <string>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/validation.hpp"

namespace vkas {

DeferredOperation::DeferredOperation() {
    parallelFor_ = [this](uint32_t count, const std::function<void(uint32_t)>& fn) {
        if (count == 0) return;
        auto left = std::make_shared<uint32_t>(count);
        std::unique_lock<std::mutex> lock(mutex_);
        for (uint32_t i = 0; i < count; ++i)
            queue_.push_back([this, i, &fn, left] {
                fn(i);
                std::lock_guard<std::mutex> guard(mutex_);
                if (--*left == 0) changed_.notify_all();
            });
        changed_.notify_all();
        // Help: run queued tasks (ours or others') until all of ours have run.
        while (*left > 0) {
            if (!queue_.empty())
                runOne(lock);
            else
                changed_.wait(lock);
        }
    };
}

void DeferredOperation::start(std::vector<Task> tasks, std::function<VkResult()> finish, uint32_t concurrencyHint) {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = true;
    finishing_ = false;
    result_ = VK_NOT_READY;
    finish_ = std::move(finish);
    concurrencyHint_ = std::max(1u, concurrencyHint);
    topLevelLeft_ = uint32_t(tasks.size());
    for (Task& t : tasks)
        queue_.push_back([this, t = std::move(t)] {
            t();
            std::lock_guard<std::mutex> guard(mutex_);
            --topLevelLeft_;
        });
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
            const VkResult r = finish_ ? finish_() : VK_SUCCESS;
            lock.lock();
            result_ = r;
            pending_ = false;
            finish_ = nullptr;
            changed_.notify_all();
            return VK_SUCCESS;
        }
        // Nothing to hand out now. Tasks that may still spread work are running: more may come (IDLE); otherwise
        // the remaining work belongs to other threads (DONE).
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

void checkDeferredOperation(Validator& v, const Device& device, VkDeferredOperationKHR operation, const char* command) {
    if (operation == VK_NULL_HANDLE) return;
    auto* op = device.live<DeferredOperation>(operation, ObjectMagic::DeferredOperation);
    const std::string vuid = std::string("VUID-") + command + "-deferredOperation-";
    if (v.check(op != nullptr, (vuid + "parameter").c_str(), "deferredOperation is not a valid VkDeferredOperationKHR."))
        v.check(!op->pending(), (vuid + "03678").c_str(),
                "deferredOperation still has a deferred command pending: join it until it completes first.");
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

VKAPI_ATTR VkResult VKAPI_CALL CreateDeferredOperationKHR(VkDevice device, const VkAllocationCallbacks*,
                                                          VkDeferredOperationKHR* pDeferredOperation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateDeferredOperationKHR");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkCreateDeferredOperationKHR-device-parameter", "device is not a valid VkDevice.");
        v.check(pDeferredOperation != nullptr, "VUID-vkCreateDeferredOperationKHR-pDeferredOperation-parameter",
                "pDeferredOperation is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    auto* op = new (std::nothrow) DeferredOperation;
    if (!op) return VK_ERROR_OUT_OF_HOST_MEMORY;
    op->device = dev;
    dev->track(op);
    *pDeferredOperation = toHandle<VkDeferredOperationKHR>(op);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyDeferredOperationKHR(VkDevice device, VkDeferredOperationKHR operation,
                                                       const VkAllocationCallbacks*) {
    if (operation == VK_NULL_HANDLE) return;
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyDeferredOperationKHR");
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled()) {
        if (!v.check(op != nullptr, "VUID-vkDestroyDeferredOperationKHR-operation-parameter",
                     "operation 0x%llx is not a live VkDeferredOperationKHR.",
                     (unsigned long long)(uintptr_t)operation))
            return;
        v.check(!op->pending(), "VUID-vkDestroyDeferredOperationKHR-operation-03436",
                "operation is not complete: join it until it completes before destroying it.");
        if (v.failed()) return;
    }
    if (!op) return;
    dev->untrack(op);
    op->magic = ObjectMagic::Dead;
    delete op;
}

VKAPI_ATTR uint32_t VKAPI_CALL GetDeferredOperationMaxConcurrencyKHR(VkDevice device,
                                                                    VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationMaxConcurrencyKHR");
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !v.check(op != nullptr, "VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parameter",
                                "operation is not a live VkDeferredOperationKHR."))
        return 0;
    return op ? op->maxConcurrency() : 0;
}

VKAPI_ATTR VkResult VKAPI_CALL GetDeferredOperationResultKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetDeferredOperationResultKHR");
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !v.check(op != nullptr, "VUID-vkGetDeferredOperationResultKHR-operation-parameter",
                                "operation is not a live VkDeferredOperationKHR."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    return op ? op->result() : VK_ERROR_UNKNOWN;
}

VKAPI_ATTR VkResult VKAPI_CALL DeferredOperationJoinKHR(VkDevice device, VkDeferredOperationKHR operation) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDeferredOperationJoinKHR");
    DeferredOperation* op = liveOperation(dev, operation);
    if (v.enabled() && !v.check(op != nullptr, "VUID-vkDeferredOperationJoinKHR-operation-parameter",
                                "operation is not a live VkDeferredOperationKHR."))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    return op ? op->join() : VK_ERROR_UNKNOWN;
}

}  // namespace vkas::entry
