// The instruction set of every trace kernel in this process, chosen once (issue 36: one registry, as Embree's ISA
// selection is one): the batch kernel and the packet kernel (batch_kernel.cpp) and the ray query's node test
// (ray_query.cpp) each have a copy per instruction set and take the one named here. Every copy gives the same hits
// bit for bit (the same float operations lane by lane, no FMA), so the choice moves only the speed.
#pragma once

namespace vkas {

enum class TraceInstructionSet {
    Sse2,  // the baseline of x86-64 (and the scalar fallback elsewhere)
    Avx2,
};

// The best the CPU has among those compiled in, unless the environment variable VKAS_TRACE_KERNEL names a lower one
// ("sse2"; the tests run their trace suites both ways). Read once per process.
TraceInstructionSet traceInstructionSet();

// "sse2" or "avx2", for reports.
const char* instructionSetName(TraceInstructionSet set);

}  // namespace vkas
