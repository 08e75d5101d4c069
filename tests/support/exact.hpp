// Exact arithmetic for the watertightness tests: an exact ray/triangle crossing count, used as the expectation.
//
// `Exact` is a dyadic rational (a signed big integer times a power of two). Every finite float and double is one,
// and sums, differences and products of dyadic rationals are dyadic rationals, so the polynomials below (degree 4
// at most in the float inputs) are evaluated with no rounding at all. It is slow; `exactCrossings` uses it only
// where a double evaluation with a proven error bound cannot decide a sign.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vkas_test.hpp"

namespace vt {

class Exact {
  public:
    Exact() = default;
    explicit Exact(double v);  // exact; v finite
    friend Exact operator+(const Exact& a, const Exact& b);
    friend Exact operator-(const Exact& a, const Exact& b);
    friend Exact operator*(const Exact& a, const Exact& b);
    Exact operator-() const;
    int sign() const { return mag_.empty() ? 0 : (neg_ ? -1 : 1); }
    double approx() const;  // nearest-ish double, for messages

  private:
    bool neg_ = false;
    std::vector<uint32_t> mag_;  // little-endian magnitude, no leading (most significant) zero limbs; empty: zero
    int64_t exp_ = 0;            // value = (neg ? -1 : 1) * mag * 2^exp
    void trim();
};

// One triangle that a ray crosses, decided exactly.
struct ExactCrossing {
    uint32_t triangle = 0;
    bool front = false;      // N = (v1 - v0) x (v2 - v0) points against the ray direction (the spec's front face)
    bool perturbed = false;  // the exact ray meets an edge or vertex of it: decided by the symbolic perturbation
};

// Crossings of the exact line o + t d, tMin < t < tMax, with the triangles of `mesh`, in exact arithmetic.
// A ray through an edge or a vertex is decided by symbolic perturbation: the line is translated by
// (e, e^2, e^3), e > 0 infinitesimal, which is a real translation of the line, so the result is the count of a
// real line arbitrarily close to the given one, and a shared edge or vertex is counted exactly once. Triangles
// whose projection along d is degenerate (edge-on) are never crossed.
//
// `nearSilhouette` and `nearBoundary` say whether the ray passes within `tolerance` (a distance measured
// perpendicular to d) of a silhouette edge (an edge whose two triangles face opposite ways along d, where the
// count changes by two) or of an open boundary edge (an edge of one triangle, where it changes by one): there,
// rounding of the ray or of the float evaluation may legitimately change the count; elsewhere it may not.
struct ExactCount {
    std::vector<ExactCrossing> crossings;
    int front = 0, back = 0;
    bool anyPerturbed = false;
    bool nearSilhouette = false, nearBoundary = false;
    double closestCriticalEdge = 1e300;  // distance (perpendicular to d) to the nearest silhouette or boundary edge
                                         // among those near the ray (1e300: none near)
    std::string str() const;
};

// For repeated queries against one mesh: edge adjacency and, per axis, a uniform grid of the triangles' bounding
// boxes over the other two axes are made once, so that a query tests only the triangles near the ray (all that can
// be crossed, or within the tolerance).
class ExactMeshOracle {
  public:
    explicit ExactMeshOracle(const Mesh& mesh);
    ExactCount count(const Float3& origin, const Float3& direction, float tMin, float tMax, double tolerance) const;
    // Whether the line crosses triangle `t` (any t) or passes within `tolerance` of one of its edges.
    bool crossesOrNear(uint32_t t, const Float3& origin, const Float3& direction, double tolerance) const;

  private:
    const Mesh& mesh_;
    struct Edge {
        uint32_t a, b;   // a < b
        int32_t tri[2];  // triangles using it (tri[1] = -1: an open boundary edge); more than two: tri[1] = -2
    };
    std::vector<Edge> edges_;
    std::vector<std::array<uint32_t, 3>> triangleEdges_;
    std::vector<std::array<double, 6>> boxes_;  // per triangle: lower xyz, upper xyz
    double lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0};
    int cells_ = 1;                                       // per side
    std::array<std::vector<std::vector<uint32_t>>, 3> grid_;  // grid_[k]: over axes (k+1)%3, (k+2)%3
    // The triangles that can be crossed by, or come within `tolerance` of, the line.
    std::vector<uint32_t> near(const Float3& o, const Float3& d, double tolerance) const;
    // The common sign of the three perturbed edge functions of triangle idx, or 0. rel: its vertices minus o.
    int edgeSigns(const uint32_t idx[3], const std::array<double, 3> rel[3], const Float3& o, const Float3& d,
                  bool& perturbed) const;
    int facing(uint32_t t, const Float3& d) const;  // sign of N . d in double, 0 when too close to call
};

}  // namespace vt
