// [NV-LSS] Oracle for sphere and linear-swept-sphere geometries, written from the spec's rules without looking at
// the engine: fetch by the range-info rules, and intersection by convex minimisation instead of root formulas.
//
// A point x is inside the shape when phi(x) = min over s in [0,1] of (|x - c(s)| - r(s)) <= 0. The function
// (x, s) -> |x - c(s)| - r(s) is jointly convex, so phi is convex in x and, along the ray, in t: golden-section
// search finds its minimum t*, and bisection on [far before, t*] finds the entry point, where phi crosses 0.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "oracle.hpp"

namespace oracle {

namespace {

template <typename T>
T load(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

double roundToFloat(double x) {
    volatile float f = float(x);
    return double(f);
}

struct Source {
    VkFormat vertexFormat;
    const uint8_t* vertexData;
    uint64_t vertexStride;
    VkFormat radiusFormat;
    const uint8_t* radiusData;
    uint64_t radiusStride;
    VkIndexType indexType;
    const uint8_t* indexData;
    uint64_t indexStride;
    bool lss;
    uint32_t indexingMode, endCapsMode;
};

const void* find(const void* chain, VkStructureType type) {
    for (auto* s = static_cast<const VkBaseInStructure*>(chain); s; s = s->pNext)
        if (s->sType == type) return s;
    return nullptr;
}

// Distance-like function of a point to the swept spheres at parameter s.
double f(const Vec3& x, const SweptPrimitive& sp, double s) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double c = sp.p[0][k] + s * (sp.p[1][k] - sp.p[0][k]);
        d2 += (x[k] - c) * (x[k] - c);
    }
    return std::sqrt(d2) - (sp.r[0] + s * (sp.r[1] - sp.r[0]));
}

// min over s in [0, 1] by golden-section search (f is convex in s); returns the value and the argmin.
double phi(const Vec3& x, const SweptPrimitive& sp, double* argmin = nullptr) {
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = 0, b = 1;
    double c = b - g * (b - a), d = a + g * (b - a);
    double fc = f(x, sp, c), fd = f(x, sp, d);
    for (int i = 0; i < 90; ++i) {
        if (fc <= fd) {
            b = d, d = c, fd = fc;
            c = b - g * (b - a);
            fc = f(x, sp, c);
        } else {
            a = c, c = d, fc = fd;
            d = a + g * (b - a);
            fd = f(x, sp, d);
        }
    }
    double s = 0.5 * (a + b);
    double v = f(x, sp, s);
    // The ends are candidates too (a minimum at s = 0 or 1 with a non-zero slope).
    for (double e : {0.0, 1.0}) {
        const double fe = f(x, sp, e);
        if (fe <= v) v = fe, s = e;
    }
    if (argmin) *argmin = s;
    return v;
}

Vec3 at(const Vec3& o, const Vec3& d, double t) { return {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]}; }

// Distance from x to the circle where end cap k meets the midsection. End sphere k (centre c, radius r, the other
// end at c + e with radius r + dr) is the nearest sphere where d/ds (|x - c(s)| - r(s)) >= 0 at the end, i.e.
// (x - c).e <= -r dr: the junction is the circle at axial offset h = -r dr / |e| with radius sqrt(r^2 - h^2). It
// is a point when r = 0 (a cone's apex) and absent for a self-enclosing LSS (the cap is the whole surface).
double junctionDistance(const Vec3& x, const SweptPrimitive& sp, int k) {
    const Vec3& c = sp.p[k];
    const double r = sp.r[k], dr = sp.r[1 - k] - r;
    Vec3 e, w;
    double ee = 0;
    for (int i = 0; i < 3; ++i) e[i] = sp.p[1 - k][i] - c[i], w[i] = x[i] - c[i], ee += e[i] * e[i];
    if (!(ee > dr * dr)) return std::numeric_limits<double>::infinity();
    const double len = std::sqrt(ee), h = -r * dr / len, rho = std::sqrt(std::max(0.0, r * r - h * h));
    const double axial = (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) / len;
    const double radial = std::sqrt(std::max(0.0, w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - axial * axial));
    return std::hypot(axial - h, radial - rho);
}

}  // namespace

