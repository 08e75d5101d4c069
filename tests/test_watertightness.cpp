// CTS `watertightness`: random tessellations of a square (recursively split at random interior points, random z)
// and closed fans. Rays aimed exactly at shared vertices, at points of shared edges and at random points must
// produce exactly one candidate (`singlehit`, non-opaque geometry, candidates counted without confirmation) and
// never miss (`nomiss`, opaque geometry, closest hit).
#include <cmath>
#include <map>

#include "meshes.h"

using namespace vt;

namespace {
struct WtParam {
    int triangles;
    bool rotated;  // instance transform: random rotation/scale (rays then reach object space through it)
};
std::string paramName(const ::testing::TestParamInfo<WtParam>& info) {
    return std::to_string(info.param.triangles) + (info.param.rotated ? "_rotated" : "_identity");
}

struct ObjectRay {
    Float3 origin, direction;
};

// The interior (shared) vertices and edge points of a mesh, plus random points, as object-space vertical rays.
std::vector<ObjectRay> watertightRays(const Mesh& m, Rng& rng, size_t maxRays, bool (*interior)(const Float3&)) {
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (size_t t = 0; t < m.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.indices[3 * t + k], b = m.indices[3 * t + (k + 1) % 3];
            ++edges[std::minmax(a, b)];
        }
    std::vector<ObjectRay> vertexRays, edgeRays, randomRays;
    std::vector<bool> used(m.positions.size(), false);
    for (uint32_t i : m.indices) used[i] = true;
    for (size_t v = 0; v < m.positions.size(); ++v)
        if (used[v] && interior(m.positions[v])) vertexRays.push_back({{m.positions[v][0], m.positions[v][1], 1.0f}, {0, 0, -1}});
    for (const auto& [e, count] : edges) {
        if (count != 2) continue;
        const Float3 &a = m.positions[e.first], &b = m.positions[e.second];
        for (float s : {0.5f, rng.uniformf(0.0f, 1.0f)})
            edgeRays.push_back({{a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), 1.0f}, {0, 0, -1}});
    }
    for (size_t i = 0; i < maxRays / 4; ++i) {
        Float3 p{rng.uniformf(0.0f, 1.0f), rng.uniformf(0.0f, 1.0f), 1.0f};
        if (interior(p)) randomRays.push_back({p, {0, 0, -1}});
    }
    std::vector<ObjectRay> out;
    for (auto* list : {&vertexRays, &edgeRays, &randomRays}) {
        std::shuffle(list->begin(), list->end(), rng.gen);
        const size_t take = std::min(list->size(), maxRays / 3 + 1);
        out.insert(out.end(), list->begin(), list->begin() + take);
    }
    return out;
}

bool insideSquare(const Float3& p) { return p[0] > 0 && p[0] < 1 && p[1] > 0 && p[1] < 1; }
}  // namespace

