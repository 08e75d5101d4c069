#include "cost_tracer.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace vkas_tool {
namespace {

template <class T>
T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

constexpr uint32_t kMaxStack = 2 * (7 * 64 + 1);  // 7 siblings a level, 64 levels (FORMAT.md's depth bound)

struct Ray {
    float o[3], d[3], inv[3];
    float tMin, tMax;
};

Ray makeRay(const float o[3], const float d[3], float tMin, float tMax) {
    Ray r;
    for (int k = 0; k < 3; ++k) {
        r.o[k] = o[k], r.d[k] = d[k];
        r.inv[k] = 1.0f / d[k];  // +-inf for a zero component: the slab test below handles it
    }
    r.tMin = tMin, r.tMax = tMax;
    return r;
}

// Entry distance of the ray into slot s of the node, or +inf when it misses the box within [tMin, tMax].
float enterSlot(const unsigned char* node, int s, const Ray& r) {
    float tNear = r.tMin, tFar = r.tMax;
    for (int k = 0; k < 3; ++k) {
        const float lo = load<float>(node + 64 * k + 4 * s), hi = load<float>(node + 64 * k + 32 + 4 * s);
        float t0 = (lo - r.o[k]) * r.inv[k], t1 = (hi - r.o[k]) * r.inv[k];
        if (std::isnan(t0) || std::isnan(t1)) {  // zero direction and origin on the slab's plane: inside
            if (r.o[k] < lo || r.o[k] > hi) return INFINITY;
            continue;
        }
        if (t0 > t1) std::swap(t0, t1);
        tNear = std::fmax(tNear, t0);
        tFar = std::fmin(tFar, t1 * (1.0f + 4.0f * std::numeric_limits<float>::epsilon()));  // conservative
    }
    return tNear <= tFar ? tNear : INFINITY;
}

// Double-precision ray / triangle test (both faces), t within (tMin, tMax].
bool hitTriangle(const double v[3][3], const Ray& r, double& t) {
    const double e1[3] = {v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
    const double e2[3] = {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
    const double d[3] = {r.d[0], r.d[1], r.d[2]};
    const double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0) return false;
    const double s[3] = {r.o[0] - v[0][0], r.o[1] - v[0][1], r.o[2] - v[0][2]};
    const double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    if (u < 0 || u > 1) return false;
    const double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    const double w = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    if (w < 0 || u + w > 1) return false;
    t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    return t >= r.tMin && t <= r.tMax;
}

struct Entry {
    uint64_t ref;
    float dist;
};

// Walks one tree (either level): `leaf(first, count)` tests a leaf's records and may lower ray.tMax.
template <class Leaf>
void walk(const unsigned char* block, Ray& ray, TraceCounters& c, Leaf&& leaf) {
    const uint64_t root = load<uint64_t>(block + 24);
    if (root == 0) return;
    const uint64_t nodeOffset = load<uint64_t>(block + 80);
    Entry stack[kMaxStack];
    uint32_t sp = 0;
    stack[sp++] = {root, ray.tMin};
    while (sp > 0) {
        const Entry e = stack[--sp];
        if (e.dist > ray.tMax) continue;  // entered past the closest hit so far
        const uint32_t kind = uint32_t(e.ref >> 62);
        if (kind == 2) {
            leaf(e.ref & 0xFFFFFFFFFFull, uint32_t((e.ref >> 40) & 0xFF));
            continue;
        }
        ++c.nodes;
        const unsigned char* node = block + nodeOffset + 256 * uint64_t(e.ref & 0xFFFFFFFFu);
        Entry hits[8];
        uint32_t n = 0;
        for (int s = 0; s < 8; ++s) {
            const uint64_t ref = load<uint64_t>(node + 192 + 8 * s);
            if (ref == 0) continue;
            const float t = enterSlot(node, s, ray);
            if (t == INFINITY) continue;
            uint32_t k = n++;  // by descending distance, so that the nearest is popped first
            while (k > 0 && hits[k - 1].dist < t) hits[k] = hits[k - 1], --k;
            hits[k] = {ref, t};
        }
        for (uint32_t k = 0; k < n && sp < kMaxStack; ++k) stack[sp++] = hits[k];
    }
}

}  // namespace

CostTracer::CostTracer(const unsigned char* topLevel, std::vector<const unsigned char*> bottomLevels)
    : top_(topLevel), bottom_(std::move(bottomLevels)) {}

CostHit CostTracer::trace(const VkasRay& in, TraceCounters& c) const {
    CostHit best;
    Ray world = makeRay(in.origin, in.direction, in.tMin, in.tMax);
    const uint64_t instanceOffset = load<uint64_t>(top_ + 88);
    walk(top_, world, c, [&](uint64_t first, uint32_t count) {
        for (uint32_t i = 0; i < count; ++i) {
            const unsigned char* rec = top_ + instanceOffset + 128 * (first + i);
            ++c.instances;
            const uint32_t id = load<uint32_t>(rec + 112);
            if (id >= bottom_.size() || !bottom_[id]) continue;
            float w2o[3][4];
            std::memcpy(w2o, rec + 48, sizeof w2o);
            float o[3], d[3];
            for (int r = 0; r < 3; ++r) {
                o[r] = w2o[r][0] * in.origin[0] + w2o[r][1] * in.origin[1] + w2o[r][2] * in.origin[2] + w2o[r][3];
                d[r] = w2o[r][0] * in.direction[0] + w2o[r][1] * in.direction[1] + w2o[r][2] * in.direction[2];
            }
            Ray object = makeRay(o, d, world.tMin, world.tMax);  // t is the same in both spaces
            const unsigned char* blas = bottom_[id];
            const uint64_t leafOffset = load<uint64_t>(blas + 88);
            walk(blas, object, c, [&](uint64_t firstTri, uint32_t n) {
                // Triangle leaves: structure of arrays, row r (3 vertex + axis) at 4 r n, lane l at 4 l.
                const unsigned char* base = blas + leafOffset + 44 * firstTri;
                for (uint32_t l = 0; l < n; ++l) {
                    ++c.primitives;
                    const uint32_t word = load<uint32_t>(base + 40 * n + 4 * l);
                    if ((word >> 24) & 0x2u) continue;  // degenerate (ALLOW_UPDATE builds): never hit
                    double v[3][3];
                    for (int r = 0; r < 9; ++r) v[r / 3][r % 3] = load<float>(base + 4 * (r * n + l));
                    double t;
                    if (hitTriangle(v, object, t) && float(t) < world.tMax) {
                        object.tMax = world.tMax = float(t);
                        best.hit = true;
                        best.t = float(t);
                        best.instanceId = int32_t(id);
                        best.primitiveIndex = int32_t(load<uint32_t>(base + 36 * n + 4 * l));
                    }
                }
            });
        }
    });
    return best;
}

}  // namespace vkas_tool
