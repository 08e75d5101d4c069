// The worker threads of vkas's own batch helpers (vkasTraceRays). Commands never use them.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace vkas {

class ThreadPool {
public:
    explicit ThreadPool(uint32_t threadCount);  // threadCount includes the calling thread
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    uint32_t threadCount() const { return uint32_t(workers_.size()) + 1; }
    // Calls task(i) for every i in [0, count) on the workers and the calling thread; returns when all are done.
    // One parallelFor runs at a time; concurrent callers wait their turn. When a task throws (out of memory), the
    // tasks not started yet are skipped and parallelFor rethrows the first exception once every thread is done.
    void parallelFor(uint64_t count, const std::function<void(uint64_t)>& task);

private:
    void workerLoop();
    void runTasks();
    void stopAndJoin();

    std::vector<std::thread> workers_;
    std::mutex callMutex_;  // serialises parallelFor calls
    std::mutex mutex_;
    std::condition_variable wake_, finished_;
    std::atomic<const std::function<void(uint64_t)>*> task_{nullptr};
    std::atomic<uint64_t> count_{0};
    std::atomic<uint64_t> next_{0};
    uint32_t busy_ = 0;
    uint64_t generation_ = 0;
    bool stop_ = false;
    std::exception_ptr error_;  // the first exception a task of the current call threw
};

}  // namespace vkas
