// The one way engine loops run on several threads. The API layer supplies a ParallelFor (a deferred operation's
// joined threads); the engine cuts its work into a number of pieces that depends only on the input sizes, never on
// the threads, so the bytes it writes are the same however the pieces are scheduled, and without threads at all.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>

#include "engine/util/function_ref.hpp"

namespace vkas {

// Runs fn(i) for every i in [0, count), possibly on several threads, and returns when all have run. fn is passed by
// reference (FunctionRef): spreading a loop allocates nothing for the loop's callable.
using ParallelFor = std::function<void(uint32_t count, FunctionRef<void(uint32_t)> fn)>;

// fn(i) for every i in [0, count): on `parallel`'s threads when there is one and more than one index, otherwise in
// order on the calling thread.
template <class Fn>
void parallelFor(const ParallelFor* parallel, uint32_t count, const Fn& fn) {
    if (parallel && count > 1)
        (*parallel)(count, fn);
    else
        for (uint32_t i = 0; i < count; ++i) fn(i);
}

// The chunks of `chunk` items that cover n items (the last one may be shorter).
constexpr uint32_t chunkCount(uint64_t n, uint32_t chunk) { return uint32_t((n + chunk - 1) / chunk); }

// fn(c, begin, end) for each chunk c = [begin, end) of [0, n) in fixed chunks of `chunk` items, through parallelFor.
template <class Fn>
void parallelForChunks(const ParallelFor* parallel, uint64_t n, uint32_t chunk, const Fn& fn) {
    parallelFor(parallel, chunkCount(n, chunk), [&](uint32_t c) {
        fn(c, uint64_t(c) * chunk, std::min<uint64_t>(n, uint64_t(c + 1) * chunk));
    });
}

}  // namespace vkas
