// Reporting: the hit comparison between the engines (agreement, classified) and a small JSON writer.
#pragma once

#include "common.hpp"

#include <functional>
#include <string>

namespace vb {

// How two engines' results for the same rays compare. Closest hits: the same primitive (t compared), another
// primitive at the same t within tolerance (a tie: a shared edge or vertex, or coincident triangles), another hit
// whose nearer triangle was met within 1e-3 (barycentric) of an edge (the other engine passed by that edge), another
// hit not explained so, or hit against miss (at an edge of the hit triangle, at the ray's end, or not explained).
// The t tolerance is 1e-4 t + 16 float ulps of the largest coordinate of the ray's origin (the precision a float
// ray at that position has). Any-hit results: hit against miss only (classified with `refClosest`).
struct Agreement {
    size_t rays = 0, samePrimitive = 0, tie = 0, differentHitAtEdge = 0, differentHit = 0;
    size_t hitMiss = 0, hitMissAtEdge = 0, hitMissAtEnd = 0;
    double maxRelT = 0;    // same primitive: max |dt| / t
    double maxTolT = 0;    // same primitive: max |dt| / tolerance (<= 1: within float precision of the ray)
    size_t disagreements() const { return differentHit + hitMiss - hitMissAtEdge - hitMissAtEnd; }
};
Agreement compareHits(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b, bool anyHit,
                      const std::vector<Hit>* refClosest);
// Identical results (type, instance, primitive, t bit for bit): vkas's own paths against each other.
size_t countDifferent(const std::vector<Hit>& a, const std::vector<Hit>& b);
std::string describe(const Agreement& g, bool anyHit);
// Up to `limit` rays where the results differ (hit against miss, or t beyond the tolerance), one line each: the ray
// and both hits; `exactT(ray, hit)` gives the double-precision t of the ray on the hit's triangle plane.
std::vector<std::string> examples(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b,
                                  bool anyHit, size_t limit, const std::function<double(size_t, const Hit&)>& exactT);

class Json {
public:
    Json& begin(const char* key, char bracket);  // key may be null inside arrays; bracket '{' or '['
    Json& end(char bracket);
    Json& field(const char* key, double v);
    Json& field(const char* key, const std::string& v);
    Json& field(const char* key, const char* v) { return field(key, std::string(v)); }
    Json& field(const char* key, bool v);
    const std::string& str() const { return s_; }

private:
    void sep(const char* key);
    std::string s_;
    std::vector<bool> first_{true};
};

}  // namespace vb
