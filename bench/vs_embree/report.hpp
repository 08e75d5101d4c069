// Reporting: the hit comparison between the engines (agreement, classified) and a small JSON writer.
#pragma once

#include "common.hpp"
#include "judge.hpp"

#include <string>

namespace vb {

// How two engines' results for the same rays compare. Closest hits: the same primitive (t compared), another
// primitive at the same t within tolerance (a tie: a shared edge or vertex, or coincident triangles), another hit
// whose nearer triangle was met within 1e-3 (barycentric) of an edge (the other engine passed by that edge), another
// hit, or hit against miss (at an edge of the hit triangle, at the ray's end (finite tMax), or elsewhere). The t
// tolerance is 1e-4 t + 16 float ulps of the largest coordinate of the ray's origin (the precision a float ray at
// that position has). Any-hit results: hit against miss only (classified with `refClosest`).
// Every ray that differs (differingRays) is decided by the oracle (judge.hpp); "unexplained" counts the rays where
// it accepts neither engine.
struct Agreement {
    size_t rays = 0, samePrimitive = 0, sameBeyondT = 0, tie = 0, differentHitAtEdge = 0, differentHit = 0;
    size_t hitMiss = 0, hitMissAtEdge = 0, hitMissAtEnd = 0;
    double maxRelT = 0;    // same primitive: max |dt| / t
    double maxTolT = 0;    // same primitive: max |dt| / tolerance (<= 1: within float precision of the ray)
    // The oracle's verdicts on the differing rays.
    size_t differing = 0, bothAcceptable = 0, vkasRight = 0, embreeRight = 0, neither = 0;
    // Against the exact answer (no tolerance): rays where only vkas / only Embree / neither gets it, and the largest
    // distance (float units, judge.hpp) by which each engine misses it.
    size_t exactVkasOnly = 0, exactEmbreeOnly = 0, exactNeither = 0;
    double maxVkasError = 0, maxEmbreeError = 0;
    size_t disagreements() const { return neither; }  // not explained by the oracle
};
// The class of one ray's pair of results (see above); `refClosest`: any-hit rays, the reference's closest hit.
enum class Category { Same, SameBeyondT, Tie, OtherPastEdge, Other, HitMissAtEdge, HitMissAtEnd, HitMiss };
Category classify(const VkasRay& ray, const Hit& a, const Hit& b, bool anyHit, const Hit& refClosest);
const char* categoryName(Category c);
// The rays whose results differ: hit against miss; closest hits: another primitive or instance, or the same one
// with t beyond the tolerance above.
std::vector<size_t> differingRays(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b,
                                  bool anyHit);
// a: vkas, b: Embree; verdicts[k]: the oracle's verdict on ray differing[k].
Agreement compareHits(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b, bool anyHit,
                      const std::vector<Hit>* refClosest, const std::vector<size_t>& differing,
                      const std::vector<Judgement>& verdicts);
// Identical results (type, instance, primitive, t bit for bit): vkas's own paths against each other.
size_t countDifferent(const std::vector<Hit>& a, const std::vector<Hit>& b);
std::string describe(const Agreement& g, bool anyHit);
const char* verdictName(Verdict v);
// One disagreeing ray, several lines: the ray (hex floats), vkas's and Embree's results as the oracle sees them, the
// oracle's candidates and its verdict.
std::string disagreementText(const char* kind, size_t index, const VkasRay& ray, Category c, const Judgement& j,
                             bool anyHit);

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
