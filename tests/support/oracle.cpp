#include "oracle.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace oracle {

namespace {
constexpr uint32_t kRayOpaque = 0x1, kRayNoOpaque = 0x2, kRayCullBack = 0x10, kRayCullFront = 0x20,
                   kRayCullOpaque = 0x40, kRayCullNoOpaque = 0x80, kRaySkipTriangles = 0x100, kRaySkipAabbs = 0x200;
constexpr uint32_t kInstCullDisable = 0x1, kInstFlip = 0x2, kInstForceOpaque = 0x4, kInstForceNoOpaque = 0x8;
constexpr uint32_t kInstForceOmm2State = 0x10, kInstDisableOmm = 0x20, kRayForceOmm2State = 0x400;  // [EXT-OMM]

template <typename T>
T load(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

double snorm(int64_t c, int bits) {
    const double maxv = double((int64_t(1) << (bits - 1)) - 1);
    return std::max(double(c) / maxv, -1.0);
}

// volatile: GCC 12 -O2 was observed to drop this conversion when inlined into fetchTriangles.
double roundToFloat(double x) {
    volatile float f = float(x);
    return double(f);
}

Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
double maxAbs(const Vec3& a) { return std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(a[2])}); }
}  // namespace

const std::vector<FormatInfo>& vertexFormats() {
    static const std::vector<FormatInfo> formats = {
        {VK_FORMAT_R32G32_SFLOAT, "R32G32_SFLOAT", 2, 4, 8, true, false},
        {VK_FORMAT_R32G32B32_SFLOAT, "R32G32B32_SFLOAT", 3, 4, 12, true, false},
        {VK_FORMAT_R32G32B32A32_SFLOAT, "R32G32B32A32_SFLOAT", 4, 4, 16, true, false},
        {VK_FORMAT_R16G16_SFLOAT, "R16G16_SFLOAT", 2, 2, 4, true, false},
        {VK_FORMAT_R16G16B16_SFLOAT, "R16G16B16_SFLOAT", 3, 2, 6, true, false},
        {VK_FORMAT_R16G16B16A16_SFLOAT, "R16G16B16A16_SFLOAT", 4, 2, 8, true, false},
        {VK_FORMAT_R16G16_SNORM, "R16G16_SNORM", 2, 2, 4, false, false},
        {VK_FORMAT_R16G16B16_SNORM, "R16G16B16_SNORM", 3, 2, 6, false, false},
        {VK_FORMAT_R16G16B16A16_SNORM, "R16G16B16A16_SNORM", 4, 2, 8, false, false},
        {VK_FORMAT_R8G8_SNORM, "R8G8_SNORM", 2, 1, 2, false, false},
        {VK_FORMAT_R8G8B8_SNORM, "R8G8B8_SNORM", 3, 1, 3, false, false},
        {VK_FORMAT_R8G8B8A8_SNORM, "R8G8B8A8_SNORM", 4, 1, 4, false, false},
        {VK_FORMAT_R64G64_SFLOAT, "R64G64_SFLOAT", 2, 8, 16, true, false},
        {VK_FORMAT_R64G64B64_SFLOAT, "R64G64B64_SFLOAT", 3, 8, 24, true, false},
        {VK_FORMAT_R64G64B64A64_SFLOAT, "R64G64B64A64_SFLOAT", 4, 8, 32, true, false},
        {VK_FORMAT_A2B10G10R10_UNORM_PACK32, "A2B10G10R10_UNORM_PACK32", 4, 4, 4, false, true},
    };
    return formats;
}

const FormatInfo& formatInfo(VkFormat format) {
    for (const FormatInfo& f : vertexFormats())
        if (f.format == format) return f;
    throw std::invalid_argument("oracle: unsupported vertex format " + std::to_string(int(format)));
}

double halfToDouble(uint16_t h) {
    const int sign = (h >> 15) & 1;
    const int exp = (h >> 10) & 0x1F;
    const int mant = h & 0x3FF;
    double v;
    if (exp == 0)
        v = std::ldexp(double(mant), -24);
    else if (exp == 31)
        v = mant ? std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::infinity();
    else
        v = std::ldexp(double(mant | 0x400), exp - 25);
    return sign ? -v : v;
}

