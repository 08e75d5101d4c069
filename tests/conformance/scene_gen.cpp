#include "scene_gen.hpp"

#include <vkas/vkas_compat.h>
#include <oracle.hpp>
#include <vkas_test.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "scene_writer.hpp"

namespace diff {

namespace {

using vt::Rng;

// SPIR-V ray flags and instance flags.
constexpr uint32_t kOpaque = 0x1, kNoOpaque = 0x2, kTerminate = 0x4, kSkipClosest = 0x8, kCullBack = 0x10,
                   kCullFront = 0x20, kCullOpaque = 0x40, kCullNoOpaque = 0x80, kSkipTriangles = 0x100,
                   kSkipAabbs = 0x200;
constexpr uint32_t kInstanceFlags[] = {VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR,
                                       VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR,
                                       VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                       VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR};

// ---- Random pieces ---------------------------------------------------------------------------------------------

Point randomPoint(Rng& rng, double extent) {
    return {rng.uniform(-extent, extent), rng.uniform(-extent, extent), rng.uniform(-extent, extent)};
}

// A soup of `n` random triangles of size ~`size` inside [-1, 1]^3 (unit-ish, so SNORM formats can hold them).
void randomSoup(Rng& rng, uint32_t n, double size, std::vector<Point>& positions, std::vector<uint32_t>& indices) {
    for (uint32_t i = 0; i < n; ++i) {
        const Point c = randomPoint(rng, 1.0 - size);
        for (int k = 0; k < 3; ++k) {
            indices.push_back(uint32_t(positions.size()));
            positions.push_back({c[0] + rng.uniform(-size, size), c[1] + rng.uniform(-size, size),
                                 c[2] + rng.uniform(-size, size)});
        }
    }
}

std::vector<std::array<float, 6>> randomBoxes(Rng& rng, uint32_t n, double size) {
    std::vector<std::array<float, 6>> boxes;
    for (uint32_t i = 0; i < n; ++i) {
        const Point c = randomPoint(rng, 1.0 - size);
        std::array<float, 6> b;
        for (int k = 0; k < 3; ++k) {
            const double h = rng.uniform(0.02, size);
            b[size_t(k)] = float(c[size_t(k)] - h);
            b[size_t(k) + 3] = float(c[size_t(k)] + h);
        }
        boxes.push_back(b);
    }
    return boxes;
}

uint32_t randomGeometryFlags(Rng& rng) {
    uint32_t f = 0;
    if (rng.coin(0.5)) f |= VK_GEOMETRY_OPAQUE_BIT_KHR;
    if (rng.coin(0.5)) f |= VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
    return f;
}

uint32_t randomInstanceFlags(Rng& rng) {
    uint32_t f = 0;
    for (uint32_t bit : kInstanceFlags)
        if (rng.coin(0.25)) f |= bit;
    // FORCE_OPAQUE and FORCE_NO_OPAQUE must not be used together.
    if ((f & VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR) && (f & VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR))
        f &= ~uint32_t(rng.coin() ? VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR : VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR);
    return f;
}

// Valid ray flags (spec-digest 6.1 exclusivity rules), every flag reachable.
uint32_t randomRayFlags(Rng& rng) {
    uint32_t f = 0;
    const uint32_t opacity[] = {0, 0, kOpaque, kNoOpaque, kCullOpaque, kCullNoOpaque};
    f |= opacity[rng.below(6)];
    const uint32_t triangles[] = {0, 0, 0, kSkipTriangles, kCullBack, kCullFront};
    f |= triangles[rng.below(6)];
    if (!(f & kSkipTriangles) && rng.coin(0.1)) f |= kSkipAabbs;
    if (rng.coin(0.2)) f |= kTerminate;
    if (rng.coin(0.1)) f |= kSkipClosest;
    return f;
}

// Count mode must not depend on traversal order: nothing may commit, so opaque candidates are made non-opaque or
// culled (both still count what remains).
uint32_t countModeFlags(Rng& rng, uint32_t flags) {
    flags &= ~(kOpaque | kNoOpaque | kCullOpaque | kCullNoOpaque);
    return flags | (rng.coin(0.75) ? kNoOpaque : kCullOpaque);
}

VkTransformMatrixKHR identity() { return vt::identityTransform(); }

Point applyTransform(const VkTransformMatrixKHR& m, const Point& p) {
    Point r;
    for (int i = 0; i < 3; ++i)
        r[size_t(i)] = m.matrix[i][0] * p[0] + m.matrix[i][1] * p[1] + m.matrix[i][2] * p[2] + m.matrix[i][3];
    return r;
}

// ---- Scene assembly --------------------------------------------------------------------------------------------

// Tracks what was put in the scene so rays can aim at it: world-space sample points per instance.
struct Builder {
    Rng& rng;
    const Capabilities& caps;
    Case out;
    SceneWriter writer{out.scene};
    std::vector<std::vector<Point>> blasTargets;  // object-space points on each BLAS's primitives
    std::vector<Point> worldTargets;
    double worldExtent = 1.0;
    bool hasAabbs = false;

