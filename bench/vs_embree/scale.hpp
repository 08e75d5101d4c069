// The scale run (`--scale N`, issue 17): a bottom level of at least N triangles (copies of bunny-4m side by side,
// one mesh, one geometry) built by vkas as a deferred build joined by every thread and by Embree MEDIUM on as many
// threads; both traced with camera and diffuse rays on all threads and their hits compared (disagreements judged by
// the double-precision oracle, a few of them); time, peak memory per triangle (vkas: the structure buffer the
// sizes query asks for plus its scratch; Embree: the most its memory monitor saw during the build) and the sizes
// query against the built and compacted sizes, printed and written to the JSON.
#pragma once

#include "report.hpp"

#include <cstddef>

namespace vb {

void runScaleRun(size_t minTriangles, unsigned threads, size_t rays, const std::string& dataDir, Json& json);

}  // namespace vb
