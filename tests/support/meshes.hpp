// Procedural meshes for the tests (indexed, consistently wound where it matters).
#pragma once

#include <cmath>

#include "vkas_test.hpp"

namespace vt {

Mesh icosphere(int subdivisions);
Mesh terrain(int n, Rng& rng);                       // n x n quads, random heights
Mesh torusKnot(int segments, int sides, int p = 2, int q = 3);
Mesh triangleSoup(int count, Rng& rng, float size);  // random triangles in [-1, 1]^3
// nx x ny quads in the plane z = 0 covering [0, nx] x [0, ny]. Quad (i, j) is triangles 2(j nx + i) (below the
// diagonal from (i, j) to (i+1, j+1), i.e. x - i > y - j) and 2(j nx + i) + 1 (above it); both counter-clockwise
// seen from +z.
Mesh grid(int nx, int ny);
// Limits on the triangles randomSquareTessellation makes. The defaults (none) are the generator the
// watertightness group used until issue 13: it makes slivers whose random heights form near-vertical facets, which
// a ray tilted by rounding may legitimately cross three times. Splits that would break a limit are not made.
struct TessellationLimits {
    double maxSlope = INFINITY;  // |grad z| of every triangle at most this
    double minAltitude = 0;      // every triangle's smallest altitude in the xy plane at least this
};
// The unit square split into triangles around an interior point, then recursively split at random interior
// points, with a random z in [-0.05, 0.05] per vertex (a height field over the square, consistently wound).
// Boundary vertices are the 4 corners and 4 edge midpoints only.
Mesh randomSquareTessellation(int triangleTarget, Rng& rng, const TessellationLimits& limits = {});
// A closed fan of n triangles around a centre vertex (index 0), a height field over the xy plane.
Mesh closedFan(int n, Rng& rng);

}  // namespace vt
