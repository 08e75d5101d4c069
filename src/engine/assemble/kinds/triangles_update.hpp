// The update of triangle geometries without motion (triangles_update.cpp), the refit and activity entries of
// kTriangleKind's table row (triangles.cpp).
#pragma once

#include "engine/assemble/refit.hpp"

namespace vkas {

// Refits job.src into job.dst: the leaves re-fetched with the reader specialised for their geometry (one float
// geometry without a transform: the pipelined two-pass refit).
void refitTriangles(const RefitJob& job);

// VUIDs 03663 / 03664 for triangles: active = no NaN vertex X.
ActivityViolation triangleActivity(const RefitJob& job);

}  // namespace vkas
