#include "api/thread_pool.hpp"

#include <exception>
#include <utility>

namespace vkas {

ThreadPool::ThreadPool(uint32_t threadCount) {
    try {
        workers_.reserve(threadCount > 1 ? threadCount - 1 : 0);
        for (uint32_t i = 1; i < threadCount; ++i) workers_.emplace_back([this] { workerLoop(); });
    } catch (...) {
        stopAndJoin();  // a thread that could not start (out of memory): the started ones end, then it throws
        throw;
    }
}

ThreadPool::~ThreadPool() { stopAndJoin(); }

void ThreadPool::stopAndJoin() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : workers_) t.join();
}

void ThreadPool::runTasks() {
    for (;;) {
        uint64_t i = next_.fetch_add(1);
        if (i >= count_.load()) break;
        try {
            (*task_.load())(i);
        } catch (...) {  // out of memory in a task: the first error is rethrown by parallelFor; the rest is skipped
            std::lock_guard lock(mutex_);
            if (!error_) error_ = std::current_exception();
            next_.store(~uint64_t(0) >> 1);
        }
    }
}

void ThreadPool::workerLoop() {
    uint64_t seen = 0;
    for (;;) {
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_) return;
            seen = generation_;
            ++busy_;
        }
        {
            ScopedHostMemory memory(memory_.load());
            runTasks();
        }
        {
            std::lock_guard lock(mutex_);
            if (--busy_ == 0) finished_.notify_all();
        }
    }
}

void ThreadPool::parallelFor(uint64_t count, FunctionRef<void(uint64_t)> task) {
    if (count == 0) return;
    std::lock_guard call(callMutex_);
    if (workers_.empty() || count == 1) {
        for (uint64_t i = 0; i < count; ++i) task(i);
        return;
    }
    {
        std::lock_guard lock(mutex_);
        next_.store(~uint64_t(0) >> 1);  // a late worker of the last call claims nothing
        error_ = nullptr;
        task_.store(&task);
        memory_.store(currentHostMemory());
        count_.store(count);
        next_.store(0);
        ++generation_;
    }
    wake_.notify_all();
    runTasks();
    std::unique_lock lock(mutex_);
    finished_.wait(lock, [&] { return busy_ == 0; });
    if (std::exception_ptr error = std::exchange(error_, nullptr)) {
        lock.unlock();
        std::rethrow_exception(error);
    }
}

}  // namespace vkas