uint16_t floatToHalf(float f) {
    uint32_t x;
    std::memcpy(&x, &f, 4);
    const uint16_t sign = uint16_t((x >> 16) & 0x8000);
    if (std::isnan(f)) return uint16_t(sign | 0x7E00);
    const double a = std::fabs(double(f));
    if (a >= 65520.0) return uint16_t(sign | 0x7C00);
    // Find the largest representable magnitude <= a by brute search over exponent, then round to nearest even.
    if (a < std::ldexp(1.0, -14)) {  // subnormal
        const double m = std::nearbyint(a / std::ldexp(1.0, -24));
        return uint16_t(sign | uint16_t(m));
    }
    int e;
    std::frexp(a, &e);  // a = f * 2^e, f in [0.5,1)
    const int exp = e - 1;  // a in [2^exp, 2^(exp+1))
    double m = std::nearbyint(a / std::ldexp(1.0, exp - 10));  // in [1024, 2048]
    int biased = exp + 15;
    if (m >= 2048) {
        m = 1024;
        ++biased;
    }
    if (biased >= 31) return uint16_t(sign | 0x7C00);
    return uint16_t(sign | (biased << 10) | (uint16_t(m) & 0x3FF));
}

Vec3 decodeVertex(VkFormat format, const void* vp, bool* xIsNaN) {
    const uint8_t* p = static_cast<const uint8_t*>(vp);
    const FormatInfo& fi = formatInfo(format);
    Vec3 out{0, 0, 0};
    const uint32_t n = fi.packed ? 3 : std::min(fi.components, 3u);
    if (fi.packed) {
        const uint32_t w = load<uint32_t>(p);
        out[0] = double(w & 0x3FF) / 1023.0;
        out[1] = double((w >> 10) & 0x3FF) / 1023.0;
        out[2] = double((w >> 20) & 0x3FF) / 1023.0;
    } else {
        for (uint32_t c = 0; c < n; ++c) {
            const uint8_t* q = p + c * fi.componentSize;
            switch (format) {
                case VK_FORMAT_R32G32_SFLOAT:
                case VK_FORMAT_R32G32B32_SFLOAT:
                case VK_FORMAT_R32G32B32A32_SFLOAT: out[c] = double(load<float>(q)); break;
                case VK_FORMAT_R16G16_SFLOAT:
                case VK_FORMAT_R16G16B16_SFLOAT:
                case VK_FORMAT_R16G16B16A16_SFLOAT: out[c] = halfToDouble(load<uint16_t>(q)); break;
                case VK_FORMAT_R16G16_SNORM:
                case VK_FORMAT_R16G16B16_SNORM:
                case VK_FORMAT_R16G16B16A16_SNORM: out[c] = snorm(load<int16_t>(q), 16); break;
                case VK_FORMAT_R8G8_SNORM:
                case VK_FORMAT_R8G8B8_SNORM:
                case VK_FORMAT_R8G8B8A8_SNORM: out[c] = snorm(load<int8_t>(q), 8); break;
                case VK_FORMAT_R64G64_SFLOAT:
                case VK_FORMAT_R64G64B64_SFLOAT:
                case VK_FORMAT_R64G64B64A64_SFLOAT: out[c] = load<double>(q); break;
                default: throw std::invalid_argument("oracle: bad format");
            }
        }
    }
    if (xIsNaN) *xIsNaN = std::isnan(out[0]);
    return out;
}

void Blas::computeBounds() {
    lo = {1e300, 1e300, 1e300};
    hi = {-1e300, -1e300, -1e300};
    auto extend = [&](const Vec3& v) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], v[k]);
            hi[k] = std::max(hi[k], v[k]);
        }
    };
    for (const Geometry& g : geometries) {
        for (const Triangle& t : g.triangles)
            if (t.active)
                for (const Vec3& v : t.v) extend(v);
        for (const Aabb& b : g.aabbs)
            if (b.valid()) extend(b.lo), extend(b.hi);
        for (const SweptPrimitive& sp : g.swept)
            if (sp.hittable())
                for (int e = 0; e < 2; ++e)
                    for (int k = 0; k < 3; ++k) {
                        lo[k] = std::min(lo[k], sp.p[e][k] - sp.r[e]);
                        hi[k] = std::max(hi[k], sp.p[e][k] + sp.r[e]);
                    }
    }
}