    Builder(Rng& r, const Capabilities& c) : rng(r), caps(c) {}

    VkFormat randomFormat() {
        return caps.vertexFormats.empty() ? VK_FORMAT_R32G32B32_SFLOAT
                                          : caps.vertexFormats[rng.below(uint32_t(caps.vertexFormats.size()))];
    }

    TriangleOptions randomLayout(VkFormat format, uint32_t vertexCount) {
        TriangleOptions o;
        o.format = format;
        const uint32_t pick = rng.below(3);
        o.indexType = pick == 0 ? VK_INDEX_TYPE_NONE_KHR
                      : (pick == 1 && vertexCount < 65536) ? VK_INDEX_TYPE_UINT16
                                                           : VK_INDEX_TYPE_UINT32;
        o.extraStride = rng.coin(0.3) ? rng.below(3) : 0;
        o.primitiveSkip = rng.coin(0.3) ? rng.below(4) : 0;
        o.firstVertex = rng.coin(0.3) ? rng.below(5) : 0;
        o.transformSkip = rng.below(2);
        return o;
    }

    int32_t addBlas(std::vector<Geometry> geometries, VkBuildAccelerationStructureFlagsKHR flags,
                    std::vector<Point> targets) {
        Blas b;
        b.geometries = std::move(geometries);
        b.buildFlags = flags;
        out.scene.blases.push_back(std::move(b));
        blasTargets.push_back(std::move(targets));
        return int32_t(out.scene.blases.size() - 1);
    }

    // A BLAS of 1-3 triangle soups in random formats and layouts; targets are triangle interior points.
    int32_t soupBlas(uint32_t minTris, uint32_t maxTris, double size, bool randomFormats, bool allowTransform) {
        std::vector<Geometry> geoms;
        std::vector<Point> targets;
        const uint32_t geometryCount = 1 + rng.below(3);
        VkBuildAccelerationStructureFlagsKHR flags = rng.coin(0.3) ? VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR : 0;
        if (caps.positionFetch && rng.coin(0.3)) flags |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
        for (uint32_t g = 0; g < geometryCount; ++g) {
            std::vector<Point> positions;
            std::vector<uint32_t> indices;
            randomSoup(rng, minTris + rng.below(maxTris - minTris + 1), size, positions, indices);
            const VkFormat format = randomFormats ? randomFormat() : VK_FORMAT_R32G32B32_SFLOAT;
            TriangleOptions o = randomLayout(format, uint32_t(positions.size()));
            o.flags = randomGeometryFlags(rng);
            VkTransformMatrixKHR transform;
            if (allowTransform && rng.coin(0.3)) {
                transform = vt::randomTransform(rng, 0.5f, 1.5f, rng.coin(0.3), 0.5f);
                o.transform = &transform;
            }
            geoms.push_back(writer.triangles(positions, indices, o));
            // Targets from the decoded, transformed triangles are computed later by the reference; here, the
            // intended positions (close enough to aim at).
            for (size_t i = 0; i + 2 < indices.size(); i += 3) {
                double a = rng.uniform(0.05, 0.9), b = rng.uniform(0.05, 0.9);
                if (a + b > 0.95) a = 0.95 - a * 0.5, b = 0.95 - a - 0.01;
                Point p;
                for (int k = 0; k < 3; ++k)
                    p[size_t(k)] = positions[indices[i]][size_t(k)] * (1 - a - b) + positions[indices[i + 1]][size_t(k)] * a +
                                   positions[indices[i + 2]][size_t(k)] * b;
                if (format == VK_FORMAT_R32G32_SFLOAT || format == VK_FORMAT_R16G16_SFLOAT ||
                    format == VK_FORMAT_R16G16_SNORM || format == VK_FORMAT_R8G8_SNORM || format == VK_FORMAT_R64G64_SFLOAT)
                    p[2] = 0;
                targets.push_back(o.transform ? applyTransform(*o.transform, p) : p);
            }
        }
        return addBlas(std::move(geoms), flags, std::move(targets));
    }

