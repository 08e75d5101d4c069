// The replacement operator new/delete of alloc_failure.hpp. Linked into vkas_test_out_of_memory only.
#include "alloc_failure.hpp"

#include <malloc.h>

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

std::atomic<bool> gArmed{false};
std::atomic<bool> gSticky{false};
std::atomic<bool> gInjected{false};
std::atomic<int64_t> gCountdown{0};  // allocations left before the one that fails
std::atomic<uint64_t> gSinceArm{0};
std::atomic<int64_t> gLive{0};

// Whether this allocation is the one (or, sticky, one of those) that must fail.
bool injectFailure() {
    if (!gArmed.load(std::memory_order_acquire)) return false;
    gSinceArm.fetch_add(1, std::memory_order_relaxed);
    const int64_t left = gCountdown.fetch_sub(1, std::memory_order_acq_rel);
    if (left == 0 || (left < 0 && gSticky.load(std::memory_order_relaxed))) {
        gInjected.store(true, std::memory_order_release);
        return true;
    }
    return false;
}

void* allocate(std::size_t size, std::size_t alignment, bool nothrow) {
    void* p = nullptr;
    if (!injectFailure()) {
        if (size == 0) size = 1;
        if (alignment <= alignof(std::max_align_t)) {
            p = std::malloc(size);
        } else {
            if (posix_memalign(&p, alignment, size) != 0) p = nullptr;
        }
    }
    if (!p) {
        if (nothrow) return nullptr;
        throw std::bad_alloc();
    }
    gLive.fetch_add(int64_t(malloc_usable_size(p)), std::memory_order_relaxed);
    return p;
}

void release(void* p) noexcept {
    if (!p) return;
    gLive.fetch_sub(int64_t(malloc_usable_size(p)), std::memory_order_relaxed);
    std::free(p);
}

}  // namespace

namespace vt::alloc {

void armFailure(uint64_t k, bool sticky) {
    gArmed.store(false, std::memory_order_release);
    gInjected.store(false);
    gSinceArm.store(0);
    gSticky.store(sticky);
    gCountdown.store(int64_t(k));
    gArmed.store(true, std::memory_order_release);
}

bool disarm() {
    gArmed.store(false, std::memory_order_release);
    return gInjected.load(std::memory_order_acquire);
}

uint64_t allocationsSinceArm() { return gSinceArm.load(); }
int64_t liveBytes() { return gLive.load(); }

}  // namespace vt::alloc

// ---- The replacements -------------------------------------------------------------------------------------------
void* operator new(std::size_t size) { return allocate(size, 0, false); }
void* operator new[](std::size_t size) { return allocate(size, 0, false); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate(size, 0, true); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate(size, 0, true); }
void* operator new(std::size_t size, std::align_val_t a) { return allocate(size, std::size_t(a), false); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocate(size, std::size_t(a), false); }
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
    return allocate(size, std::size_t(a), true);
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
    return allocate(size, std::size_t(a), true);
}

void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