Geometry fetchTriangles(const VkAccelerationStructureGeometryKHR& geometry,
                        const VkAccelerationStructureBuildRangeInfoKHR& range) {
    if (geometry.geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR)
        throw std::invalid_argument("oracle: only triangle geometries are supported");
    const VkAccelerationStructureGeometryTrianglesDataKHR& tri = geometry.geometry.triangles;
    Geometry out;
    out.opaque = (geometry.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) != 0;
    const uint8_t* vbase = static_cast<const uint8_t*>(tri.vertexData.hostAddress);
    const uint8_t* ibase = static_cast<const uint8_t*>(tri.indexData.hostAddress);
    const uint64_t stride = tri.vertexStride;
    bool hasTransform = tri.transformData.hostAddress != nullptr;
    double m[3][4] = {};
    if (hasTransform) {
        const uint8_t* tp = static_cast<const uint8_t*>(tri.transformData.hostAddress) + range.transformOffset;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) m[r][c] = double(load<float>(tp + 4 * (4 * r + c)));
    }
    out.triangles.resize(range.primitiveCount);
    for (uint64_t i = 0; i < range.primitiveCount; ++i) {
        Triangle& t = out.triangles[i];
        t.active = true;
        for (uint64_t j = 0; j < 3; ++j) {
            const uint8_t* addr;
            if (tri.indexType == VK_INDEX_TYPE_NONE_KHR) {
                addr = vbase + range.primitiveOffset + stride * (uint64_t(range.firstVertex) + 3 * i + j);
            } else {
                uint64_t index;
                if (tri.indexType == VK_INDEX_TYPE_UINT16)
                    index = load<uint16_t>(ibase + range.primitiveOffset + 2 * (3 * i + j));
                else if (tri.indexType == VK_INDEX_TYPE_UINT32)
                    index = load<uint32_t>(ibase + range.primitiveOffset + 4 * (3 * i + j));
                else
                    throw std::invalid_argument("oracle: bad index type");
                addr = vbase + stride * (index + range.firstVertex);
            }
            bool nan = false;
            Vec3 p = decodeVertex(tri.vertexFormat, addr, &nan);
            if (nan) t.active = false;
            if (hasTransform) {
                Vec3 q;
                for (int r = 0; r < 3; ++r) q[r] = m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3];
                p = q;
            }
            for (int k = 0; k < 3; ++k) t.v[j][k] = roundToFloat(p[k]);
        }
    }
    out.micromap = fetchGeometryMicromap(tri, range.primitiveCount);
    return out;
}

Geometry fetchAabbs(const VkAccelerationStructureGeometryKHR& geometry,
                    const VkAccelerationStructureBuildRangeInfoKHR& range) {
    if (geometry.geometryType != VK_GEOMETRY_TYPE_AABBS_KHR)
        throw std::invalid_argument("oracle: not an AABB geometry");
    const VkAccelerationStructureGeometryAabbsDataKHR& data = geometry.geometry.aabbs;
    Geometry out;
    out.type = VK_GEOMETRY_TYPE_AABBS_KHR;
    out.opaque = (geometry.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) != 0;
    const uint8_t* base = static_cast<const uint8_t*>(data.data.hostAddress) + range.primitiveOffset;
    out.aabbs.resize(range.primitiveCount);
    for (uint64_t i = 0; i < range.primitiveCount; ++i) {
        const uint8_t* p = base + data.stride * i;  // VkAabbPositionsKHR: minX, minY, minZ, maxX, maxY, maxZ
        Aabb& b = out.aabbs[i];
        for (int k = 0; k < 3; ++k) {
            b.lo[k] = double(load<float>(p + 4 * k));
            b.hi[k] = double(load<float>(p + 12 + 4 * k));
        }
        b.active = !std::isnan(b.lo[0]);
    }
    return out;
}

Geometry fetchGeometry(const VkAccelerationStructureGeometryKHR& geometry,
                       const VkAccelerationStructureBuildRangeInfoKHR& range) {
    if (geometry.geometryType == VK_GEOMETRY_TYPE_SPHERES_NV ||
        geometry.geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV)
        return fetchSweptSpheres(geometry, range);
    return geometry.geometryType == VK_GEOMETRY_TYPE_AABBS_KHR ? fetchAabbs(geometry, range)
                                                                : fetchTriangles(geometry, range);
}

void invert34(const double m[3][4], double out[3][4]) {
    const double a = m[0][0], b = m[0][1], c = m[0][2];
    const double d = m[1][0], e = m[1][1], f = m[1][2];
    const double g = m[2][0], h = m[2][1], i = m[2][2];
    const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    const double det = a * A + b * B + c * C;
    const double inv[3][3] = {
        {A / det, -(b * i - c * h) / det, (b * f - c * e) / det},
        {B / det, (a * i - c * g) / det, -(a * f - c * d) / det},
        {C / det, -(a * h - b * g) / det, (a * e - b * d) / det},
    };
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) out[r][k] = inv[r][k];
        out[r][3] = -(inv[r][0] * m[0][3] + inv[r][1] * m[1][3] + inv[r][2] * m[2][3]);
    }
}

Instance decodeInstance(const void* bytes, const std::function<std::shared_ptr<const Blas>(uint64_t)>& lookup) {
    const uint8_t* p = static_cast<const uint8_t*>(bytes);
    Instance inst;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) inst.toWorld[r][c] = double(load<float>(p + 4 * (4 * r + c)));
    invert34(inst.toWorld, inst.toObject);
    const uint32_t w0 = load<uint32_t>(p + 48), w1 = load<uint32_t>(p + 52);
    inst.customIndex = w0 & 0xFFFFFFu;
    inst.mask = w0 >> 24;
    inst.sbtOffset = w1 & 0xFFFFFFu;
    inst.flags = w1 >> 24;
    inst.reference = load<uint64_t>(p + 56);
    if (inst.reference != 0) {
        inst.blas = lookup(inst.reference);
        if (!inst.blas) throw std::invalid_argument("oracle: unknown acceleration structure reference");
    }
    return inst;
}

