#include "compare.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdarg>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>
#include <vector>

namespace diff {

namespace {

constexpr uint32_t kRayTerminateOnFirstHit = 0x4;

const char* const kVerdictNames[] = {"identical",          "tie",
                                     "any-hit",            "edge-rounding",
                                     "duplicate-candidate", "aabb-false-positive",
                                     "lavapipe-shared-edge", "lavapipe-degenerate-hit",
                                     "lavapipe-inactive-hides", "lavapipe-fetch-blas-index",
                                     "VKAS-WRONG",
                                     "MISMATCH"};
static_assert(sizeof kVerdictNames / sizeof *kVerdictNames == size_t(Verdict::Count));

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return buf;
}

uint32_t candidateTypeOf(const Result& r) { return r.committedType == 2 ? 1u : 0u; }

const Expected* committedExpected(const ExpectedRay& exp, const Result& r) {
    return exp.find(candidateTypeOf(r), r.instanceId, r.geometryIndex, r.primitiveIndex);
}

// Is `r` a correct committed result for the ray? Sets *why when not.
bool validClosest(const Reference& ref, const ExpectedRay& exp, const Ray& ray, const Result& r, std::string* why) {
    const bool anyHit = ray.flags & kRayTerminateOnFirstHit;
    if (r.committedType == 0) {
        for (const Expected& e : exp.candidates)
            if (e.accepted && !e.optional && !e.acceptOptional) {
                *why = format("missed a required hit: type %u instance %u geometry %u primitive %u at t %.9g", e.type,
                              e.instanceId, e.geometryIndex, e.primitiveIndex, e.t);
                return false;
            }
        return true;
    }
    if (r.committedType > 2) {
        *why = format("committed type %u", r.committedType);
        return false;
    }
    const Expected* e = committedExpected(exp, r);
    if (!e || !(e->accepted || e->acceptOptional)) {
        *why = e ? "committed a candidate the ray program does not accept"
                 : "committed a primitive the ray does not meet (reference has no such candidate)";
        return false;
    }
    const double tTol = e->tTolerance + 1e-6 * std::fabs(e->t);
    if (!(std::fabs(double(r.t) - e->t) <= tTol)) {
        *why = format("t %.9g, reference %.9g (tolerance %.3g)", r.t, e->t, tTol);
        return false;
    }
    if (!anyHit)
        for (const Expected& y : exp.candidates)
            if (y.accepted && !y.optional && !y.acceptOptional && y.t < e->t - (y.tTolerance + tTol)) {
                *why = format("a closer required hit exists: type %u instance %u geometry %u primitive %u at t %.9g",
                              y.type, y.instanceId, y.geometryIndex, y.primitiveIndex, y.t);
                return false;
            }
    const Instance& inst = ref.scene().instances[r.instanceId];
    if (r.customIndex != (inst.customIndex & 0xFF'FFFFu) || r.sbtOffset != (inst.sbtOffset & 0xFF'FFFFu)) {
        *why = format("custom index %u / SBT offset %u, instance has %u / %u", r.customIndex, r.sbtOffset,
                      inst.customIndex & 0xFF'FFFFu, inst.sbtOffset & 0xFF'FFFFu);
        return false;
    }
    if (r.committedType == 1) {
        const oracle::Candidate& c = e->triangle;
        if (!c.facingAmbiguous && (r.frontFace != 0) != c.frontFace) {
            *why = format("front face %u, reference %d", r.frontFace, int(c.frontFace));
            return false;
        }
        const double bTol = std::max(c.baryTolerance, 1e-5) * 2;
        if (!(std::fabs(r.barycentrics[0] - c.bary[0]) <= bTol && std::fabs(r.barycentrics[1] - c.bary[1]) <= bTol)) {
            *why = format("barycentrics (%.9g, %.9g), reference (%.9g, %.9g)", r.barycentrics[0], r.barycentrics[1],
                          c.bary[0], c.bary[1]);
            return false;
        }
        if (r.positionsValid) {
            const oracle::Triangle* tri = ref.triangle(r.instanceId, r.geometryIndex, r.primitiveIndex);
            for (int i = 0; i < 3; ++i)
                for (int k = 0; k < 3; ++k) {
                    const double want = tri->v[size_t(i)][size_t(k)];
                    if (!(std::fabs(r.positions[i][k] - want) <= 1e-6 * std::max(1.0, std::fabs(want)))) {
                        *why = format("fetched position %d.%d = %.9g, reference %.9g", i, k, r.positions[i][k], want);
                        uint32_t g, p;
                        if (ref.findTriangle(r.instanceId, r.positions, &g, &p))
                            *why += format("; the fetched vertices are those of geometry %u primitive %u", g, p);
                        return false;
                    }
                }
        }
    } else if (r.frontFace != 0 || r.positionsValid) {
        *why = "a generated hit reported a front face or positions";
        return false;
    }
    return true;
}

using Key = std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>;
Key key(const CandidateRecord& c) { return {c.type, c.instanceId, c.geometryIndex, c.primitiveIndex}; }
Key key(const Expected& e) { return {e.type, e.instanceId, e.geometryIndex, e.primitiveIndex}; }

std::map<Key, uint32_t> candidateSet(const Result& r) {
    std::map<Key, uint32_t> m;
    for (uint32_t i = 0; i < std::min(r.candidateCount, kMaxRecordedCandidates); ++i) ++m[key(r.candidates[i])];
    return m;
}

size_t requiredCount(const ExpectedRay& exp) {
    return size_t(std::count_if(exp.candidates.begin(), exp.candidates.end(), [](const Expected& e) { return !e.optional; }));
}

RayVerdict compareCount(const Reference& ref, const ExpectedRay& exp, const Result& v, const Result& l) {
    const size_t required = requiredCount(exp), total = exp.candidates.size();
    if (v.candidateCount > kMaxRecordedCandidates || l.candidateCount > kMaxRecordedCandidates) {
        // Only the counts can be checked.
        if (v.candidateCount < required || v.candidateCount > total)
            return {Verdict::VkasWrong, format("vkas counted %u candidates, reference %zu required of %zu", v.candidateCount,
                                               required, total)};
        if (l.candidateCount < required)
            return {Verdict::Mismatch, format("lavapipe counted %u candidates, reference requires %zu", l.candidateCount,
                                              required)};
        return {v.candidateCount == l.candidateCount ? Verdict::Identical : Verdict::EdgeRounding,
                format("counts only: vkas %u lavapipe %u, required %zu of %zu", v.candidateCount, l.candidateCount,
                       required, total)};
    }
    const auto vs = candidateSet(v), ls = candidateSet(l);
    // vkas: each candidate once, each one the reference knows, every required one present.
    for (const auto& [k, n] : vs) {
        const Expected* e = exp.find(std::get<0>(k), std::get<1>(k), std::get<2>(k), std::get<3>(k));
        if (!e) return {Verdict::VkasWrong, format("vkas returned a candidate the ray does not meet: type %u instance %u geometry %u primitive %u",
                                                    std::get<0>(k), std::get<1>(k), std::get<2>(k), std::get<3>(k))};
        if (n > 1) return {Verdict::VkasWrong, format("vkas returned instance %u geometry %u primitive %u %u times",
                                                       std::get<1>(k), std::get<2>(k), std::get<3>(k), n)};
    }
    for (const Expected& e : exp.candidates)
        if (!e.optional && !vs.count(key(e)))
            return {Verdict::VkasWrong, format("vkas missed required candidate type %u instance %u geometry %u primitive %u (t %.9g)",
                                                e.type, e.instanceId, e.geometryIndex, e.primitiveIndex, e.t)};
    // lavapipe: every required one present; extras explained.
    Verdict worst = Verdict::Identical;
    std::string detail;
    auto note = [&](Verdict verdict, const std::string& d) {
        if (int(verdict) > int(worst)) worst = verdict, detail = d;
    };
    for (const Expected& e : exp.candidates)
        if (!e.optional && !ls.count(key(e))) {
            if (ref.blasHasInactivePrimitives(e.instanceId))
                note(Verdict::LavapipeInactiveHides, format("lavapipe missed instance %u geometry %u primitive %u; its BLAS has inactive primitives",
                                                            e.instanceId, e.geometryIndex, e.primitiveIndex));
            else
                note(Verdict::Mismatch, format("lavapipe missed required candidate type %u instance %u geometry %u primitive %u (t %.9g)",
                                               e.type, e.instanceId, e.geometryIndex, e.primitiveIndex, e.t));
        }
    for (const auto& [k, n] : ls) {
        const auto [type, inst, geom, prim] = k;
        const Expected* e = exp.find(type, inst, geom, prim);
        if (!e) {
            if (type == 1) note(Verdict::AabbFalsePositive, format("lavapipe returned AABB instance %u geometry %u primitive %u, which the ray misses", inst, geom, prim));
            else if (ref.isDegenerate(inst, geom, prim)) note(Verdict::LavapipeDegenerate, format("lavapipe returned degenerate triangle instance %u geometry %u primitive %u", inst, geom, prim));
            else note(Verdict::Mismatch, format("lavapipe returned a candidate the ray does not meet: type %u instance %u geometry %u primitive %u", type, inst, geom, prim));
            continue;
        }
        if (n > 1) {
            if (e->noDuplicates) note(Verdict::Mismatch, format("lavapipe returned instance %u geometry %u primitive %u %u times despite NO_DUPLICATE_ANY_HIT_INVOCATION", inst, geom, prim, n));
            else note(Verdict::DuplicateCandidate, format("lavapipe returned instance %u geometry %u primitive %u %u times", inst, geom, prim, n));
        }
        if (!vs.count(k)) {  // optional (vkas has every required one): a candidate within rounding of an edge
            const bool sharedEdge = std::any_of(vs.begin(), vs.end(), [&](const auto& other) {
                const Expected* o = exp.find(std::get<0>(other.first), std::get<1>(other.first), std::get<2>(other.first), std::get<3>(other.first));
                return o && o->type == 0 && type == 0 && std::fabs(o->t - e->t) <= o->tTolerance + e->tTolerance;
            });
            note(sharedEdge ? Verdict::LavapipeSharedEdge : Verdict::EdgeRounding,
                 format("lavapipe also returned instance %u geometry %u primitive %u (t %.9g) within rounding of an edge%s",
                        inst, geom, prim, e->t, sharedEdge ? "; vkas returned its neighbour at the same t" : ""));
        }
    }
    for (const auto& [k, n] : vs)
        if (!ls.count(k))
            note(Verdict::EdgeRounding, format("vkas returned optional instance %u geometry %u primitive %u; lavapipe did not",
                                               std::get<1>(k), std::get<2>(k), std::get<3>(k)));
    return {worst, detail};
}

}  // namespace

