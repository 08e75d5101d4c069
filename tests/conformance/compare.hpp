// Ray-by-ray comparison of two implementations' results for one differential case. Each result is first checked
// against the double-precision reference; then the two are compared with each other. Every accepted difference
// gets a named reason, proven with the reference's own intersections; anything else is a mismatch.
#pragma once

#include <string>

#include "diff_case.hpp"
#include "reference.hpp"

namespace diff {

enum class Verdict {
    Identical,             // same committed intersection (or the same candidate set), values within rounding
    Tie,                   // different primitives at the same t within rounding, both proven by the reference
    AnyHit,                // TerminateOnFirstHit: different first hits, both valid (the spec allows any)
    EdgeRounding,          // differ only in candidates within rounding of an edge, box face or tMin/tMax
    DuplicateCandidate,    // lavapipe returned a candidate twice in a geometry without NO_DUPLICATE (allowed)
    AabbFalsePositive,     // lavapipe returned an AABB candidate the ray misses (implementations may enlarge AABBs)
    LavapipeSharedEdge,    // lavapipe-notes 3: extra candidates on shared edges / closed-fan vertices
    LavapipeDegenerate,    // lavapipe-notes 2: lavapipe hit a degenerate triangle
    LavapipeInactiveHides, // lavapipe-notes 1: an inactive primitive hid active ones from lavapipe
    LavapipeFetchBlasIndex,  // lavapipe's position fetch took the primitive index as an index over the whole BLAS
    VkasWrong,             // vkas disagrees with the reference: a vkas bug
    Mismatch,              // an unexplained difference
    Count
};
const char* verdictName(Verdict v);
inline bool isFailure(Verdict v) { return v == Verdict::VkasWrong || v == Verdict::Mismatch; }

struct RayVerdict {
    Verdict verdict = Verdict::Identical;
    std::string detail;  // why, with the reference's numbers
};

RayVerdict compareRay(const Reference& reference, const Ray& ray, const Result& vkas, const Result& lavapipe);

std::string describe(const Ray& ray);        // hex floats, for reproduction
std::string describe(const Result& result);  // committed values and candidates

}  // namespace diff