const Candidate* Result::find(int32_t instanceId, int32_t geometryIndex, int32_t primitiveIndex) const {
    for (const Candidate& c : candidates)
        if (c.instanceId == instanceId && c.geometryIndex == geometryIndex && c.primitiveIndex == primitiveIndex)
            return &c;
    return nullptr;
}

const Candidate* Result::closestRequired() const {
    const Candidate* best = nullptr;
    for (const Candidate& c : candidates)
        if (!c.optional && (!best || c.t < best->t)) best = &c;
    return best;
}

size_t Result::requiredCount() const {
    size_t n = 0;
    for (const Candidate& c : candidates) n += c.optional ? 0 : 1;
    return n;
}

Result Result::withoutAabbs() const {
    Result r;
    r.candidates.reserve(candidates.size());  // rays through tens of thousands of coincident triangles
    for (const Candidate& c : candidates)
        if (!c.aabb) r.candidates.push_back(c);
    return r;
}

bool boxInterval(const Vec3& o, const Vec3& d, const Vec3& lo, const Vec3& hi, double& t0, double& t1) {
    t0 = -std::numeric_limits<double>::infinity();
    t1 = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        if (!(lo[k] <= hi[k]) || (d[k] == 0 && (o[k] < lo[k] || o[k] > hi[k]))) {
            t0 = std::numeric_limits<double>::infinity();
            t1 = -t0;
            return false;
        }
        if (d[k] == 0) continue;
        double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
    }
    return t0 <= t1;
}

namespace {
// Slab test against a box grown by a generous margin; only used to skip instances that cannot be hit.
bool mayHitBox(const Vec3& o, const Vec3& d, Vec3 lo, Vec3 hi, double tMin, double tMax) {
    if (lo[0] > hi[0]) return false;
    double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], maxAbs(lo), maxAbs(hi), 1e-6});
    const double margin = 1e-3 * extent;
    double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        lo[k] -= margin;
        hi[k] += margin;
        if (d[k] == 0) {
            if (o[k] < lo[k] || o[k] > hi[k]) return false;
            continue;
        }
        double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
    }
    if (t0 > t1) return false;
    if (t1 < tMin - 1e-3 * (std::fabs(tMin) + std::fabs(t1) + 1.0)) return false;
    if (!std::isinf(tMax) && t0 > tMax + 1e-3 * (std::fabs(tMax) + std::fabs(t0) + 1.0)) return false;
    return true;
}

constexpr double kRel = 1e-5;

// An instance's object-space ray and the magnitudes the tolerances scale with.
struct ObjectRay {
    Vec3 o, d;
    double minv;         // infinity norm of the inverse's 3x3 part
    double originScale;  // magnitude of the coordinates the world-to-object transform of the origin involves
    double dlen;         // |d|
    double dwMax;        // largest world direction component
};

ObjectRay objectRay(const Instance& inst, const Vec3& ow, const Vec3& dw) {
    const auto& M = inst.toObject;
    ObjectRay r;
    for (int k = 0; k < 3; ++k) {
        r.o[k] = M[k][0] * ow[0] + M[k][1] * ow[1] + M[k][2] * ow[2] + M[k][3];
        r.d[k] = M[k][0] * dw[0] + M[k][1] * dw[1] + M[k][2] * dw[2];
    }
    r.minv = 0;
    for (int k = 0; k < 3; ++k) r.minv = std::max(r.minv, std::fabs(M[k][0]) + std::fabs(M[k][1]) + std::fabs(M[k][2]));
    r.originScale = maxAbs(r.o) + r.minv * maxAbs(ow) + std::max({std::fabs(M[0][3]), std::fabs(M[1][3]), std::fabs(M[2][3])});
    r.dlen = norm(r.d);
    r.dwMax = maxAbs(dw);
    return r;
}