const char* verdictName(Verdict v) { return kVerdictNames[size_t(v)]; }

RayVerdict compareRay(const Reference& ref, const Ray& ray, const Result& v, const Result& l) {
    const ExpectedRay exp = ref.expect(ray);
    if (ray.mode == kModeCount) return compareCount(ref, exp, v, l);

    std::string whyV, whyL;
    if (!validClosest(ref, exp, ray, v, &whyV)) return {Verdict::VkasWrong, "vkas: " + whyV};
    if (!validClosest(ref, exp, ray, l, &whyL)) {
        if (l.committedType == 1 && l.positionsValid && l.geometryIndex != 0) {
            // Everything but the positions right, and the positions those of the triangle whose index is the
            // primitive index when the BLAS's geometries are numbered as one array?
            Result withoutPositions = l;
            withoutPositions.positionsValid = 0;
            std::string unused;
            uint32_t g = 0, p = 0;
            const oracle::Triangle* t = ref.triangleByBlasIndex(l.instanceId, l.primitiveIndex, &g, &p);
            bool same = t != nullptr;
            for (int i = 0; i < 3 && same; ++i)
                for (int k = 0; k < 3 && same; ++k)
                    same = std::fabs(l.positions[i][k] - t->v[size_t(i)][size_t(k)]) <=
                           1e-6 * std::max(1.0, std::fabs(t->v[size_t(i)][size_t(k)]));
            if (same && validClosest(ref, exp, ray, withoutPositions, &unused))
                return {Verdict::LavapipeFetchBlasIndex,
                        format("lavapipe fetched the vertices of geometry %u primitive %u (BLAS-wide triangle %u) for "
                               "a hit on geometry %u primitive %u",
                               g, p, l.primitiveIndex, l.geometryIndex, l.primitiveIndex)};
        }
        if (l.committedType == 1 && ref.isDegenerate(l.instanceId, l.geometryIndex, l.primitiveIndex))
            return {Verdict::LavapipeDegenerate, "lavapipe hit degenerate triangle: " + whyL};
        const bool hidden = v.committedType != 0 && (l.committedType == 0 || l.t > v.t) &&
                            ref.blasHasInactivePrimitives(v.instanceId);
        if (hidden) return {Verdict::LavapipeInactiveHides, "lavapipe: " + whyL + "; vkas's hit is in a BLAS with inactive primitives"};
        return {Verdict::Mismatch, "lavapipe: " + whyL};
    }
    if (v.committedType == 0 && l.committedType == 0) return {Verdict::Identical, ""};
    if (v.committedType != 0 && l.committedType != 0 && v.committedType == l.committedType &&
        v.instanceId == l.instanceId && v.geometryIndex == l.geometryIndex && v.primitiveIndex == l.primitiveIndex) {
        if (v.frontFace != l.frontFace && !committedExpected(exp, v)->triangle.facingAmbiguous)
            return {Verdict::Mismatch, "front faces differ"};
        if (v.positionsValid != l.positionsValid) return {Verdict::Mismatch, "only one side fetched positions"};
        return {Verdict::Identical, ""};
    }
    if (v.committedType != 0 && l.committedType != 0) {
        const Expected* ev = committedExpected(exp, v);
        const Expected* el = committedExpected(exp, l);
        if (ray.flags & kRayTerminateOnFirstHit)
            return {Verdict::AnyHit, format("first hits differ (both valid): vkas t %.9g, lavapipe t %.9g", ev->t, el->t)};
        if (std::fabs(ev->t - el->t) <= ev->tTolerance + el->tTolerance + 1e-6 * std::fabs(ev->t))
            return {Verdict::Tie, format("vkas instance %u geometry %u primitive %u at double t %.17g; lavapipe instance %u geometry %u primitive %u at double t %.17g",
                                         v.instanceId, v.geometryIndex, v.primitiveIndex, ev->t, l.instanceId,
                                         l.geometryIndex, l.primitiveIndex, el->t)};
        // Both valid but not at the same t: the closer one is within rounding of tMin/tMax or an edge (optional),
        // so the other side may skip it.
        const Expected* closer = ev->t < el->t ? ev : el;
        if (closer->optional || closer->acceptOptional)
            return {Verdict::EdgeRounding, format("%s hit instance %u geometry %u primitive %u at t %.9g, within rounding of an edge or the t interval; the other side skipped it",
                                                  closer == ev ? "vkas" : "lavapipe", closer->instanceId,
                                                  closer->geometryIndex, closer->primitiveIndex, closer->t)};
        return {Verdict::Mismatch, "different hits that are not a tie"};
    }
    // One side hit, the other missed, and both are valid: the hit is within rounding of an edge or the interval.
    // When lavapipe hit and vkas met a neighbour at the same point (and the confirmation rule rejected it), the
    // difference comes from lavapipe returning several triangles at one edge or vertex.
    if (l.committedType == 1) {
        const Expected* el = committedExpected(exp, l);
        for (uint32_t i = 0; i < std::min(v.candidateCount, kMaxRecordedCandidates); ++i) {
            const CandidateRecord& c = v.candidates[i];
            const Expected* ec = exp.find(c.type, c.instanceId, c.geometryIndex, c.primitiveIndex);
            if (c.type == 0 && ec && ec != el && std::fabs(ec->t - el->t) <= ec->tTolerance + el->tTolerance)
                return {Verdict::LavapipeSharedEdge,
                        format("lavapipe committed instance %u geometry %u primitive %u at t %.9g; vkas returned its "
                               "neighbour primitive %u at the same point, which the ray program did not confirm",
                               l.instanceId, l.geometryIndex, l.primitiveIndex, el->t, c.primitiveIndex)};
        }
    }
    return {Verdict::EdgeRounding, v.committedType ? "vkas hit an optional candidate, lavapipe missed it"
                                                   : "lavapipe hit an optional candidate, vkas missed it"};
}

std::string describe(const Ray& r) {
    return format("origin (%a, %a, %a) direction (%a, %a, %a) tMin %a tMax %a flags 0x%x cullMask 0x%x mode %u",
                  r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2], r.tMin, r.tMax,
                  r.flags, r.cullMask, r.mode);
}

std::string describe(const Result& r) {
    std::string s = format("committed type %u instance %u custom %u sbt %u geometry %u primitive %u t %.9g bary (%.9g %.9g) front %u; %u candidates:",
                           r.committedType, r.instanceId, r.customIndex, r.sbtOffset, r.geometryIndex, r.primitiveIndex,
                           r.t, r.barycentrics[0], r.barycentrics[1], r.frontFace, r.candidateCount);
    for (uint32_t i = 0; i < std::min(r.candidateCount, kMaxRecordedCandidates); ++i)
        s += format(" %s%u/%u/%u", r.candidates[i].type ? "A" : "T", r.candidates[i].instanceId,
                    r.candidates[i].geometryIndex, r.candidates[i].primitiveIndex);
    return s;
}

}  // namespace diff
