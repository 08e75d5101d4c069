#include "report.hpp"

#include <cstdio>
#include <cstring>

namespace vb {

namespace {

double tTolerance(const VkasRay& r, const Hit& x, const Hit& y) {
    const double t = std::max(std::abs(double(x.t)), std::abs(double(y.t)));
    const float* o = r.origin;
    return 1e-4 * t + 16 * std::ldexp(std::max({std::abs(o[0]), std::abs(o[1]), std::abs(o[2]), 1e-30f}), -23);
}

}  // namespace

std::vector<size_t> differingRays(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b,
                                  bool anyHit) {
    std::vector<size_t> out;
    for (size_t i = 0; i < rays.size(); ++i) {
        const Hit &x = a[i], &y = b[i];
        bool differ = x.hit() != y.hit();
        if (!differ && x.hit() && !anyHit)
            differ = x.prim != y.prim || x.inst != y.inst || std::abs(double(x.t) - y.t) > tTolerance(rays[i], x, y);
        if (differ) out.push_back(i);
    }
    return out;
}

Category classify(const VkasRay& ray, const Hit& x, const Hit& y, bool anyHit, const Hit& refClosest) {
    if (x.hit() != y.hit()) {
        // Classify with whichever closest hit we have: the one that hit (closest-hit rays) or the reference's.
        const Hit& h = anyHit ? refClosest : (x.hit() ? x : y);
        if (h.hit()) {
            const float w = 1 - h.u - h.v;
            if (std::min({h.u, h.v, w}) < 1e-3f) return Category::HitMissAtEdge;
            if (std::isfinite(ray.tMax) && std::abs(h.t - ray.tMax) <= 1e-4f * ray.tMax) return Category::HitMissAtEnd;
        }
        return Category::HitMiss;
    }
    if (!x.hit() || anyHit) return Category::Same;
    const double dt = std::abs(double(x.t) - y.t);
    const double tol = tTolerance(ray, x, y);
    if (x.prim == y.prim && x.inst == y.inst) return dt > tol ? Category::SameBeyondT : Category::Same;
    if (dt <= tol) return Category::Tie;
    const Hit& nearer = x.t < y.t ? x : y;
    return std::min({nearer.u, nearer.v, 1 - nearer.u - nearer.v}) < 1e-3f ? Category::OtherPastEdge : Category::Other;
}

const char* categoryName(Category c) {
    switch (c) {
        case Category::Same: return "same result";
        case Category::SameBeyondT: return "same primitive, t beyond the tolerance";
        case Category::Tie: return "tie: other primitive, same t";
        case Category::OtherPastEdge: return "other hit, past an edge";
        case Category::Other: return "other hit";
        case Category::HitMissAtEdge: return "hit/miss at an edge";
        case Category::HitMissAtEnd: return "hit/miss at tMax";
        case Category::HitMiss: return "hit/miss";
    }
    return "?";
}

Agreement compareHits(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b, bool anyHit,
                      const std::vector<Hit>* refClosest, const std::vector<size_t>& differing,
                      const std::vector<Judgement>& verdicts) {
    Agreement g;
    g.rays = rays.size();
    for (size_t i = 0; i < rays.size(); ++i) {
        const Hit &x = a[i], &y = b[i];
        const Category c = classify(rays[i], x, y, anyHit, refClosest ? (*refClosest)[i] : Hit{});
        g.hitMiss += c == Category::HitMiss || c == Category::HitMissAtEdge || c == Category::HitMissAtEnd;
        g.hitMissAtEdge += c == Category::HitMissAtEdge;
        g.hitMissAtEnd += c == Category::HitMissAtEnd;
        g.samePrimitive += c == Category::Same || c == Category::SameBeyondT;
        g.sameBeyondT += c == Category::SameBeyondT;
        g.tie += c == Category::Tie;
        g.differentHitAtEdge += c == Category::OtherPastEdge;
        g.differentHit += c == Category::Other;
        if (x.hit() && y.hit() && !anyHit && x.prim == y.prim && x.inst == y.inst) {
            const double dt = std::abs(double(x.t) - y.t), t = std::max(std::abs(double(x.t)), std::abs(double(y.t)));
            g.maxRelT = std::max(g.maxRelT, dt / std::max(t, 1e-30));
            g.maxTolT = std::max(g.maxTolT, dt / tTolerance(rays[i], x, y));
        }
    }
    g.differing = differing.size();
    for (const Judgement& j : verdicts) {
        switch (j.verdict) {
            case Verdict::BothAcceptable: ++g.bothAcceptable; break;
            case Verdict::VkasRight: ++g.vkasRight; break;
            case Verdict::EmbreeRight: ++g.embreeRight; break;
            case Verdict::Neither: ++g.neither; break;
        }
        if (j.exactVkas && !j.exactEmbree) ++g.exactVkasOnly;
        else if (j.exactEmbree && !j.exactVkas) ++g.exactEmbreeOnly;
        else if (!j.exactVkas && !j.exactEmbree) ++g.exactNeither;
        g.maxVkasError = std::max(g.maxVkasError, j.vkasError);
        g.maxEmbreeError = std::max(g.maxEmbreeError, j.embreeError);
    }
    return g;
}

size_t countDifferent(const std::vector<Hit>& a, const std::vector<Hit>& b) {
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i)
        n += a[i].prim != b[i].prim || a[i].inst != b[i].inst || std::memcmp(&a[i].t, &b[i].t, sizeof(float)) != 0;
    return n;
}