// One triangle against an object-space ray, before any culling.
TriangleTest testTriangle(const Triangle& tri, const ObjectRay& r, double tMin, double tMax) {
    TriangleTest x;
    if (!tri.active) return x;
    const Vec3 &o = r.o, &d = r.d;
    const Vec3 e1 = sub(tri.v[1], tri.v[0]), e2 = sub(tri.v[2], tri.v[0]);
    const Vec3 n = cross(e1, e2);
    const double dn = dot(n, d);
    x.status = TriangleStatus::EdgeOn;
    x.dn = dn;
    if (dn == 0) return x;  // edge-on (or degenerate): never a candidate
    const Vec3 pvec = cross(d, e2);
    const double det = dot(e1, pvec);  // == -dn
    const Vec3 tvec = sub(o, tri.v[0]);
    const double u = dot(tvec, pvec) / det;
    const Vec3 qvec = cross(tvec, e1);
    const double v = dot(d, qvec) / det;
    const double t = dot(e2, qvec) / det;
    const double w = 1.0 - u - v;
    const double nlen = norm(n);
    const double cosv = std::fabs(dn) / (nlen * r.dlen);
    x.t = t, x.bary[0] = w, x.bary[1] = u, x.bary[2] = v, x.cosine = cosv;
    if (!(cosv > 0)) return x;
    const Vec3 hit{o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    const double scale = std::max({r.originScale, maxAbs(hit), std::fabs(t) * r.minv * r.dwMax, maxAbs(tri.v[0]),
                                   maxAbs(tri.v[1]), maxAbs(tri.v[2]), 1e-30});
    const double tolDist = kRel * scale;
    // Heights of the triangle over each edge: distance from vertex k to the opposite edge.
    const double h0 = nlen / norm(sub(tri.v[2], tri.v[1]));
    const double h1 = nlen / norm(e2);
    const double h2 = nlen / norm(e1);
    const double heights[3] = {h0, h1, h2};
    bool inside = true, near = true;
    double baryTol = 0;
    for (int k = 0; k < 3; ++k) {
        double margin = std::max(kRel, tolDist / (heights[k] * cosv));
        if (!std::isfinite(margin)) margin = std::numeric_limits<double>::infinity();
        baryTol = std::max(baryTol, margin);
        if (!(x.bary[k] > margin)) inside = false;
        if (!(x.bary[k] >= -margin)) near = false;
    }
    double tTol = kRel * std::fabs(t) + tolDist / (r.dlen * std::max(cosv, 1e-6));
    // So ill-conditioned (nearly degenerate after rounding) that the whole triangle lies within the
    // tolerance: its plane, hence t, is not determined by float arithmetic.
    if (baryTol > 0.5) tTol = std::numeric_limits<double>::infinity();
    x.baryTolerance = baryTol, x.tTolerance = tTol, x.inside = inside, x.tolDistance = tolDist, x.scale = scale;
    for (int k = 0; k < 3; ++k) x.distance[k] = x.bary[k] * heights[k];
    x.inRange = t > tMin + tTol && t < tMax - tTol;
    const bool nearRange = t > tMin - tTol && t < tMax + tTol;
    x.status = !near ? TriangleStatus::Outside : !nearRange ? TriangleStatus::OutOfRange : TriangleStatus::Candidate;
    return x;
}
}  // namespace

const char* triangleStatusName(TriangleStatus s) {
    switch (s) {
        case TriangleStatus::Candidate: return "candidate";
        case TriangleStatus::Inactive: return "inactive";
        case TriangleStatus::EdgeOn: return "edge-on";
        case TriangleStatus::Outside: return "outside the triangle beyond the margin";
        case TriangleStatus::OutOfRange: return "outside [tMin, tMax] beyond the tolerance";
    }
    return "?";
}

TriangleTest examineTriangle(const Scene& scene, const Ray& ray, int32_t instanceId, int32_t geometryIndex,
                             int32_t primitiveIndex) {
    if (instanceId < 0 || size_t(instanceId) >= scene.instances.size()) return {};
    const Instance& inst = scene.instances[size_t(instanceId)];
    if (!inst.blas || geometryIndex < 0 || size_t(geometryIndex) >= inst.blas->geometries.size()) return {};
    const Geometry& geom = inst.blas->geometries[size_t(geometryIndex)];
    if (primitiveIndex < 0 || size_t(primitiveIndex) >= geom.triangles.size()) return {};
    const ObjectRay r = objectRay(inst, {ray.origin[0], ray.origin[1], ray.origin[2]},
                                  {ray.direction[0], ray.direction[1], ray.direction[2]});
    return testTriangle(geom.triangles[size_t(primitiveIndex)], r, ray.tMin, ray.tMax);
}

