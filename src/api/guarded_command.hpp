// What the proc table (proc_table.cpp) hands out for each command: the command itself, run with its host memory
// current (command_memory.hpp) and no exception leaving it (exception_result.hpp).
#pragma once

#include "api/command_memory.hpp"
#include "api/exception_result.hpp"

namespace vkas {

// Guarded<&F>::call has F's exact signature and runs F through guarded() with the command's host memory current:
// the proc table hands these out.
template <auto F>
struct Guarded;
template <class R, class... A, R(VKAPI_PTR* F)(A...)>
struct Guarded<F> {
    static VKAPI_ATTR R VKAPI_CALL call(A... args) noexcept {
        CommandHostMemory<A...> memory(args...);
        return guarded([&]() -> R { return F(args...); });
    }
};

}  // namespace vkas
