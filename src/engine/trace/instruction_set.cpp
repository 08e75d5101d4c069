#include "engine/trace/instruction_set.hpp"

#include <cstdlib>
#include <cstring>
#include <initializer_list>

namespace vkas {

namespace {

// The best set this CPU (and its operating system: libgcc's probe checks the saved register state) can run.
TraceInstructionSet cpuInstructionSet() {
#if defined(__x86_64__)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) return TraceInstructionSet::Avx512;
    if (__builtin_cpu_supports("avx2")) return TraceInstructionSet::Avx2;
#endif
    return TraceInstructionSet::Sse2;
}

TraceInstructionSet chooseInstructionSet() {
    const TraceInstructionSet best = cpuInstructionSet();
    const char* forced = std::getenv("VKAS_TRACE_KERNEL");
    if (!forced) return best;
    for (TraceInstructionSet set : {TraceInstructionSet::Sse2, TraceInstructionSet::Avx2})
        if (std::strcmp(forced, instructionSetName(set)) == 0 && set < best) return set;
    return best;
}

}  // namespace

TraceInstructionSet traceInstructionSet() {
    static const TraceInstructionSet chosen = chooseInstructionSet();
    return chosen;
}

const char* instructionSetName(TraceInstructionSet set) {
    switch (set) {
        case TraceInstructionSet::Avx512: return "avx512";
        case TraceInstructionSet::Avx2: return "avx2";
        case TraceInstructionSet::Sse2: break;
    }
    return "sse2";
}

}  // namespace vkas