    int32_t aabbBlas(uint32_t minBoxes, uint32_t maxBoxes, double size, double inactiveFraction) {
        hasAabbs = true;
        std::vector<Geometry> geoms;
        std::vector<Point> targets;
        const uint32_t geometryCount = 1 + rng.below(2);
        for (uint32_t g = 0; g < geometryCount; ++g) {
            auto boxes = randomBoxes(rng, minBoxes + rng.below(maxBoxes - minBoxes + 1), size);
            for (auto& b : boxes) {
                if (rng.coin(inactiveFraction)) {
                    b[0] = NAN;
                    continue;
                }
                targets.push_back({rng.uniform(b[0], b[3]), rng.uniform(b[1], b[4]), rng.uniform(b[2], b[5])});
            }
            AabbOptions o;
            o.flags = randomGeometryFlags(rng);
            o.extraStride = rng.coin(0.3) ? rng.below(3) : 0;
            o.primitiveSkip = rng.coin(0.3) ? rng.below(3) : 0;
            geoms.push_back(writer.aabbs(boxes, o));
        }
        return addBlas(std::move(geoms), rng.coin(0.3) ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR : 0,
                       std::move(targets));
    }

    void addInstance(int32_t blas, const VkTransformMatrixKHR& transform, uint32_t flags, bool randomIds) {
        Instance in;
        in.transform = transform;
        in.blas = blas;
        in.flags = flags;
        if (randomIds) {
            in.customIndex = rng.u32() & 0xFF'FFFFu;
            in.sbtOffset = rng.u32() & 0xFF'FFFFu;
            in.mask = rng.coin(0.8) ? 0xFFu : (rng.u32() & 0xFFu);
        }
        out.scene.instances.push_back(in);
        if (blas >= 0)
            for (const Point& p : blasTargets[size_t(blas)]) worldTargets.push_back(applyTransform(transform, p));
    }

    // ---- Rays ----
    void addRay(const Point& origin, const Point& direction, float tMin, float tMax, uint32_t flags, uint32_t mask,
                Mode mode, int32_t crossings = -1) {
        Ray r{};
        for (int k = 0; k < 3; ++k) {
            r.origin[k] = float(origin[size_t(k)]);
            r.direction[k] = float(direction[size_t(k)]);
        }
        if (hasAabbs)  // the procedural step divides by the direction: keep every component away from zero
            for (float& d : r.direction)
                if (std::fabs(d) < 1e-3f) d = d < 0 ? -1e-3f : 1e-3f;
        r.tMin = tMin;
        r.tMax = tMax;
        r.mode = mode;
        r.flags = mode == kModeCount ? countModeFlags(rng, flags) : flags;
        r.cullMask = mask;
        out.rays.push_back(r);
        out.crossings.push_back(crossings);
    }

