#include "api/thread_pool.hpp"

namespace vkas {

ThreadPool::ThreadPool(uint32_t threadCount) {
    for (uint32_t i = 1; i < threadCount; ++i) workers_.emplace_back([this] { workerLoop(); });
}

ThreadPool::~ThreadPool() {
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
        (*task_.load())(i);
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
        runTasks();
        {
            std::lock_guard lock(mutex_);
            if (--busy_ == 0) finished_.notify_all();
        }
    }
}

void ThreadPool::parallelFor(uint64_t count, const std::function<void(uint64_t)>& task) {
    if (count == 0) return;
    std::lock_guard call(callMutex_);
    if (workers_.empty() || count == 1) {
        for (uint64_t i = 0; i < count; ++i) task(i);
        return;
    }
    {
        std::lock_guard lock(mutex_);
        next_.store(~uint64_t(0) >> 1);  // a late worker of the last call claims nothing
        task_.store(&task);
        count_.store(count);
        next_.store(0);
        ++generation_;
    }
    wake_.notify_all();
    runTasks();
    std::unique_lock lock(mutex_);
    finished_.wait(lock, [&] { return busy_ == 0; });
}

}  // namespace vkas
