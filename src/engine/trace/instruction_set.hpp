// The instruction set of every trace kernel in this process, chosen once (issue 36: one registry, as Embree's ISA
// selection is one): the batch kernel and the packet kernel (batch_kernel.cpp) and the ray query's node test
// (ray_query.cpp) each have a copy per instruction set and take the one named here. Every copy gives the same hits
// bit for bit (the same float operations lane by lane, no FMA), so the choice moves only the speed: the node tests
// are held to each other lane for lane (tests/engine/test_node_test.cpp), and the trace suites run once with the
// best the CPU has and once per lower set forced (VKAS_TRACE_KERNEL).
#pragma once

namespace vkas {

enum class TraceInstructionSet {
    Sse2,  // the baseline of x86-64 (and the scalar fallback elsewhere)
    Avx2,
    Avx512,  // AVX-512F and VL: the node test's comparisons in mask registers (node_intersector_avx512.hpp)
};

// The best the CPU has among those compiled in, unless the environment variable VKAS_TRACE_KERNEL names a lower one
// ("sse2" or "avx2"; a set the CPU lacks is never taken). Read once per process.
TraceInstructionSet traceInstructionSet();

// "sse2", "avx2" or "avx512", for reports and for VKAS_TRACE_KERNEL.
const char* instructionSetName(TraceInstructionSet set);

}  // namespace vkas