    // Rays aimed at the scene's targets from random directions, plus random rays through the scene's volume.
    void randomRays(uint32_t count, double countFraction, bool randomFlags, bool randomMasks, bool randomWindow) {
        for (uint32_t i = 0; i < count; ++i) {
            Point target = worldTargets.empty() || rng.coin(0.2) ? randomPoint(rng, worldExtent)
                                                                  : worldTargets[rng.below(uint32_t(worldTargets.size()))];
            Point dir = randomPoint(rng, 1.0);
            const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            if (len < 1e-3) dir = {0, 0, 1};
            const double distance = rng.uniform(0.5, 3.0) * worldExtent;
            const double dirScale = std::exp(rng.uniform(-2.0, 2.0)) / std::max(len, 1e-3);
            Point origin, direction;
            for (int k = 0; k < 3; ++k) {
                origin[size_t(k)] = target[size_t(k)] - dir[size_t(k)] / std::max(len, 1e-3) * distance;
                direction[size_t(k)] = dir[size_t(k)] * dirScale;
            }
            if (rng.coin(0.05)) {  // axis-aligned
                const int axis = int(rng.below(3));
                direction = {0, 0, 0};
                direction[size_t(axis)] = target[size_t(axis)] > origin[size_t(axis)] ? 1.0 : -1.0;
                for (int k = 0; k < 3; ++k)
                    if (k != axis) origin[size_t(k)] = target[size_t(k)];
            }
            const double dd = direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2];
            const double tHit = ((target[0] - origin[0]) * direction[0] + (target[1] - origin[1]) * direction[1] +
                                 (target[2] - origin[2]) * direction[2]) / dd;  // t of the target
            float tMin = 0, tMax = rng.coin(0.2) ? INFINITY : float(1e3 * tHit + 1e3);
            if (randomWindow) {
                switch (rng.below(6)) {
                    case 0:  // a window somewhere around the target
                        tMin = float(tHit * rng.uniform(0.0, 1.2));
                        tMax = float(tHit * rng.uniform(double(tMin) / tHit + 0.01, 2.0));
                        break;
                    case 1: tMax = float(tHit * (1 - 1e-4)); break;  // ends just before the target
                    case 2: tMax = float(tHit * (1 + 1e-4)); break;  // ends just after it
                    case 3: tMin = float(tHit * (1 - 1e-4)); break;  // starts just before it
                    case 4: tMin = float(tHit * (1 + 1e-4)); break;  // starts just after it
                    default: break;
                }
            }
            const uint32_t flags = randomFlags ? randomRayFlags(rng) : 0;
            const uint32_t mask = randomMasks ? rng.u32() & 0xFFu : 0xFFu;
            addRay(origin, direction, tMin, tMax, flags, mask, rng.coin(countFraction) ? kModeCount : kModeClosest);
        }
    }
};

// ---- Groups ------------------------------------------------------------------------------------------------------

// Triangle soups under many instances: rotations, scales, mirroring, custom indices, SBT offsets, masks, every
// instance flag; random ray flags.
void instanceScene(Builder& b) {
    const uint32_t blasCount = 2 + b.rng.below(4);
    for (uint32_t i = 0; i < blasCount; ++i) b.soupBlas(10, 80, 0.3, false, true);
    const uint32_t instanceCount = 20 + b.rng.below(60);
    b.worldExtent = 6;
    for (uint32_t i = 0; i < instanceCount; ++i) {
        auto m = vt::randomTransform(b.rng, 0.3f, 2.0f, b.rng.coin(0.3), 5.0f);
        b.addInstance(int32_t(b.rng.below(blasCount)), m, randomInstanceFlags(b.rng), true);
    }
    b.randomRays(1500, 0.25, true, true, true);
}

// Every ray flag against opaque and non-opaque geometry, with confirmation by the ray program's rule.
void rayFlagScene(Builder& b) {
    const uint32_t blasCount = 3;
    for (uint32_t i = 0; i < blasCount; ++i) b.soupBlas(20, 60, 0.35, false, false);
    b.worldExtent = 4;
    for (uint32_t i = 0; i < 12; ++i)
        b.addInstance(int32_t(i % blasCount), vt::randomTransform(b.rng, 0.8f, 1.5f, i % 4 == 3, 3.0f),
                      i % 5 == 0 ? randomInstanceFlags(b.rng) : 0, false);
    // Each valid flag combination, with aimed rays.
    const uint32_t opacity[] = {0, kOpaque, kNoOpaque, kCullOpaque, kCullNoOpaque};
    const uint32_t triangles[] = {0, kSkipTriangles, kCullBack, kCullFront};
    for (uint32_t o : opacity)
        for (uint32_t t : triangles)
            for (uint32_t extra : {0u, kTerminate, kSkipClosest, kSkipAabbs}) {
                if ((t & kSkipTriangles) && (extra & kSkipAabbs)) continue;
                const size_t first = b.out.rays.size();
                b.randomRays(24, 0.0, false, false, false);
                for (size_t i = first; i < b.out.rays.size(); ++i) b.out.rays[i].flags = o | t | extra;
            }
    b.randomRays(400, 0.3, true, true, true);
}

// Height fields and closed fans with exactly representable vertices; rays through exact vertices and edges, both
// closest-hit and counting candidates (a watertight implementation reports exactly one per crossing).
void watertightScene(Builder& b) {
    const int n = 8 + int(b.rng.below(9));
    std::vector<Point> positions;
    std::vector<uint32_t> indices;
    std::vector<double> heights;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            const double h = double(int(b.rng.below(17)) - 8) / 16.0;  // exact in every float format
            heights.push_back(h);
            positions.push_back({double(x), double(y), h});
        }
    auto vid = [&](int x, int y) { return uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const uint32_t a = vid(x, y), c = vid(x + 1, y), d = vid(x + 1, y + 1), e = vid(x, y + 1);
            if (b.rng.coin()) indices.insert(indices.end(), {a, c, d, a, d, e});
            else indices.insert(indices.end(), {a, c, e, c, d, e});
        }
    TriangleOptions o;
    o.format = VK_FORMAT_R32G32B32_SFLOAT;
    o.indexType = VK_INDEX_TYPE_UINT32;
    o.flags = VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
    Geometry field = b.writer.triangles(positions, indices, o);

