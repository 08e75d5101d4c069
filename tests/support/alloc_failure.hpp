// Allocation-failure injection for the out_of_memory test group. alloc_failure.cpp replaces the global operator
// new and delete (every form: plain, array, aligned, nothrow, sized) of the executable it is linked into, and only
// that one (tests/api/CMakeLists.txt). The replacements call malloc/aligned_alloc and free, so AddressSanitizer and
// LeakSanitizer still see every allocation. Allocations are counted on every thread (atomics).
//
//   vt::alloc::armFailure(k);   // the k-th operator new from now (0: the next one) fails
//   VkResult r = call();         // std::bad_alloc inside vkas, nullptr from a nothrow new
//   bool hit = vt::alloc::disarm();  // true when the failure was injected (k was below the call's allocations)
//
// liveBytes() is the bytes currently allocated through operator new (malloc_usable_size of each block): a call that
// fails must leave it as it found it.
#pragma once

#include <cstdint>

namespace vt::alloc {

// Makes the k-th allocation after this call fail; with `sticky`, that one and every later one fail until disarm().
void armFailure(uint64_t k, bool sticky = false);
// Stops injecting; returns whether a failure was injected since armFailure.
bool disarm();
// Allocations through operator new since the last armFailure (failed ones included).
uint64_t allocationsSinceArm();
// Bytes allocated through operator new and not freed yet, over the whole process.
int64_t liveBytes();

// Arms for the scope, disarms when it ends.
class ScopedFailure {
  public:
    explicit ScopedFailure(uint64_t k, bool sticky = false) { armFailure(k, sticky); }
    ~ScopedFailure() { disarm(); }
    bool injected() { return disarm(); }
    ScopedFailure(const ScopedFailure&) = delete;
    ScopedFailure& operator=(const ScopedFailure&) = delete;
};

}  // namespace vt::alloc
