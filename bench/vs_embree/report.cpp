#include "report.hpp"

#include <cstdio>
#include <cstring>

namespace vb {

Agreement compareHits(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b, bool anyHit,
                      const std::vector<Hit>* refClosest) {
    Agreement g;
    g.rays = rays.size();
    for (size_t i = 0; i < rays.size(); ++i) {
        const Hit &x = a[i], &y = b[i];
        if (x.hit() != y.hit()) {
            ++g.hitMiss;
            // Classify with whichever closest hit we have: the one that hit (closest-hit rays) or the reference's.
            const Hit& h = anyHit ? (refClosest ? (*refClosest)[i] : Hit{}) : (x.hit() ? x : y);
            if (h.hit()) {
                const float w = 1 - h.u - h.v;
                if (std::min({h.u, h.v, w}) < 1e-3f) ++g.hitMissAtEdge;
                else if (std::abs(h.t - rays[i].tMax) <= 1e-4f * rays[i].tMax) ++g.hitMissAtEnd;
            }
            continue;
        }
        if (!x.hit() || anyHit) {
            ++g.samePrimitive;
            continue;
        }
        const double dt = std::abs(double(x.t) - y.t), t = std::max(std::abs(double(x.t)), std::abs(double(y.t)));
        const float* o = rays[i].origin;
        const double tol = 1e-4 * t + 16 * std::ldexp(std::max({std::abs(o[0]), std::abs(o[1]), std::abs(o[2]), 1e-30f}), -23);
        if (x.prim == y.prim && x.inst == y.inst) {
            ++g.samePrimitive;
            g.maxRelT = std::max(g.maxRelT, dt / std::max(t, 1e-30));
            g.maxTolT = std::max(g.maxTolT, dt / tol);
        } else if (dt <= tol) {
            ++g.tie;
        } else {
            const Hit& nearer = x.t < y.t ? x : y;
            if (std::min({nearer.u, nearer.v, 1 - nearer.u - nearer.v}) < 1e-3f) ++g.differentHitAtEdge;
            else ++g.differentHit;
        }
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
    char buf[400];
    if (anyHit)
        std::snprintf(buf, sizeof buf, "%zu rays: %zu hit/miss differences (%zu at a triangle edge, %zu at tMax, %zu unexplained)",
                      g.rays, g.hitMiss, g.hitMissAtEdge, g.hitMissAtEnd, g.hitMiss - g.hitMissAtEdge - g.hitMissAtEnd);
    else
        std::snprintf(buf, sizeof buf,
                      "%zu rays: %zu hit/miss (%zu at an edge, %zu unexplained), %zu ties (other primitive, same t), "
                      "%zu other hits past an edge, %zu other hits unexplained; same primitive: max |dt|/t %.2g, "
                      "max |dt|/tolerance %.2g",
                      g.rays, g.hitMiss, g.hitMissAtEdge, g.hitMiss - g.hitMissAtEdge - g.hitMissAtEnd, g.tie,
                      g.differentHitAtEdge, g.differentHit, g.maxRelT, g.maxTolT);
    return buf;
}

std::vector<std::string> examples(const std::vector<VkasRay>& rays, const std::vector<Hit>& a, const std::vector<Hit>& b,
                                  bool anyHit, size_t limit, const std::function<double(size_t, const Hit&)>& exactT) {
    std::vector<std::string> out;
    for (size_t i = 0; i < rays.size() && out.size() < limit; ++i) {
        const Hit &x = a[i], &y = b[i];
        bool show = x.hit() != y.hit();
        if (!show && x.hit() && !anyHit) {
            const float* o = rays[i].origin;
            const double t = std::max(std::abs(double(x.t)), std::abs(double(y.t)));
            show = std::abs(double(x.t) - y.t) > 1e-4 * t + 16 * std::ldexp(std::max({std::abs(o[0]), std::abs(o[1]), std::abs(o[2])}), -23);
        }
        if (!show) continue;
        const VkasRay& r = rays[i];
        char buf[600];
        std::snprintf(buf, sizeof buf,
                      "ray %zu: origin (%.9g, %.9g, %.9g) direction (%.9g, %.9g, %.9g) t [%.9g, %.9g]: vkas inst %d prim %d "
                      "t %.9g (plane, double: %.9g) uv (%.3g, %.3g); Embree inst %d prim %d t %.9g (plane, double: %.9g) "
                      "uv (%.3g, %.3g)",
                      i, r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2], r.tMin,
                      r.tMax, x.inst, x.prim, x.t, x.hit() ? exactT(i, x) : NAN, x.u, x.v, y.inst, y.prim, y.t,
                      y.hit() && !anyHit ? exactT(i, y) : NAN, y.u, y.v);
        out.push_back(buf);
    }
    return out;
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
    if (std::isfinite(v)) std::snprintf(buf, sizeof buf, "%.6g", v);
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