    // A closed fan: k triangles around a centre vertex at the origin, ring vertices at exact coordinates.
    std::vector<Point> fanPositions{{0, 0, 0}};
    std::vector<uint32_t> fanIndices;
    // At least 4 ring vertices with jittered angles: every angular gap stays below 180 degrees, so the centre is
    // inside the ring as seen along the axis and an axial ray crosses the fan exactly once.
    const uint32_t k = 4 + b.rng.below(9);
    for (uint32_t i = 0; i < k; ++i) {
        const double angle = 2 * M_PI * (i + b.rng.uniform(0.1, 0.9)) / k;
        fanPositions.push_back({std::round(std::cos(angle) * 64) / 64, std::round(std::sin(angle) * 64) / 64,
                                double(int(b.rng.below(9)) - 4) / 16});
    }
    for (uint32_t i = 0; i < k; ++i) fanIndices.insert(fanIndices.end(), {0u, 1 + i, 1 + (i + 1) % k});
    TriangleOptions fo;
    fo.format = VK_FORMAT_R32G32B32_SFLOAT;
    fo.indexType = VK_INDEX_TYPE_UINT16;
    Geometry fan = b.writer.triangles(fanPositions, fanIndices, fo);

    const int32_t fieldBlas = b.addBlas({field}, 0, {});
    const int32_t fanBlas = b.addBlas({fan}, 0, {});
    // Integer translations keep every vertex exact in world space.
    b.addInstance(fieldBlas, identity(), 0, false);
    VkTransformMatrixKHR fanAt = identity();
    fanAt.matrix[0][3] = float(n + 4);
    fanAt.matrix[1][3] = 2;
    b.addInstance(fanBlas, fanAt, VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR, false);
    b.worldExtent = n;

