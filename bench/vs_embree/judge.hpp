// The referee of the hit comparison: every ray where vkas and Embree disagree is decided by the brute-force,
// double-precision oracle of the test suite (tests/support/oracle.*, library vkas_oracle), which reads the same
// application buffers as the vkas build and tests every triangle of every instance.
//
// An engine's result is acceptable to the oracle when:
//   closest hit: the hit triangle is one of the oracle's candidates (required, or optional: within the oracle's
//     margin of an edge or of tMin/tMax), its t is within the candidate's t tolerance, and no required candidate
//     is nearer by more than the two tolerances;
//   any hit: the hit triangle is a candidate (vkas; Embree's rtcOccluded1 names no triangle: the oracle must have
//     some candidate);
//   miss: the oracle has no required candidate.
// The verdict: vkas right (Embree wrong), Embree right (vkas wrong), both acceptable (within the oracle's tolerance
// of an edge, of tMin/tMax, or a tie), or neither acceptable (the oracle explains neither: "unexplained").
// Each engine is also measured against the exact answer (no tolerance), in float units: the oracle's tolerance is
// 1e-5 of the coordinates involved, about 168 float units, so "both acceptable" still says which engine got the
// exact answer and by how much the other missed it.
#pragma once

#include "common.hpp"

#include <memory>
#include <string>

namespace vb {

enum class Verdict { VkasRight, EmbreeRight, BothAcceptable, Neither };

struct Judgement {
    Verdict verdict = Verdict::Neither;
    bool vkasOk = false, embreeOk = false;
    std::string vkas, embree;  // each engine's result, as the oracle sees it
    std::string oracle;        // the oracle's candidates (nearest first)
    std::string reason;        // why the verdict: the numbers that decide it
    // Against the exact answer (the oracle's double-precision computation without tolerances): how far each engine
    // is from it, in float units (one rounding, 2^-24, of the largest coordinate involved, moved into the
    // triangle's plane: 2^-24 scale / cos); 0: the engine's answer is the exact one.
    double vkasError = 0, embreeError = 0;
    bool exactVkas = false, exactEmbree = false;
};

class Judge {
public:
    explicit Judge(const Scene& scene);
    ~Judge();
    Judge(const Judge&) = delete;
    Judge& operator=(const Judge&) = delete;

    // `embree` of an any-hit ray (rtcOccluded1) names no triangle. Thread-safe.
    Judgement judge(const VkasRay& ray, const Hit& vkas, const Hit& embree, bool anyHit) const {
        return judge(ray, vkas, embree, anyHit, !anyHit);
    }
    // The same with the second answer's any hit naming its triangle or not (true: two vkas builds compared,
    // --compare-hits; the "Embree" side of the texts is then the other build).
    Judgement judge(const VkasRay& ray, const Hit& vkas, const Hit& embree, bool anyHit, bool embreeNamesTriangle) const;
    // Whether the hit's triangle is a candidate of the ray with t within its tolerance: judge()'s rule for an any hit
    // that names its triangle, without tracing the whole scene (a closest hit must also have no nearer required
    // candidate).
    bool hitsTriangle(const VkasRay& ray, const Hit& hit) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace vb