class watertightness : public VkasTest, public ::testing::WithParamInterface<WtParam> {
  protected:
    // Runs both variants on one mesh: every object-space ray (through the instance transform) must give exactly one
    // candidate (non-opaque) and a committed hit (opaque).
    void checkMesh(const Mesh& mesh, const std::vector<ObjectRay>& objectRays, bool rotated) {
        auto nonOpaque = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR);
        auto opaque = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        const VkTransformMatrixKHR xf = rotated ? randomTransform(rng, 0.5f, 2.0f, rng.coin(), 2.0f) : identityTransform();
        AccelStruct* tlasSingle = buildTlas({Instance{xf, 0, 0xFF, 0, 0, buildBlas(*nonOpaque)}});
        AccelStruct* tlasNoMiss = buildTlas({Instance{xf, 0, 0xFF, 0, 0, buildBlas(*opaque)}});
        size_t failures = 0;
        std::vector<oracle::Ray> worldRays;
        for (const ObjectRay& r : objectRays) {
            oracle::Ray w;
            w.origin = transformPoint(xf, r.origin);
            const Float3 end = transformPoint(xf, {r.origin[0] + r.direction[0], r.origin[1] + r.direction[1],
                                                   r.origin[2] + r.direction[2]});
            w.direction = rotated ? Float3{end[0] - w.origin[0], end[1] - w.origin[1], end[2] - w.origin[2]} : r.direction;
            w.tMin = 0;
            w.tMax = 100;
            worldRays.push_back(w);
            // singlehit
            const QueryTrace tr = query(tlasSingle->handle, w, 0, 0xFF, Confirm::None);
            if (tr.candidates.size() != 1 && ++failures <= 10) {
                std::string list;
                for (const auto& c : tr.candidates) list += "\n    " + c.str();
                ADD_FAILURE() << "singlehit: " << tr.candidates.size() << " candidates for " << describe(w)
                              << " (object-space origin " << r.origin[0] << " " << r.origin[1] << ")" << list << "\n  seed " << seed;
            }
            if (!tr.problems.empty() && ++failures <= 10) ADD_FAILURE() << tr.problems;
            if (tr.committed.type != VKAS_COMMITTED_INTERSECTION_NONE && ++failures <= 10)
                ADD_FAILURE() << "nothing was confirmed, yet the committed type is " << tr.committed.type;
            // nomiss
            const Hit h = traceClosest(tlasNoMiss, w);
            if (h.type != VKAS_COMMITTED_INTERSECTION_TRIANGLE && ++failures <= 10)
                ADD_FAILURE() << "nomiss: the ray missed " << describe(w) << "\n  seed " << seed;
        }
        if (failures > 10) ADD_FAILURE() << failures << " failures in total, seed " << seed;
        // The oracle agrees on a sample (it treats edge rays as optional, so this checks hit values elsewhere).
        worldRays.resize(std::min<size_t>(worldRays.size(), 200));
        checkRays(tlasNoMiss, worldRays);
    }
};

TEST_P(watertightness, random_tessellation) {
    const Mesh mesh = randomSquareTessellation(GetParam().triangles, rng);
    checkMesh(mesh, watertightRays(mesh, rng, 3000, insideSquare), GetParam().rotated);
}

TEST_P(watertightness, closed_fan) {
    for (int round = 0; round < 8; ++round) {
        const int n = 4 + int(rng.below(13));
        const Mesh fan = closedFan(n, rng);
        std::vector<ObjectRay> rays;
        const Float3 c = fan.positions[0];
        // Largest slope of the fan (as a height field): tilting a ray by less than 1/slope keeps one crossing.
        double slope = 1e-3;
        for (size_t t = 0; t < fan.triangleCount(); ++t) {
            const Float3 &p0 = fan.positions[fan.indices[3 * t]], &p1 = fan.positions[fan.indices[3 * t + 1]],
                         &p2 = fan.positions[fan.indices[3 * t + 2]];
            const double ax = p1[0] - p0[0], ay = p1[1] - p0[1], az = p1[2] - p0[2];
            const double bx = p2[0] - p0[0], by = p2[1] - p0[1], bz = p2[2] - p0[2];
            const double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
            slope = std::max(slope, std::sqrt(nx * nx + ny * ny) / std::fabs(nz));
        }
        const float tilt = float(std::min(0.3, 0.4 / slope));
        for (int i = 0; i < 64; ++i) {
            // At the shared vertex from tilted directions (the fan stays a single sheet along them).
            const Float3 d{rng.uniformf(-tilt, tilt) * 0.7f, rng.uniformf(-tilt, tilt) * 0.7f, -1.0f};
            rays.push_back({{c[0] - 2 * d[0], c[1] - 2 * d[1], c[2] - 2 * d[2]}, d});
            // At a point of a spoke (shared edge).
            const Float3& p = fan.positions[1 + rng.below(uint32_t(n))];
            const float s = i % 2 ? 0.5f : rng.uniformf(0.05f, 0.95f);
            const Float3 e{c[0] + s * (p[0] - c[0]), c[1] + s * (p[1] - c[1]), c[2] + s * (p[2] - c[2])};
            rays.push_back({{e[0] - 2 * d[0], e[1] - 2 * d[1], e[2] - 2 * d[2]}, d});
        }
        checkMesh(fan, rays, GetParam().rotated);
        if (HasFailure()) return;
    }
}

INSTANTIATE_TEST_SUITE_P(cpu_built, watertightness,
                         ::testing::Values(WtParam{8, false}, WtParam{16, false}, WtParam{256, false},
                                           WtParam{1024, false}, WtParam{16384, false}, WtParam{16, true},
                                           WtParam{256, true}, WtParam{4096, true}),
                         paramName);