    const float top = 4, tMax = 100;
    // Vertical rays through interior vertices and edge midpoints: exactly one crossing.
    for (int i = 0; i < 400; ++i) {
        const int x = 1 + int(b.rng.below(uint32_t(n - 1))), y = 1 + int(b.rng.below(uint32_t(n - 1)));
        Point p{double(x), double(y), top};
        switch (b.rng.below(4)) {
            case 0: break;                           // vertex
            case 1: p[0] += 0.5; break;              // horizontal edge
            case 2: p[1] += 0.5; break;              // vertical edge
            default: p[0] += 0.5, p[1] += 0.5; break;  // cell centre: on the diagonal edge or not, one crossing either way
        }
        if (p[0] >= n || p[1] >= n) continue;
        const bool up = b.rng.coin(0.3);
        if (up) p[2] = -top;
        b.addRay(p, {0, 0, up ? 1.0 : -1.0}, 0, tMax, 0, 0xFF, b.rng.coin(0.6) ? kModeCount : kModeClosest, 1);
    }
    // Slanted rays through exact vertices (origin = vertex + small integer offsets, so the line is exact).
    for (int i = 0; i < 300; ++i) {
        const int x = 1 + int(b.rng.below(uint32_t(n - 1))), y = 1 + int(b.rng.below(uint32_t(n - 1)));
        const double h = heights[size_t(vid(x, y))];
        const Point d{double(int(b.rng.below(3)) - 1) / 8, double(int(b.rng.below(3)) - 1) / 8, -1};
        const Point origin{x - 4 * d[0], y - 4 * d[1], h + 4};
        b.addRay(origin, d, 0, tMax, b.rng.coin(0.3) ? randomRayFlags(b.rng) & ~(kSkipTriangles) : 0, 0xFF,
                 b.rng.coin(0.5) ? kModeCount : kModeClosest);
    }
    // The fan's centre along and across its axis, from both sides: one crossing.
    for (int i = 0; i < 200; ++i) {
        const bool below = b.rng.coin();
        const Point d{double(int(b.rng.below(5)) - 2) / 16, double(int(b.rng.below(5)) - 2) / 16, below ? 1.0 : -1.0};
        const Point origin{n + 4 - 2 * d[0], 2 - 2 * d[1], -2 * d[2]};
        b.addRay(origin, d, 0, tMax, 0, 0xFF, b.rng.coin(0.6) ? kModeCount : kModeClosest,
                 std::fabs(d[0]) + std::fabs(d[1]) == 0 ? 1 : -1);
    }
    b.randomRays(300, 0.4, true, false, true);
}

// AABB geometry with the procedural step, mixed with triangle BLASes under random instances.
void proceduralScene(Builder& b) {
    const uint32_t aabbBlases = 2 + b.rng.below(3), triangleBlases = 1 + b.rng.below(2);
    std::vector<int32_t> blases;
    for (uint32_t i = 0; i < aabbBlases; ++i) blases.push_back(b.aabbBlas(10, 60, 0.25, 0.0));
    for (uint32_t i = 0; i < triangleBlases; ++i) blases.push_back(b.soupBlas(10, 40, 0.3, false, false));
    b.worldExtent = 5;
    const uint32_t instanceCount = 10 + b.rng.below(30);
    for (uint32_t i = 0; i < instanceCount; ++i)
        b.addInstance(blases[b.rng.below(uint32_t(blases.size()))],
                      vt::randomTransform(b.rng, 0.5f, 2.0f, b.rng.coin(0.3), 4.0f), randomInstanceFlags(b.rng), true);
    b.randomRays(2000, 0.3, true, true, true);
}

// Inactive triangles (NaN x in each vertex position), inactive AABBs and null instances among active ones.
void inactiveScene(Builder& b) {
    std::vector<int32_t> blases;
    for (uint32_t i = 0; i < 3; ++i) {
        std::vector<Point> positions;
        std::vector<uint32_t> indices;
        randomSoup(b.rng, 40 + b.rng.below(40), 0.3, positions, indices);
        std::vector<Point> targets;
        for (size_t t = 0; t + 2 < indices.size(); t += 3) {
            if (b.rng.coin(0.2)) {
                positions[indices[t + b.rng.below(3)]][0] = NAN;  // vertex 0, 1 or 2
                continue;
            }
            Point p;
            for (int k = 0; k < 3; ++k)
                p[size_t(k)] = (positions[indices[t]][size_t(k)] + positions[indices[t + 1]][size_t(k)] +
                                positions[indices[t + 2]][size_t(k)]) / 3;
            targets.push_back(p);
        }
        TriangleOptions o = b.randomLayout(VK_FORMAT_R32G32B32_SFLOAT, uint32_t(positions.size()));
        o.indexType = VK_INDEX_TYPE_NONE_KHR;  // one vertex per corner, so a NaN makes only its own triangle inactive
        o.flags = randomGeometryFlags(b.rng);
        blases.push_back(b.addBlas({b.writer.triangles(positions, indices, o)}, 0, std::move(targets)));
    }
    for (uint32_t i = 0; i < 2; ++i) blases.push_back(b.aabbBlas(20, 64, 0.2, 0.2));
    b.worldExtent = 4;
    for (uint32_t i = 0; i < 24; ++i) {
        const bool null = b.rng.coin(0.15);
        b.addInstance(null ? -1 : blases[b.rng.below(uint32_t(blases.size()))],
                      vt::randomTransform(b.rng, 0.5f, 1.5f, false, 3.0f), 0, true);
    }
    b.randomRays(2000, 0.3, true, false, true);
}

