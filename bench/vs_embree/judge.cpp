#include "judge.hpp"

#include "vkas_side.hpp"

#include <oracle.hpp>

#include <algorithm>
#include <cstdarg>
#include <cstdio>

namespace vb {
namespace {

std::string format(const char* fmt, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return buf;
}

bool isOptional(const oracle::TriangleTest& x) {
    return !x.inside || !x.inRange || x.cosine < 1e-6 || x.baryTolerance > 0.5;
}

// The edge nearest the hit point: the smallest weight.
int nearestEdge(const oracle::TriangleTest& x) {
    return int(std::min_element(x.bary, x.bary + 3) - x.bary);
}

// The oracle's numbers for one triangle: t and its tolerance, the weights and the margin, and at the nearest edge
// the distance of the hit point from it against the distance the tolerance allows (both in object space).
std::string numbers(const oracle::TriangleTest& x) {
    const int k = nearestEdge(x);
    return format("oracle t %.9g (tolerance %.3g), weights (%.6g, %.6g, %.6g), margin %.3g; nearest edge: opposite "
                  "vertex %d, hit point %.3g from it (object space; the tolerance allows %.3g, at cos %.3g)",
                  x.t, x.tTolerance, x.bary[0], x.bary[1], x.bary[2], x.baryTolerance, k, x.distance[k],
                  x.tolDistance, x.cosine);
}

std::string whyOptional(const oracle::TriangleTest& x) {
    std::string s;
    auto add = [&](const std::string& part) { s += (s.empty() ? "" : "; ") + part; };
    if (!x.inside) {
        const int k = nearestEdge(x);
        add(format("weight %.3g of vertex %d is within the margin %.3g of the edge", x.bary[k], k, x.baryTolerance));
    }
    if (!x.inRange) add("t is within its tolerance of tMin or tMax");
    if (x.cosine < 1e-6) add("nearly edge-on");
    if (x.baryTolerance > 0.5) add("ill-conditioned (the whole triangle is within the tolerance)");
    return s;
}

std::string candidateText(const oracle::Candidate& c) {
    return format("inst %d prim %d t %.9g (tolerance %.3g) uv (%.6g, %.6g) margin %.3g %s", c.instanceId,
                  c.primitiveIndex, c.t, c.tTolerance, c.bary[0], c.bary[1], c.baryTolerance,
                  c.optional ? "optional" : "required");
}

// One float unit at a triangle: how far in its plane the hit point of a float object-space ray can move for one
// rounding (2^-24) of the largest coordinate the computation involves (the oracle's scale): 2^-24 scale / cos.
double unitOf(const oracle::TriangleTest& x) {
    return std::ldexp(x.scale, -24) / std::max(x.cosine, 1e-12);
}

// The exact hit point's distance inside the triangle's nearest edge (object space; < 0: outside).
double minDistance(const oracle::TriangleTest& x) {
    return std::min({x.distance[0], x.distance[1], x.distance[2]});
}

// In float units, how far the exact ray misses the triangle (0 when it hits it within (tMin, tMax)); infinite when
// the ray's t there is outside [tMin, tMax] or the ray is edge-on.
double outsideBy(const oracle::TriangleTest& x, double tMin, double tMax) {
    if (x.status == oracle::TriangleStatus::Inactive || x.status == oracle::TriangleStatus::EdgeOn || !(x.cosine > 0))
        return INFINITY;
    if (!(x.t > tMin && x.t < tMax)) return INFINITY;
    return std::max(0.0, -minDistance(x) / unitOf(x));
}

struct Assessment {
    bool ok = false;
    bool hit = false, identified = false, optional = false;
    oracle::TriangleTest x;
    std::string text, why;  // why: the deciding numbers, short
};

}  // namespace

struct Judge::Impl {
    oracle::Scene scene;
};

Judge::Judge(const Scene& s) : impl_(std::make_unique<Impl>()) {
    // The oracle fetches the same buffers the vkas build reads, and decodes the same instance records.
    const VkAccelerationStructureGeometryKHR g = triangleGeometry(s.mesh, s.mesh.vertices.data());
    const VkAccelerationStructureBuildRangeInfoKHR range{uint32_t(s.mesh.triangleCount()), 0, 0, 0};
    auto blas = std::make_shared<oracle::Blas>();
    blas->geometries.push_back(oracle::fetchTriangles(g, range));
    blas->computeBounds();
    const uint64_t reference = 1;  // any non-zero value: the records' reference, resolved to `blas` below
    const auto records = instanceRecords(s.instances, reinterpret_cast<VkAccelerationStructureKHR>(reference));
    for (const VkAccelerationStructureInstanceKHR& r : records)
        impl_->scene.instances.push_back(oracle::decodeInstance(
            &r, [&](uint64_t ref) { return ref == reference ? std::shared_ptr<const oracle::Blas>(blas) : nullptr; }));
}

Judge::~Judge() = default;

bool Judge::hitsTriangle(const VkasRay& ray, const Hit& h) const {
    if (!h.hit()) return false;
    const oracle::Ray r{{ray.origin[0], ray.origin[1], ray.origin[2]}, ray.tMin,
                        {ray.direction[0], ray.direction[1], ray.direction[2]}, ray.tMax};
    const oracle::TriangleTest x = oracle::examineTriangle(impl_->scene, r, h.inst, 0, h.prim);
    return x.status == oracle::TriangleStatus::Candidate && std::abs(double(h.t) - x.t) <= x.tTolerance;
}

Judgement Judge::judge(const VkasRay& ray, const Hit& vkas, const Hit& embree, bool anyHit, bool embreeNamesTriangle) const {
    const oracle::Ray r{{ray.origin[0], ray.origin[1], ray.origin[2]}, ray.tMin,
                        {ray.direction[0], ray.direction[1], ray.direction[2]}, ray.tMax};
    oracle::Result res = oracle::trace(impl_->scene, r, 0, 0xFF);
    std::sort(res.candidates.begin(), res.candidates.end(),
              [](const oracle::Candidate& a, const oracle::Candidate& b) { return a.t < b.t; });
    const oracle::Candidate* required = res.closestRequired();

    auto assess = [&](const Hit& h, bool identified) {
        Assessment a;
        a.hit = h.hit(), a.identified = identified;
        if (!h.hit()) {
            a.ok = required == nullptr;
            a.text = a.ok ? "miss: acceptable (the oracle has no required candidate)"
                          : "miss: NOT acceptable: it misses the required candidate " + candidateText(*required);
            a.why = a.ok ? "a miss, no required candidate"
                         : format("misses inst %d prim %d at t %.9g (required: weights >= %.3g above the margin)",
                                  required->instanceId, required->primitiveIndex, required->t,
                                  std::min({1 - required->bary[0] - required->bary[1], required->bary[0],
                                            required->bary[1]}) - required->baryTolerance);
            return a;
        }
        if (!identified) {  // rtcOccluded1: occluded, by something
            a.ok = !res.candidates.empty();
            a.optional = a.ok && required == nullptr;
            a.text = a.ok ? format("occluded (no triangle named): acceptable: the oracle has %zu candidates (%zu required)",
                                   res.candidates.size(), res.requiredCount())
                          : "occluded (no triangle named): NOT acceptable: the oracle has no candidate";
            a.why = a.ok ? (a.optional ? "occluded by an optional candidate" : "occluded by a required candidate")
                         : "occluded, but the oracle has no candidate";
            return a;
        }
        a.x = oracle::examineTriangle(impl_->scene, r, h.inst, 0, h.prim);
        const oracle::TriangleTest& x = a.x;
        const std::string head = format("inst %d prim %d t %.9g uv (%.6g, %.6g): ", h.inst, h.prim, h.t, h.u, h.v);
        if (x.status != oracle::TriangleStatus::Candidate) {
            a.text = head + "NOT acceptable: not a candidate (" + oracle::triangleStatusName(x.status) + "): " + numbers(x);
            const int k = nearestEdge(x);
            a.why = x.status == oracle::TriangleStatus::Outside
                        ? format("hits inst %d prim %d, which the exact ray passes %.3g outside (weight %.3g < -margin %.3g)",
                                 h.inst, h.prim, -x.distance[k], x.bary[k], x.baryTolerance)
                        : format("hits inst %d prim %d, not a candidate (%s)", h.inst, h.prim,
                                 oracle::triangleStatusName(x.status));
            return a;
        }
        a.optional = isOptional(x);
        const double dt = std::abs(double(h.t) - x.t);
        const bool tOk = dt <= x.tTolerance;
        const oracle::Candidate* nearer = nullptr;
        if (!anyHit)
            for (const oracle::Candidate& c : res.candidates)
                if (!c.optional && !(c.instanceId == h.inst && c.primitiveIndex == h.prim) &&
                    c.t + c.tTolerance + x.tTolerance < x.t) {
                    nearer = &c;
                    break;
                }
        a.ok = tOk && !nearer;
        a.text = head + (a.ok ? "acceptable: " : "NOT acceptable: ") +
                 (a.optional ? "an optional candidate (" + whyOptional(x) + ")" : std::string("a required candidate")) +
                 format(", |t - oracle t| = %.3g%s; ", dt, tOk ? "" : " beyond the tolerance") + numbers(x);
        if (nearer) a.text += "; passes the nearer required candidate " + candidateText(*nearer);
        a.why = !tOk      ? format("inst %d prim %d at t %.9g, %.3g from the oracle's t (tolerance %.3g)", h.inst, h.prim,
                                   h.t, dt, x.tTolerance)
                : nearer  ? format("passes the required inst %d prim %d at t %.9g", nearer->instanceId,
                                   nearer->primitiveIndex, nearer->t)
                : a.optional ? format("inst %d prim %d is optional: %s", h.inst, h.prim, whyOptional(x).c_str())
                             : format("inst %d prim %d is a required candidate", h.inst, h.prim);
        return a;
    };

    const Assessment av = assess(vkas, true), ae = assess(embree, embreeNamesTriangle);

    // The exact answer: the oracle's double-precision computation without tolerances (every weight >= 0,
    // tMin < t < tMax), and how far each engine is from it, in units of the float precision of the object-space
    // ray at that triangle (unitOf).
    const oracle::Candidate* exact = nullptr;
    for (const oracle::Candidate& c : res.candidates)
        if (std::min({1 - c.bary[0] - c.bary[1], c.bary[0], c.bary[1]}) >= 0 && c.t > ray.tMin && c.t < ray.tMax) {
            exact = &c;  // nearest first
            break;
        }
    const oracle::TriangleTest xe =
        exact ? oracle::examineTriangle(impl_->scene, r, exact->instanceId, 0, exact->primitiveIndex) : oracle::TriangleTest{};
    auto error = [&](const Hit& h, const Assessment& a) -> double {  // float units off the exact answer; 0: exact
        if (!h.hit()) return exact ? minDistance(xe) / unitOf(xe) : 0;
        if (!a.identified) {  // occluded: off by the nearest candidate's distance outside its triangle
            if (exact) return 0;
            double best = INFINITY;
            for (const oracle::Candidate& c : res.candidates) {
                const oracle::TriangleTest x = oracle::examineTriangle(impl_->scene, r, c.instanceId, 0, c.primitiveIndex);
                best = std::min(best, outsideBy(x, ray.tMin, ray.tMax));
            }
            return best;
        }
        if (exact && h.inst == exact->instanceId && h.prim == exact->primitiveIndex) return 0;
        double e = outsideBy(a.x, ray.tMin, ray.tMax);
        // A closest hit behind the exact one passed through it.
        if (exact && !anyHit && a.x.t > exact->t) e = std::max(e, minDistance(xe) / unitOf(xe));
        if (exact && anyHit) e = 0;  // any hit: only hit against miss matters
        return e;
    };
    Judgement j;
    j.vkasOk = av.ok, j.embreeOk = ae.ok;
    j.vkas = av.text, j.embree = ae.text;
    j.vkasError = error(vkas, av), j.embreeError = error(embree, ae);
    j.exactVkas = j.vkasError == 0, j.exactEmbree = j.embreeError == 0;
    j.oracle = format("%zu candidates (%zu required)", res.candidates.size(), res.requiredCount());
    for (size_t i = 0; i < res.candidates.size() && i < 6; ++i) j.oracle += (i ? "; " : ": ") + candidateText(res.candidates[i]);
    if (res.candidates.size() > 6) j.oracle += "; ...";
    j.oracle += exact ? format("; the exact answer (no tolerance): inst %d prim %d t %.9g, %.3g inside its nearest edge = "
                               "%.3g float units (one unit: %.3g, object space)",
                               exact->instanceId, exact->primitiveIndex, exact->t, minDistance(xe),
                               minDistance(xe) / unitOf(xe), unitOf(xe))
                      : std::string("; the exact answer (no tolerance): a miss");
    auto errorText = [](const char* name, double e) {
        return e == 0 ? format("%s matches it", name) : format("%s is off by %.3g float units", name, e);
    };
    const std::string exactText = "the exact answer is " +
                                  (exact ? format("inst %d prim %d", exact->instanceId, exact->primitiveIndex)
                                         : std::string("a miss")) +
                                  ": " + errorText("vkas", j.vkasError) + ", " + errorText("Embree", j.embreeError);
    if (av.ok && ae.ok) {
        j.verdict = Verdict::BothAcceptable;
        if (av.hit && ae.hit && av.identified && ae.identified && !(vkas.inst == embree.inst && vkas.prim == embree.prim) &&
            !av.optional && !ae.optional)
            j.reason = format("a tie: two required candidates at t %.9g and %.9g, %.3g apart, within the tolerances %.3g + %.3g",
                              av.x.t, ae.x.t, std::abs(av.x.t - ae.x.t), av.x.tTolerance, ae.x.tTolerance);
        else if (av.hit && ae.hit && av.identified && ae.identified && vkas.inst == embree.inst && vkas.prim == embree.prim)
            j.reason = format("the same triangle; t %.9g (vkas) and %.9g (Embree) are both within %.3g of the oracle's %.9g",
                              vkas.t, embree.t, av.x.tTolerance, av.x.t);
        else
            j.reason = "within the oracle's tolerance of an edge, of tMin/tMax, or a tie: vkas " + av.why + "; Embree " + ae.why;
        j.reason += "; " + exactText;
    } else if (av.ok) {
        j.verdict = Verdict::VkasRight;
        j.reason = "Embree " + ae.why + " (vkas " + av.why + "); " + exactText;
    } else if (ae.ok) {
        j.verdict = Verdict::EmbreeRight;
        j.reason = "vkas " + av.why + " (Embree " + ae.why + "); " + exactText;
    } else {
        j.verdict = Verdict::Neither;
        j.reason = "vkas " + av.why + "; Embree " + ae.why + "; " + exactText;
    }
    return j;
}

}  // namespace vb