Result trace(const Scene& scene, const Ray& ray, uint32_t rayFlags, uint32_t cullMask) {
    Result result;
    const uint32_t mask = cullMask & 0xFFu;
    const Vec3 ow{ray.origin[0], ray.origin[1], ray.origin[2]};
    const Vec3 dw{ray.direction[0], ray.direction[1], ray.direction[2]};
    const double tMin = ray.tMin, tMax = ray.tMax;

    for (size_t id = 0; id < scene.instances.size(); ++id) {
        const Instance& inst = scene.instances[id];
        if (!inst.blas) continue;
        if ((inst.mask & mask) == 0) continue;
        const ObjectRay objRay = objectRay(inst, ow, dw);
        const Vec3 &o = objRay.o, &d = objRay.d;
        if (!mayHitBox(o, d, inst.blas->lo, inst.blas->hi, tMin, tMax)) continue;
        const double minv = objRay.minv, originScale = objRay.originScale;

        for (size_t gi = 0; gi < inst.blas->geometries.size(); ++gi) {
            const Geometry& geom = inst.blas->geometries[gi];
            // Opacity: the geometry's (or, per candidate below, its micromap's), then the instance's and the ray's
            // overrides, then the culls.
            auto resolve = [&](bool geometryOpaque) {
                bool opaque = geometryOpaque;
                if (inst.flags & kInstForceOpaque) opaque = true;
                if (inst.flags & kInstForceNoOpaque) opaque = false;
                if (rayFlags & kRayOpaque) opaque = true;
                if (rayFlags & kRayNoOpaque) opaque = false;
                return opaque;
            };
            auto culled = [&](bool opaque) {
                return ((rayFlags & kRayCullOpaque) && opaque) || ((rayFlags & kRayCullNoOpaque) && !opaque);
            };
            const bool opaque = resolve(geom.opaque);
            // [EXT-OMM] "If the intersection candidate is with a geometry with an associated opacity micromap and
            // VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_BIT_KHR is not set in its instance then the micromap is
            // used to determine geometry opacity instead of the VK_GEOMETRY_OPAQUE_BIT_KHR flag in the geometry."
            const bool micromapDecides = geom.micromap && !(inst.flags & kInstDisableOmm);
            const bool force2State = (inst.flags & kInstForceOmm2State) || (rayFlags & kRayForceOmm2State);
            if (!micromapDecides && culled(opaque)) continue;

            if (geom.type == VK_GEOMETRY_TYPE_AABBS_KHR) {
                if (rayFlags & kRaySkipAabbs) continue;
                // The implementation tests its own float object ray: origin and direction are off by the rounding
                // of the world-to-object transform, and the ray points by that much times t. Within delta of the
                // box surface a candidate is optional.
                const double cond = maxAbs(d) > 0 ? std::max(1.0, minv * maxAbs(dw) / maxAbs(d)) : 1.0;
                for (size_t pi = 0; pi < geom.aabbs.size(); ++pi) {
                    const Aabb& box = geom.aabbs[pi];
                    if (!box.valid()) continue;  // inactive or inverted: never hit
                    double boxScale = 0;
                    for (int k = 0; k < 3; ++k)
                        for (double v : {box.lo[k], box.hi[k]})
                            if (std::isfinite(v)) boxScale = std::max(boxScale, std::fabs(v));
                    const double delta = kRel * std::max({originScale, boxScale, 1e-30}) * cond;
                    Vec3 glo, ghi, slo, shi;
                    for (int k = 0; k < 3; ++k) {
                        glo[k] = box.lo[k] - delta, ghi[k] = box.hi[k] + delta;
                        slo[k] = box.lo[k] + delta, shi[k] = box.hi[k] - delta;
                    }
                    double e0, e1, g0, g1, s0, s1;
                    const bool exact = boxInterval(o, d, box.lo, box.hi, e0, e1) &&
                                       std::max(e0, tMin) <= std::min(e1, tMax);
                    const bool grown = boxInterval(o, d, glo, ghi, g0, g1) && std::max(g0, tMin) <= std::min(g1, tMax);
                    const bool shrunk = boxInterval(o, d, slo, shi, s0, s1) && std::max(s0, tMin) <= std::min(s1, tMax);
                    if (!grown) continue;
                    Candidate c;
                    c.aabb = true;
                    c.t = exact ? std::max(e0, tMin) : std::max(g0, tMin);
                    c.tExit = exact ? std::min(e1, tMax) : std::min(g1, tMax);
                    // How far the entry moves when the box grows or shrinks by delta; without an exact hit, the
                    // whole grown interval.
                    c.tTolerance = exact ? std::fabs(std::max(g0, tMin) - c.t) : c.tExit - c.t;
                    if (shrunk) c.tTolerance = std::max(c.tTolerance, std::fabs(std::max(s0, tMin) - c.t));
                    c.instanceId = int32_t(id);
                    c.geometryIndex = int32_t(gi);
                    c.primitiveIndex = int32_t(pi);
                    c.customIndex = inst.customIndex;
                    c.sbtOffset = inst.sbtOffset;
                    c.facingAmbiguous = true;  // AABBs have no facing
                    c.opaque = opaque;
                    c.optional = !shrunk;
                    c.baryTolerance = std::numeric_limits<double>::infinity();  // no barycentrics
                    for (int k = 0; k < 3; ++k) {
                        c.objectOrigin[k] = o[k];
                        c.objectDirection[k] = d[k];
                    }
                    result.candidates.push_back(c);
                }
                continue;
            }
            if (rayFlags & kRaySkipTriangles) continue;  // SkipBuiltinPrimitivesNV: spheres and LSS too
            if (geom.type == VK_GEOMETRY_TYPE_SPHERES_NV || geom.type == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV) {
                Candidate proto;
                proto.instanceId = int32_t(id);
                proto.geometryIndex = int32_t(gi);
                proto.customIndex = inst.customIndex;
                proto.sbtOffset = inst.sbtOffset;
                proto.opaque = opaque;
                const double cond = maxAbs(d) > 0 ? std::max(1.0, minv * maxAbs(dw) / maxAbs(d)) : 1.0;
                for (int k = 0; k < 3; ++k) proto.objectOrigin[k] = o[k], proto.objectDirection[k] = d[k];
                sweptCandidates(geom, o, d, tMin, tMax, originScale * cond, proto, result.candidates);
                continue;
            }
            for (size_t pi = 0; pi < geom.triangles.size(); ++pi) {
                const Triangle& tri = geom.triangles[pi];
                const TriangleTest x = testTriangle(tri, objRay, tMin, tMax);
                if (x.status != TriangleStatus::Candidate) continue;
                bool front = x.dn < 0;
                if (inst.flags & kInstFlip) front = !front;
                // Nearly edge-on, or so ill-conditioned (nearly degenerate after rounding) that the whole triangle is
                // within the tolerance: float arithmetic may decide the facing either way.
                const bool facingAmbiguous = x.cosine < 1e-6 || x.baryTolerance > 0.5;
                bool optional = !x.inside || !x.inRange || facingAmbiguous;
                if (!(inst.flags & kInstCullDisable)) {
                    const bool cullThis = ((rayFlags & kRayCullBack) && !front) || ((rayFlags & kRayCullFront) && front);
                    if (cullThis && !facingAmbiguous) continue;
                }
                bool candidateOpaque = opaque, opacityAmbiguous = false;
                if (micromapDecides) {
                    // Every outcome the micromap may give within the barycentrics' tolerance: a candidate that some
                    // of them ignore or cull is optional; one that all of them drop is none.
                    bool anyKept = false, anyDropped = false, opacityKnown = true, first = true;
                    for (const Opacity o : micromapOutcomes(*geom.micromap, pi, x.bary[1], x.bary[2], x.baryTolerance,
                                                            force2State)) {
                        // "If the result of the opacity micromap operation is ignored, the candidate is considered
                        // neither opaque or non-opaque and execution instead proceeds with enumerating the next
                        // candidate."
                        const bool kept = o != Opacity::Ignored && !culled(resolve(o == Opacity::Opaque));
                        if (!kept) {
                            anyDropped = true;
                            continue;
                        }
                        const bool op = resolve(o == Opacity::Opaque);
                        if (!first && op != candidateOpaque) opacityKnown = false;
                        candidateOpaque = op, first = false, anyKept = true;
                    }
                    if (!anyKept) continue;
                    if (anyDropped || !opacityKnown) optional = true;
                    opacityAmbiguous = !opacityKnown;
                }
                Candidate c;
                c.t = x.t;
                c.bary[0] = x.bary[1];
                c.bary[1] = x.bary[2];
                c.instanceId = int32_t(id);
                c.geometryIndex = int32_t(gi);
                c.primitiveIndex = int32_t(pi);
                c.customIndex = inst.customIndex;
                c.sbtOffset = inst.sbtOffset;
                c.frontFace = front;
                c.facingAmbiguous = facingAmbiguous;
                c.opaque = candidateOpaque;
                c.opacityAmbiguous = opacityAmbiguous;
                c.optional = optional;
                c.tTolerance = x.tTolerance;
                c.baryTolerance = x.baryTolerance;
                for (int k = 0; k < 3; ++k) {
                    c.objectOrigin[k] = o[k];
                    c.objectDirection[k] = d[k];
                }
                result.candidates.push_back(c);
            }
        }
    }
    return result;
}