// Empty structures: BLASes with no primitives (or only inactive ones), instances of them, null instances, and
// (variant 0) a TLAS with no instances at all.
void emptyScene(Builder& b, uint32_t variant) {
    b.worldExtent = 3;
    if (variant % 3 == 0) {
        b.randomRays(300, 0.3, true, true, true);
        return;
    }
    TriangleOptions o;
    Geometry none = b.writer.triangles({}, {}, o);
    const int32_t emptyTriangles = b.addBlas({none}, 0, {});
    const int32_t emptyAabbs = b.addBlas({b.writer.aabbs({}, {})}, 0, {});
    std::vector<Point> positions{{NAN, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const int32_t allInactive = b.addBlas({b.writer.triangles(positions, {0, 1, 2}, o)}, 0, {});
    const int32_t real = b.soupBlas(10, 30, 0.3, false, false);
    for (uint32_t i = 0; i < 16; ++i) {
        const int32_t pick[] = {emptyTriangles, emptyAabbs, allInactive, -1, variant % 3 == 2 ? real : emptyTriangles};
        b.addInstance(pick[b.rng.below(5)], vt::randomTransform(b.rng, 0.5f, 1.5f, false, 2.0f), 0, true);
    }
    b.randomRays(600, 0.3, true, false, true);
}

// Rays whose [tMin, tMax] window ends just before, at, or just after hits.
void tWindowScene(Builder& b) {
    for (uint32_t i = 0; i < 3; ++i) b.soupBlas(20, 50, 0.3, false, false);
    b.worldExtent = 4;
    for (uint32_t i = 0; i < 10; ++i)
        b.addInstance(int32_t(i % 3), vt::randomTransform(b.rng, 0.7f, 1.3f, false, 3.0f), 0, false);
    b.randomRays(2000, 0.3, false, false, true);
}

// Every vertex format lavapipe supports, indexed and non-indexed, with offsets, strides and geometry transforms.
void formatScene(Builder& b) {
    std::vector<int32_t> blases;
    for (VkFormat format : b.caps.vertexFormats) {
        std::vector<Point> positions;
        std::vector<uint32_t> indices;
        randomSoup(b.rng, 20 + b.rng.below(20), 0.35, positions, indices);
        if (oracle::formatInfo(format).packed)  // UNORM: move the soup into [0, 1]^3
            for (Point& p : positions)
                for (double& c : p) c = (c + 1) / 2;
        std::vector<Geometry> geoms;
        std::vector<Point> targets;
        for (uint32_t g = 0; g < 2; ++g) {
            TriangleOptions o = b.randomLayout(format, uint32_t(positions.size()));
            o.indexType = g == 0 ? VK_INDEX_TYPE_NONE_KHR : (b.rng.coin() ? VK_INDEX_TYPE_UINT16 : VK_INDEX_TYPE_UINT32);
            o.flags = randomGeometryFlags(b.rng);
            VkTransformMatrixKHR transform = vt::randomTransform(b.rng, 0.5f, 1.5f, b.rng.coin(0.3), 0.5f);
            if (b.rng.coin(0.5)) o.transform = &transform;
            geoms.push_back(b.writer.triangles(positions, indices, o));
            for (size_t t = 0; t + 2 < indices.size(); t += 3) {
                Point p;
                for (int k = 0; k < 3; ++k)
                    p[size_t(k)] = (positions[indices[t]][size_t(k)] + positions[indices[t + 1]][size_t(k)] +
                                    positions[indices[t + 2]][size_t(k)]) / 3;
                if (oracle::formatInfo(format).components == 2) p[2] = 0;
                targets.push_back(o.transform ? applyTransform(*o.transform, p) : p);
            }
        }
        VkBuildAccelerationStructureFlagsKHR flags = 0;
        if (b.caps.positionFetch && b.rng.coin()) flags |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
        blases.push_back(b.addBlas(std::move(geoms), flags, std::move(targets)));
    }
    b.worldExtent = 4;
    for (size_t i = 0; i < blases.size(); ++i)
        b.addInstance(blases[i], vt::randomTransform(b.rng, 0.8f, 1.2f, b.rng.coin(0.3), 4.0f), 0, true);
    b.randomRays(uint32_t(150 * blases.size()), 0.2, true, false, false);
}

// Position fetch: BLASes built with ALLOW_DATA_ACCESS, under geometry and instance transforms.
void positionFetchScene(Builder& b) {
    std::vector<int32_t> blases;
    for (uint32_t i = 0; i < 3; ++i) {
        const int32_t id = b.soupBlas(20, 50, 0.3, true, true);
        b.out.scene.blases[size_t(id)].buildFlags |=
            b.caps.positionFetch && i != 2 ? VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR : 0;
        blases.push_back(id);
    }
    b.worldExtent = 4;
    for (uint32_t i = 0; i < 15; ++i)
        b.addInstance(blases[i % 3], vt::randomTransform(b.rng, 0.5f, 2.0f, b.rng.coin(0.3), 3.0f), 0, true);
    b.randomRays(1500, 0.0, false, false, false);
}

// Degenerate triangles (collinear, repeated vertices) among real ones: never hit.
void degenerateScene(Builder& b) {
    std::vector<Point> positions;
    std::vector<uint32_t> indices;
    randomSoup(b.rng, 60, 0.3, positions, indices);
    std::vector<Point> targets;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        Point& a = positions[indices[t]];
        Point& c = positions[indices[t + 1]];
        Point& e = positions[indices[t + 2]];
        if (b.rng.coin(0.3)) {  // make it exactly degenerate: a point repeated, or exact midpoints on a line
            if (b.rng.coin()) e = c;
            else {
                a = {std::round(a[0] * 64) / 64, std::round(a[1] * 64) / 64, std::round(a[2] * 64) / 64};
                e = {a[0] + 0.25, a[1] + 0.125, a[2] - 0.25};
                c = {a[0] + 0.125, a[1] + 0.0625, a[2] - 0.125};
            }
            for (int k = 0; k < 3; ++k) targets.push_back(positions[indices[t + size_t(b.rng.below(3))]]);
            continue;
        }
        targets.push_back({(a[0] + c[0] + e[0]) / 3, (a[1] + c[1] + e[1]) / 3, (a[2] + c[2] + e[2]) / 3});
    }
    TriangleOptions o;
    o.indexType = VK_INDEX_TYPE_NONE_KHR;
    o.flags = randomGeometryFlags(b.rng);
    const int32_t blas = b.addBlas({b.writer.triangles(positions, indices, o)},
                                   b.rng.coin() ? VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR : 0,
                                   std::move(targets));
    b.worldExtent = 3;
    for (uint32_t i = 0; i < 4; ++i)
        b.addInstance(blas, vt::randomTransform(b.rng, 0.7f, 1.4f, false, 2.0f), 0, false);
    b.randomRays(1200, 0.3, false, false, false);
}

}  // namespace

