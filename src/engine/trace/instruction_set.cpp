#include "engine/trace/instruction_set.hpp"

#include <cstdlib>
#include <cstring>

namespace vkas {

namespace {

bool cpuHasAvx2() {
#if defined(__x86_64__)
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

TraceInstructionSet chooseInstructionSet() {
    const char* forced = std::getenv("VKAS_TRACE_KERNEL");
    if (forced && std::strcmp(forced, "sse2") == 0) return TraceInstructionSet::Sse2;
    return cpuHasAvx2() ? TraceInstructionSet::Avx2 : TraceInstructionSet::Sse2;
}

}  // namespace

TraceInstructionSet traceInstructionSet() {
    static const TraceInstructionSet chosen = chooseInstructionSet();
    return chosen;
}

const char* instructionSetName(TraceInstructionSet set) {
    switch (set) {
        case TraceInstructionSet::Avx2: return "avx2";
        case TraceInstructionSet::Sse2: break;
    }
    return "sse2";
}

}  // namespace vkas