Geometry fetchSweptSpheres(const VkAccelerationStructureGeometryKHR& geometry,
                           const VkAccelerationStructureBuildRangeInfoKHR& range) {
    Source src{};
    if (geometry.geometryType == VK_GEOMETRY_TYPE_SPHERES_NV) {
        auto* s = static_cast<const VkAccelerationStructureGeometrySpheresDataNV*>(
            find(geometry.pNext, VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV));
        if (!s) throw std::invalid_argument("oracle: sphere geometry without VkAccelerationStructureGeometrySpheresDataNV");
        src = {s->vertexFormat, static_cast<const uint8_t*>(s->vertexData.hostAddress), s->vertexStride,
               s->radiusFormat, static_cast<const uint8_t*>(s->radiusData.hostAddress), s->radiusStride,
               s->indexType, static_cast<const uint8_t*>(s->indexData.hostAddress), s->indexStride, false, 0, 0};
    } else {
        auto* s = static_cast<const VkAccelerationStructureGeometryLinearSweptSpheresDataNV*>(
            find(geometry.pNext, VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV));
        if (!s) throw std::invalid_argument("oracle: LSS geometry without its data structure");
        src = {s->vertexFormat, static_cast<const uint8_t*>(s->vertexData.hostAddress), s->vertexStride,
               s->radiusFormat, static_cast<const uint8_t*>(s->radiusData.hostAddress), s->radiusStride,
               s->indexType, static_cast<const uint8_t*>(s->indexData.hostAddress), s->indexStride, true,
               uint32_t(s->indexingMode), uint32_t(s->endCapsMode)};
    }
    Geometry out;
    out.type = geometry.geometryType;
    out.opaque = (geometry.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) != 0;
    const bool indexed = src.indexType != VK_INDEX_TYPE_NONE_KHR;
    const bool successive = src.lss && src.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV;
    // The k-th index of the geometry (indexed geometries only).
    auto indexAt = [&](uint64_t k) -> uint64_t {
        const uint8_t* p = src.indexData + range.primitiveOffset + k * src.indexStride;
        return src.indexType == VK_INDEX_TYPE_UINT16 ? load<uint16_t>(p) : load<uint32_t>(p);
    };
    // Position and radius of "vertex" v: indexed -> v is an index value, + firstVertex, no primitiveOffset;
    // not indexed -> v counts vertices from primitiveOffset + firstVertex in both buffers.
    auto vertex = [&](uint64_t v, Vec3& p, double& r, bool& nan) {
        const uint64_t offset = indexed ? 0 : range.primitiveOffset;
        const uint64_t n = v + range.firstVertex;
        bool xNaN = false;
        p = decodeVertex(src.vertexFormat, src.vertexData + offset + src.vertexStride * n, &xNaN);
        const uint8_t* rp = src.radiusData + offset + src.radiusStride * n;
        r = src.radiusFormat == VK_FORMAT_R16_SFLOAT ? halfToDouble(load<uint16_t>(rp)) : double(load<float>(rp));
        nan = std::isnan(r) || std::isnan(p[0]) || std::isnan(p[1]) || std::isnan(p[2]);
        for (int k = 0; k < 3; ++k) p[k] = roundToFloat(p[k]);
    };
    out.swept.resize(range.primitiveCount);
    for (uint64_t i = 0; i < range.primitiveCount; ++i) {
        SweptPrimitive& sp = out.swept[i];
        uint64_t v[2];
        if (!src.lss) {
            v[0] = v[1] = indexed ? indexAt(i) : i;
        } else if (successive) {
            v[0] = indexed ? indexAt(i) : i;
            v[1] = v[0] + 1;
        } else {
            v[0] = indexed ? indexAt(2 * i) : 2 * i;
            v[1] = indexed ? indexAt(2 * i + 1) : 2 * i + 1;
        }
        bool nan0, nan1;
        vertex(v[0], sp.p[0], sp.r[0], nan0);
        vertex(v[1], sp.p[1], sp.r[1], nan1);
        sp.active = !nan0 && !nan1;
        if (!src.lss) {
            sp.cap = {true, true};
        } else if (src.endCapsMode == VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV) {
            sp.cap = {false, false};
        } else {
            // CHAINED: in a SUCCESSIVE chain (index k following index k-1 of the previous primitive) only the
            // first primitive keeps its leading cap.
            const bool continues = successive && i > 0 && indexed && indexAt(i) == indexAt(i - 1) + 1;
            const bool continuesPlain = successive && i > 0 && !indexed;
            sp.cap = {!(continues || continuesPlain), true};
        }
    }
    return out;
}