std::string describe(const Agreement& g, bool anyHit) {
    char buf[1200];
    int n;
    if (anyHit)
        n = std::snprintf(buf, sizeof buf, "%zu rays, %zu differ: %zu hit/miss (%zu at a triangle edge, %zu at tMax)", g.rays,
                          g.differing, g.hitMiss, g.hitMissAtEdge, g.hitMissAtEnd);
    else
        n = std::snprintf(buf, sizeof buf,
                          "%zu rays, %zu differ: %zu hit/miss (%zu at an edge, %zu at tMax), %zu ties (other primitive, "
                          "same t), %zu other hits past an edge, %zu other hits, %zu same primitive with t beyond the "
                          "tolerance",
                          g.rays, g.differing, g.hitMiss, g.hitMissAtEdge, g.hitMissAtEnd, g.tie, g.differentHitAtEdge,
                          g.differentHit, g.sameBeyondT);
    n += std::snprintf(buf + n, sizeof buf - size_t(n),
                       "; the oracle: %zu both acceptable, %zu vkas right (Embree wrong), %zu Embree right (vkas wrong), "
                       "%zu unexplained (neither acceptable); the exact answer: vkas's only %zu, Embree's only %zu, "
                       "neither's %zu; largest miss of it: vkas %.3g, Embree %.3g float units",
                       g.bothAcceptable, g.vkasRight, g.embreeRight, g.neither, g.exactVkasOnly, g.exactEmbreeOnly,
                       g.exactNeither, g.maxVkasError, g.maxEmbreeError);
    if (!anyHit)
        std::snprintf(buf + n, sizeof buf - size_t(n), "; same primitive: max |dt|/t %.2g, max |dt|/tolerance %.2g", g.maxRelT,
                      g.maxTolT);
    return buf;
}

const char* verdictName(Verdict v) {
    switch (v) {
        case Verdict::VkasRight: return "vkas right, Embree wrong";
        case Verdict::EmbreeRight: return "Embree right, vkas wrong";
        case Verdict::BothAcceptable: return "both acceptable";
        case Verdict::Neither: return "UNEXPLAINED: the oracle accepts neither";
    }
    return "?";
}

std::string disagreementText(const char* kind, size_t index, const VkasRay& r, Category c, const Judgement& j,
                             bool anyHit) {
    char buf[700];
    std::snprintf(buf, sizeof buf, "%s ray %zu (%s): origin (%a, %a, %a) direction (%a, %a, %a) t [%a, %a] = origin (%.9g, "
                  "%.9g, %.9g) direction (%.9g, %.9g, %.9g) t [%.9g, %.9g]",
                  kind, index, categoryName(c), r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2],
                  r.tMin, r.tMax, r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2],
                  r.tMin, r.tMax);
    const std::string pad = "\n      ";
    return std::string(buf) + pad + "vkas " + (anyHit ? "any hit" : "closest") + ": " + j.vkas + pad + "Embree " +
           (anyHit ? "rtcOccluded1" : "rtcIntersect1") + ": " + j.embree + pad + "oracle: " + j.oracle + pad + "verdict: " + verdictName(j.verdict) + ": " + j.reason;
}

void Json::sep(const char* key) {
    if (!first_.back()) s_ += ",";
    first_.back() = false;
    s_ += "\n" + std::string(2 * (first_.size() - 1), ' ');
    if (key) s_ += "\"" + std::string(key) + "\": ";
}

Json& Json::begin(const char* key, char bracket) {
    sep(key);
    s_ += bracket;
    first_.push_back(true);
    return *this;
}

Json& Json::end(char bracket) {
    first_.pop_back();
    s_ += "\n" + std::string(2 * (first_.size() - 1), ' ') + bracket;
    return *this;
}

Json& Json::field(const char* key, double v) {
    sep(key);
    char buf[64];
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9007199254740992.0)
        std::snprintf(buf, sizeof buf, "%.0f", v);  // counts and byte sizes: every digit
    else if (std::isfinite(v)) std::snprintf(buf, sizeof buf, "%.6g", v);
    else std::snprintf(buf, sizeof buf, "null");
    s_ += buf;
    return *this;
}

Json& Json::field(const char* key, const std::string& v) {
    sep(key);
    s_ += "\"";
    for (char c : v) {
        if (c == '"' || c == '\\') s_ += '\\';
        s_ += c;
    }
    s_ += "\"";
    return *this;
}

Json& Json::field(const char* key, bool v) {
    sep(key);
    s_ += v ? "true" : "false";
    return *this;
}

}  // namespace vb