const std::vector<std::string>& caseGroups() {
    static const std::vector<std::string> groups = {
        "instance_triangle_culling", "ray_flags", "watertightness", "procedural_geometry", "inactive_primitives",
        "empty_as", "tmin_tmax", "vertex_formats", "position_fetch", "degenerate_triangles"};
    return groups;
}

Case makeCase(const std::string& group, uint32_t variant, uint64_t seed, const Capabilities& caps) {
    Rng rng(seed);
    Builder b(rng, caps);
    b.out.scene.name = group + " variant " + std::to_string(variant);
    if (rng.coin(0.3)) b.out.scene.tlasFlags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
    if (group == "instance_triangle_culling") instanceScene(b);
    else if (group == "ray_flags") rayFlagScene(b);
    else if (group == "watertightness") watertightScene(b);
    else if (group == "procedural_geometry") proceduralScene(b);
    else if (group == "inactive_primitives") inactiveScene(b);
    else if (group == "empty_as") emptyScene(b, variant);
    else if (group == "tmin_tmax") tWindowScene(b);
    else if (group == "vertex_formats") formatScene(b);
    else if (group == "position_fetch") positionFetchScene(b);
    else if (group == "degenerate_triangles") degenerateScene(b);
    else throw std::invalid_argument("unknown differential group " + group);
    return std::move(b.out);
}

}  // namespace diff