// ---- [NV-motion] -------------------------------------------------------------------------------------------------
Geometry fetchTrianglesAtTime1(const VkAccelerationStructureGeometryKHR& geometry,
                               const VkAccelerationStructureBuildRangeInfoKHR& range) {
    VkAccelerationStructureGeometryKHR g = geometry;
    for (auto* p = static_cast<const VkBaseInStructure*>(geometry.geometry.triangles.pNext); p; p = p->pNext)
        if (p->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV)
            g.geometry.triangles.vertexData =
                reinterpret_cast<const VkAccelerationStructureGeometryMotionTrianglesDataNV*>(p)->vertexData;
    return fetchTriangles(g, range);
}

std::shared_ptr<const Blas> blasAt(const std::shared_ptr<const Blas>& blas, double time) {
    if (!blas || !blas->atTime1) return blas;
    auto out = std::make_shared<Blas>();
    out->geometries = blas->geometries;
    for (size_t g = 0; g < out->geometries.size(); ++g) {
        auto& tris = out->geometries[g].triangles;
        const auto& later = blas->atTime1->geometries[g].triangles;
        for (size_t i = 0; i < tris.size(); ++i) {
            tris[i].active = tris[i].active && later[i].active;
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k) tris[i].v[j][k] += time * (later[i].v[j][k] - tris[i].v[j][k]);
        }
    }
    out->computeBounds();
    return out;
}