void sweptCandidates(const Geometry& geometry, const Vec3& o, const Vec3& d, double tMin, double tMax, double scale,
                     const Candidate& proto, std::vector<Candidate>& out) {
    constexpr double kRel = 1e-5;
    const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double dlen = std::sqrt(dd);
    if (!(dlen > 0)) return;
    for (size_t pi = 0; pi < geometry.swept.size(); ++pi) {
        const SweptPrimitive& sp = geometry.swept[pi];
        if (!sp.hittable()) continue;
        // Bounding ball of the shape, and the t interval where the line is within it.
        Vec3 m;
        double half = 0;
        for (int k = 0; k < 3; ++k) {
            m[k] = 0.5 * (sp.p[0][k] + sp.p[1][k]);
            half += (sp.p[1][k] - sp.p[0][k]) * (sp.p[1][k] - sp.p[0][k]);
        }
        const double R = 0.5 * std::sqrt(half) + std::max(sp.r[0], sp.r[1]);
        double primScale = R;
        for (int k = 0; k < 3; ++k) primScale = std::max(primScale, std::fabs(m[k]));
        const double delta = kRel * std::max({scale, primScale, 1e-30});
        const Vec3 om{m[0] - o[0], m[1] - o[1], m[2] - o[2]};
        const double tc = (om[0] * d[0] + om[1] * d[1] + om[2] * d[2]) / dd;
        const Vec3 pc = at(o, d, tc);
        double dist2 = 0;
        for (int k = 0; k < 3; ++k) dist2 += (pc[k] - m[k]) * (pc[k] - m[k]);
        const double Rg = R + 2 * delta;
        if (dist2 > Rg * Rg) continue;
        const double halfChord = std::sqrt(Rg * Rg - dist2) / dlen;
        const double ta = tc - halfChord, tb = tc + halfChord;
        // Minimum of phi along the ray (convex): golden section.
        const double g = 0.5 * (std::sqrt(5.0) - 1.0);
        double a = ta, b = tb, c = b - g * (b - a), e = a + g * (b - a);
        double fc = phi(at(o, d, c), sp), fe = phi(at(o, d, e), sp);
        for (int i = 0; i < 100; ++i) {
            if (fc <= fe) {
                b = e, e = c, fe = fc;
                c = b - g * (b - a);
                fc = phi(at(o, d, c), sp);
            } else {
                a = c, c = e, fc = fe;
                e = a + g * (b - a);
                fe = phi(at(o, d, e), sp);
            }
        }
        const double tStar = 0.5 * (a + b);
        const double phiMin = phi(at(o, d, tStar), sp);
        if (phiMin > delta) continue;  // clearly missed
        // Entry: bisection on [ta, tStar], phi(ta) > 0 >= phi(tStar) (or a graze).
        double lo = ta, hi = tStar;
        if (phiMin <= 0) {
            for (int i = 0; i < 200 && hi - lo > 0; ++i) {
                const double mid = 0.5 * (lo + hi);
                if (mid == lo || mid == hi) break;
                if (phi(at(o, d, mid), sp) > 0) lo = mid;
                else hi = mid;
            }
        }
        const double tEntry = hi;
        double u = 0;
        phi(at(o, d, tEntry), sp, &u);
        // Slope of phi at the entry (at most |d|): how far t moves when the surface moves by delta.
        const double h = std::max(1e-9 * std::fabs(tEntry), delta / dlen);
        const double slope = std::fabs(phi(at(o, d, tEntry - h), sp) - phi(at(o, d, tEntry), sp)) / h;
        const bool graze = phiMin > -delta || slope < 1e-3 * dlen;
        const double tTol = kRel * std::fabs(tEntry) + (graze ? (tb - ta) : 4 * delta / std::max(slope, 1e-300));
        const bool isLss = geometry.type == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
        // End caps. Spec: "For rays that originate inside a LSS or sphere primitive, or enter through an absent
        // endcap, no intersections will be reported", and "If the u value is exactly 0 or 1, then the intersection
        // occurred on the respective endcap". Near a cap/midsection junction it is optional. u cannot tell how far
        // the entry is from the junction (it is 0 all over the cap and grows from 0 on the midsection), so a
        // clear entry through the cap also needs the entry point farther from the junction than the position
        // error: a ray that passes an end of radius 0 within that error enters the midsection there, at u > 0.
        bool capOptional = false;
        if (isLss) {
            const double uTol = 1e-5 + 1e-3 * (graze ? 1.0 : 0.0);
            const Vec3 x = at(o, d, tEntry);
            const double posTol = 4 * delta + tTol * dlen;
            bool clearlyCap = false;
            for (int k = 0; k < 2; ++k) {
                const double toEnd = k == 0 ? u : 1 - u;
                if (sp.cap[k] || !(toEnd < uTol)) continue;
                if (toEnd < 1e-7 && !graze && junctionDistance(x, sp, k) > posTol) clearlyCap = true;
                else capOptional = true;
            }
            if (clearlyCap) continue;  // clearly through an absent cap
        }
        // A ray starting inside (entry before tMin) or reaching the shape after tMax: no hit.
        if (tEntry < tMin - tTol || tEntry > tMax + tTol) continue;
        const bool inRange = tEntry >= tMin + tTol && tEntry <= tMax - tTol;
        Candidate cand = proto;
        cand.primitiveIndex = int32_t(pi);
        cand.t = tEntry;
        cand.tTolerance = tTol;
        cand.optional = graze || !inRange || capOptional;
        cand.facingAmbiguous = true;  // no facing
        cand.frontFace = false;
        cand.baryTolerance = std::numeric_limits<double>::infinity();
        cand.sweptType = geometry.type;
        cand.u = isLss ? u : 0.0;
        // u moves by about the t error over the shape's length, and is flat where a cap meets the midsection.
        cand.uTolerance = isLss ? 1e-3 + tTol * dlen / std::max(2 * R, 1e-300) : 0.0;
        out.push_back(cand);
    }
}

}  // namespace oracle
