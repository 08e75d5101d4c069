// The worker threads of vkas's own batch helpers (vkasTraceRays). Commands never use them.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory_resource>
#include <mutex>
#include <thread>

#include "engine/util/function_ref.hpp"
#include "engine/util/host_memory.hpp"

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
    // The workers run the tasks with the caller's current host memory (engine/util/host_memory.hpp).
    void parallelFor(uint64_t count, FunctionRef<void(uint64_t)> task);

private:
    void workerLoop();
    void runTasks();
    void stopAndJoin();

    HostVector<std::thread> workers_;  // the list from the current host memory at construction (the device's)
    std::mutex callMutex_;  // serialises parallelFor calls
    std::mutex mutex_;
    std::condition_variable wake_, finished_;
    std::atomic<const FunctionRef<void(uint64_t)>*> task_{nullptr};
    std::atomic<std::pmr::memory_resource*> memory_{nullptr};  // the current call's caller's host memory
    std::atomic<uint64_t> count_{0};
    std::atomic<uint64_t> next_{0};
    uint32_t busy_ = 0;
    uint64_t generation_ = 0;
    bool stop_ = false;
    std::exception_ptr error_;  // the first exception a task of the current call threw
};

}  // namespace vkas