namespace {
// Rotation of v by the unit quaternion (x, y, z, w): v + 2w (q x v) + 2 q x (q x v).
Vec3 rotate(const double q[4], const Vec3& v) {
    const Vec3 u{q[0], q[1], q[2]};
    const Vec3 c1 = cross(u, v);
    const Vec3 c2 = cross(u, c1);
    Vec3 r;
    for (int k = 0; k < 3; ++k) r[k] = v[k] + 2.0 * q[3] * c1[k] + 2.0 * c2[k];
    return r;
}
}  // namespace

void srtMatrix(const double p[16], double out[3][4]) {
    // S maps object space: columns of S are its images of the basis vectors and of the origin.
    const double S[3][4] = {{p[0], p[1], p[2], p[3]}, {0, p[4], p[5], p[6]}, {0, 0, p[7], p[8]}};
    double q[4] = {p[9], p[10], p[11], p[12]};
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (len > 0) {
        for (double& c : q) c /= len;
    } else {
        q[0] = q[1] = q[2] = 0, q[3] = 1;
    }
    for (int col = 0; col < 4; ++col) {
        const Vec3 r = rotate(q, {S[0][col], S[1][col], S[2][col]});
        for (int row = 0; row < 3; ++row) out[row][col] = r[row] + (col == 3 ? p[13 + row] : 0.0);
    }
}

MotionInstance decodeMotionInstance(uint32_t type, const void* payload,
                                    const std::function<std::shared_ptr<const Blas>(uint64_t)>& lookup) {
    const uint8_t* p = static_cast<const uint8_t*>(payload);
    MotionInstance m;
    m.type = type;
    size_t words = 48;  // static: VkAccelerationStructureInstanceKHR
    if (type == 0) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) m.transform0[r][c] = m.transform1[r][c] = load<float>(p + 4 * (4 * r + c));
    } else if (type == 1) {  // VkAccelerationStructureMatrixMotionInstanceNV
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) {
                m.transform0[r][c] = load<float>(p + 4 * (4 * r + c));
                m.transform1[r][c] = load<float>(p + 48 + 4 * (4 * r + c));
            }
        words = 96;
    } else if (type == 2) {  // VkAccelerationStructureSRTMotionInstanceNV
        for (int k = 0; k < 16; ++k) {
            m.srt0[k] = load<float>(p + 4 * k);
            m.srt1[k] = load<float>(p + 64 + 4 * k);
        }
        words = 128;
    } else {
        throw std::invalid_argument("oracle: bad motion instance type");
    }
    const uint32_t w0 = load<uint32_t>(p + words), w1 = load<uint32_t>(p + words + 4);
    m.base.customIndex = w0 & 0xFFFFFFu;
    m.base.mask = w0 >> 24;
    m.base.sbtOffset = w1 & 0xFFFFFFu;
    m.base.flags = w1 >> 24;
    m.base.reference = load<uint64_t>(p + words + 8);
    if (m.base.reference != 0) {
        m.base.blas = lookup(m.base.reference);
        if (!m.base.blas) throw std::invalid_argument("oracle: unknown acceleration structure reference");
    }
    return m;
}

Instance instanceAt(const MotionInstance& m, double time) {
    Instance inst = m.base;
    if (m.type == 2) {
        double p[16];
        for (int k = 0; k < 16; ++k) p[k] = (1.0 - time) * m.srt0[k] + time * m.srt1[k];
        srtMatrix(p, inst.toWorld);
    } else {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) inst.toWorld[r][c] = (1.0 - time) * m.transform0[r][c] + time * m.transform1[r][c];
    }
    invert34(inst.toWorld, inst.toObject);
    inst.blas = blasAt(m.base.blas, time);
    return inst;
}

Scene MotionScene::at(double time) const {
    Scene s;
    for (const MotionInstance& m : instances) s.instances.push_back(instanceAt(m, time));
    return s;
}

}  // namespace oracle
