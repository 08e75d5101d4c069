// Two independent pieces of work at once: `side` on a thread of its own while the calling thread runs `main`, when
// the work is large enough to pay for starting a thread (and a second processor is there to run it); otherwise, or
// when no thread can be started, both on the calling thread, one after the other. Returns when both are done, also when `main` throws (the exception is passed
// on after `side` finished). `side` must not throw. The results do not depend on which way it ran.
#pragma once

#include <exception>
#include <system_error>
#include <thread>
#include <utility>

#if defined(__linux__)
#include <sched.h>
#endif

namespace vkas {

// Whether this thread may run on at least two processors (its affinity mask), so that a second thread can run at
// the same time rather than take turns with it.
inline bool secondProcessorAvailable() {
#if defined(__linux__)
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) return CPU_COUNT(&set) >= 2;
#endif
    return std::thread::hardware_concurrency() >= 2;
}

template <class Side, class Main>
void alongside(bool worthAThread, Side&& side, Main&& main) {
    std::thread helper;
    if (worthAThread && secondProcessorAvailable()) {
        try {
            helper = std::thread(std::ref(side));
        } catch (const std::system_error&) {  // no thread to be had: do it here
        } catch (const std::bad_alloc&) {
        }
    }
    if (!helper.joinable()) {
        side();
        main();
        return;
    }
    try {
        main();
    } catch (...) {
        helper.join();
        throw;
    }
    helper.join();
}

}  // namespace vkas
