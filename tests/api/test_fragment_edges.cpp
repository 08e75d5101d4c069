// PREFER_FAST_TRACE's fragments (spatial splits, docs/FORMAT.md "Fragments") where bugs live: rays through every
// vertex, every edge midpoint and random edge points of meshes whose triangles the builder cut, under the identity
// and under rotated, scaled (and mirrored) instances.
//
// The meshes are graphs over the unit square (a vertical line through its interior crosses them once), made the way
// that found issue 35's defect: a height field split at random interior points (slivers and high-valence vertices
// appear by themselves), strips of long thin triangles, and a fan around one vertex of high valence.
//
// The oracle is the same mesh built with no preference: which triangles a ray meets is decided by the watertight test
// on the same vertices and the same object-space ray, whatever the tree, so the fragmented structure must show
// exactly the same candidates (bit for bit), each triangle once (with NO_DUPLICATE_ANY_HIT_INVOCATION: exactly one
// candidate per triangle; without it: never none), and commit exactly the same hits. A ray through a target inside
// the mesh meets at least one triangle (the watertight test leaves no gap along a shared edge or at a vertex).
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include "meshes.hpp"
#include "vkas_test.hpp"

namespace vt {
namespace {

constexpr uint32_t kRayNoOpaque = 0x2;  // SPIR-V RayFlagsNoOpaqueKHR

Mesh readObj(const std::string& path) {
    Mesh m;
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            Float3 p;
            s >> p[0] >> p[1] >> p[2];
            m.positions.push_back(p);
        } else if (tag == "f") {
            for (int k = 0; k < 3; ++k) {
                uint32_t i;
                s >> i;
                m.indices.push_back(i - 1);
            }
        }
    }
    return m;
}

// A smooth height over the plane.
float height(double x, double y) {
    return float(0.12 * std::sin(3.1 * x + 0.4) + 0.09 * std::cos(4.3 * y - 0.2) - 0.05 * x * y);
}

// Each mesh is a graph over a square: the unit square in (u, v), turned by `angle` about its centre in (x, y), so
// that long thin triangles lie across the axes (their boxes are large, the builder cuts them).
struct Domain {
    double angle = 0;

    Float3 at(double u, double v) const {
        const double c = std::cos(angle), s = std::sin(angle);
        const double x = 0.5 + c * (u - 0.5) - s * (v - 0.5), y = 0.5 + s * (u - 0.5) + c * (v - 0.5);
        return {float(x), float(y), height(x, y)};
    }
    // How far (x, y) lies inside the square, in (u, v) units (negative outside).
    double inside(const Float3& p) const {
        const double c = std::cos(angle), s = std::sin(angle);
        const double u = 0.5 + c * (p[0] - 0.5) + s * (p[1] - 0.5), v = 0.5 - s * (p[0] - 0.5) + c * (p[1] - 0.5);
        return std::min(std::min(u, 1 - u), std::min(v, 1 - v));
    }
};

// Splits a random triangle of `m` at a random interior point into three, `splits` times (a third of the points lie
// within 1e-3 to 1e-6 of an edge, in barycentric terms: slivers). The graph stays a graph over the domain.
void splitAtRandomInteriorPoints(Mesh& m, int splits, Rng& rng) {
    for (int s = 0; s < splits; ++s) {
        const size_t t = rng.below(uint32_t(m.triangleCount()));
        const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        double w[3] = {rng.uniform(0.05, 1), rng.uniform(0.05, 1), rng.uniform(0.05, 1)};
        if (s % 3 == 0) w[rng.below(3)] = std::pow(10.0, rng.uniform(-6, -3)) * (w[0] + w[1] + w[2]);
        const double sum = w[0] + w[1] + w[2];
        const double x = (w[0] * m.positions[a][0] + w[1] * m.positions[b][0] + w[2] * m.positions[c][0]) / sum;
        const double y = (w[0] * m.positions[a][1] + w[1] * m.positions[b][1] + w[2] * m.positions[c][1]) / sum;
        const uint32_t p = uint32_t(m.positions.size());
        m.positions.push_back({float(x), float(y), height(float(x), float(y))});
        m.indices[3 * t + 2] = p;  // (a, b, p), then (b, c, p) and (c, a, p): the winding is kept
        m.indices.insert(m.indices.end(), {b, c, p, c, a, p});
    }
}

// The unit square's two triangles, split `splits` times.
Mesh splitHeightField(int splits, Rng& rng) {
    const Domain d;
    Mesh m;
    m.positions = {d.at(0, 0), d.at(1, 0), d.at(1, 1), d.at(0, 1)};
    m.indices = {0, 1, 2, 0, 2, 3};
    splitAtRandomInteriorPoints(m, splits, rng);
    return m;
}

// Bands of long thin triangles: lines across the square, line r with pointsPerLine[r] random points between its
// ends, and each band between two lines zipped into triangles spanning the band (a line of few points beside one of
// many makes fans of long slivers).
Mesh thinStrips(const std::vector<int>& pointsPerLine, const Domain& d, Rng& rng) {
    Mesh m;
    const int rows = int(pointsPerLine.size()) - 1;
    std::vector<std::vector<uint32_t>> lines(rows + 1);
    std::vector<std::vector<float>> us(rows + 1);
    for (int r = 0; r <= rows; ++r) {
        us[r] = {0.0f, 1.0f};
        for (int i = 0; i < pointsPerLine[r]; ++i) us[r].push_back(rng.uniformf(0.001f, 0.999f));
        std::sort(us[r].begin(), us[r].end());
        us[r].erase(std::unique(us[r].begin(), us[r].end()), us[r].end());
        for (const float u : us[r]) {
            lines[r].push_back(uint32_t(m.positions.size()));
            m.positions.push_back(d.at(u, double(r) / rows));
        }
    }
    for (int r = 0; r < rows; ++r) {
        const auto &lo = lines[r], &hi = lines[r + 1];
        const auto &ulo = us[r], &uhi = us[r + 1];
        size_t i = 0, j = 0;
        while (i + 1 < lo.size() || j + 1 < hi.size()) {
            const bool advanceLow = j + 1 == hi.size() || (i + 1 < lo.size() && ulo[i + 1] < uhi[j + 1]);
            if (advanceLow) {
                m.indices.insert(m.indices.end(), {lo[i], lo[i + 1], hi[j]});
                ++i;
            } else {
                m.indices.insert(m.indices.end(), {lo[i], hi[j + 1], hi[j]});
                ++j;
            }
        }
    }
    return m;
}

// A fan of `n` long thin triangles around a random interior point, to `n` points along the square's boundary (the
// corners among them).
Mesh highValenceFan(int n, const Domain& d, Rng& rng) {
    Mesh m;
    m.positions.push_back(d.at(rng.uniform(0.3, 0.7), rng.uniform(0.3, 0.7)));
    std::vector<double> ts;  // positions along the boundary, 0..4 counter-clockwise from (0, 0)
    for (int k = 0; k < 4; ++k) ts.push_back(k);
    for (int i = 4; i < n; ++i) ts.push_back(rng.uniform(0, 4));
    std::sort(ts.begin(), ts.end());
    for (const double t : ts) {
        const int side = int(t);
        const double f = t - side;
        const double u = side == 0 ? f : side == 1 ? 1.0 : side == 2 ? 1.0 - f : 0.0;
        const double v = side == 0 ? 0.0 : side == 1 ? f : side == 2 ? 1.0 : 1.0 - f;
        m.positions.push_back(d.at(u, v));
    }
    for (uint32_t i = 0; i < uint32_t(ts.size()); ++i)
        m.indices.insert(m.indices.end(), {0, 1 + i, 1 + (i + 1) % uint32_t(ts.size())});
    return m;
}

// Object-space targets: every vertex, every edge's midpoint, `edgePoints` random points of random edges, `interior`
// random points inside random triangles; of these, the ones at least `margin` inside the domain (a ray through the
// mesh's outer boundary may rightly miss it once an instance transform has rounded it).
std::vector<Float3> targets(const Mesh& m, const Domain& d, double margin, Rng& rng, size_t edgePoints,
                            size_t interior) {
    std::vector<Float3> out;
    for (const Float3& p : m.positions) out.push_back(p);
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (size_t t = 0; t < m.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.indices[3 * t + k], b = m.indices[3 * t + (k + 1) % 3];
            edges.insert({std::min(a, b), std::max(a, b)});
        }
    const std::vector<std::pair<uint32_t, uint32_t>> edgeList(edges.begin(), edges.end());
    auto along = [&](const std::pair<uint32_t, uint32_t>& e, float s) {
        const Float3 &a = m.positions[e.first], &b = m.positions[e.second];
        return Float3{a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])};
    };
    for (const auto& e : edgeList) out.push_back(along(e, 0.5f));
    for (size_t i = 0; i < edgePoints; ++i)
        out.push_back(along(edgeList[rng.below(uint32_t(edgeList.size()))], rng.uniformf(0, 1)));
    for (size_t i = 0; i < interior; ++i) {
        const size_t t = rng.below(uint32_t(m.triangleCount()));
        float b = rng.uniformf(0, 1), c = rng.uniformf(0, 1);
        if (b + c > 1) b = 1 - b, c = 1 - c;
        const Float3 &p0 = m.positions[m.indices[3 * t]], &p1 = m.positions[m.indices[3 * t + 1]],
                     &p2 = m.positions[m.indices[3 * t + 2]];
        Float3 p;
        for (int a = 0; a < 3; ++a) p[a] = p0[a] + b * (p1[a] - p0[a]) + c * (p2[a] - p0[a]);
        out.push_back(p);
    }
    std::vector<Float3> kept;
    for (const Float3& p : out)
        if (d.inside(p) >= margin) kept.push_back(p);
    return kept;
}

// How far (in object units) rounding a world-space ray can move it for the instance `m` (a rotation times a scale
// along each axis): a few ulps of the world coordinates' magnitude, divided by the smallest scale.
double objectRoundoff(const VkTransformMatrixKHR& m) {
    double reach = 0, largest = 0, smallest = HUGE_VAL;
    for (int c = 0; c < 3; ++c) {
        double norm = 0;
        for (int r = 0; r < 3; ++r) norm += double(m.matrix[r][c]) * m.matrix[r][c];
        largest = std::max(largest, std::sqrt(norm));
        smallest = std::min(smallest, std::sqrt(norm));
    }
    for (int r = 0; r < 3; ++r) reach = std::max(reach, std::fabs(double(m.matrix[r][3])));
    return 64 * 0x1p-24 * (reach + 4 * largest) / smallest;
}

// World rays that are vertical in object space (down from above, or up from below) through each target.
std::vector<oracle::Ray> raysThrough(const std::vector<Float3>& objectTargets, const VkTransformMatrixKHR& m,
                                     Rng& rng) {
    double up[3];
    for (int i = 0; i < 3; ++i) up[i] = m.matrix[i][2];  // the object's +z in world space
    std::vector<oracle::Ray> rays;
    for (const Float3& target : objectTargets) {
        const Float3 q = transformPoint(m, target);
        const double side = rng.coin(0.75) ? 1.0 : -1.0;
        oracle::Ray r;
        for (int i = 0; i < 3; ++i) {
            r.origin[i] = float(q[i] + side * 2.0 * up[i]);
            r.direction[i] = float(-side * up[i]);
        }
        r.tMin = 0.0f;
        r.tMax = 1e4f;
        rays.push_back(r);
    }
    return rays;
}

std::set<std::tuple<int32_t, int32_t, uint32_t>> candidateSet(const QueryTrace& q) {
    std::set<std::tuple<int32_t, int32_t, uint32_t>> s;
    for (const Hit& h : q.candidates) {
        uint32_t bits;
        std::memcpy(&bits, &h.t, 4);
        s.insert({h.geometryIndex, h.primitiveIndex, bits});
    }
    return s;
}

// Where the object-space ray of candidate `h` crosses the plane of its triangle in `m`, in long double.
long double crossingT(const Mesh& m, const Hit& h) {
    long double r[3][3], w[3];
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a)
            r[k][a] = (long double)m.positions[m.indices[3 * h.primitiveIndex + k]][a] - h.objectOrigin[a];
    for (int k = 0; k < 3; ++k) {
        const long double* u = r[(k + 1) % 3];
        const long double* v = r[(k + 2) % 3];
        w[k] = h.objectDirection[0] * (u[1] * v[2] - u[2] * v[1]) + h.objectDirection[1] * (u[2] * v[0] - u[0] * v[2]) +
               h.objectDirection[2] * (u[0] * v[1] - u[1] * v[0]);
    }
    long double dd = 0, t = 0;
    for (int a = 0; a < 3; ++a) {
        const long double p = (w[0] * r[0][a] + w[1] * r[1][a] + w[2] * r[2][a]) / (w[0] + w[1] + w[2]);
        t += p * h.objectDirection[a];
        dd += (long double)h.objectDirection[a] * h.objectDirection[a];
    }
    return t / dd;
}

const Hit* findCandidate(const std::vector<Hit>& candidates, const Hit& h) {
    for (const Hit& c : candidates)
        if (c.geometryIndex == h.geometryIndex && c.primitiveIndex == h.primitiveIndex &&
            std::memcmp(&c.t, &h.t, 4) == 0 && std::memcmp(c.bary, h.bary, 8) == 0 && c.frontFace == h.frontFace)
            return &c;
    return nullptr;
}

// Whether the fragmented structure's committed hit `h` agrees with the control's, `controlCandidates` being every
// triangle the control shows the ray (with their object-space rays):
// - the same hit, bit for bit;
// - or, where several triangles meet the ray at the same t (a shared vertex or edge; which commits first depends
//   on the tree's order), the same t on another of them;
// - or the control's hit is an artifact of the float test: a triangle all but edge-on to the ray (a sliver of a
//   fold), whose float t lies before the point where the ray really crosses it. A fragment's box bounds the part
//   of the triangle in its region, not that t, so a hit committed in between may cull the box before the fragment
//   is tested (docs/FORMAT.md, "Fragments"); the fragmented structure must then still commit one of the ray's
//   candidates, which can only lie farther.
bool agreesWithControl(const Mesh& m, const Hit& h, const Hit& control, const std::vector<Hit>& controlCandidates,
                       size_t& artifacts) {
    if (identical(h, control)) return true;
    if (h.type != control.type || !findCandidate(controlCandidates, h)) return false;
    if (std::memcmp(&h.t, &control.t, 4) == 0) return true;
    const Hit* c = findCandidate(controlCandidates, control);
    if (!c) return false;
    const long double crossing = crossingT(m, *c);
    if (!((long double)control.t < crossing * (1 - 1e-12L) && h.t > control.t)) return false;
    ++artifacts;
    return true;
}

class fragment_edges : public VkasTest {
protected:
    static uint32_t fragmentCount(const AccelStruct* as) { return as->header32(128); }

    std::vector<Hit> batch(const AccelStruct* tlas, VkasTraceMode mode, const std::vector<oracle::Ray>& rays) {
        std::vector<VkasRay> in(rays.size());
        for (size_t i = 0; i < rays.size(); ++i) {
            std::memcpy(in[i].origin, rays[i].origin.data(), 12);
            std::memcpy(in[i].direction, rays[i].direction.data(), 12);
            in[i].tMin = rays[i].tMin;
            in[i].tMax = rays[i].tMax;
        }
        std::vector<VkasHit> out(rays.size());
        EXPECT_EQ(vkasTraceRays(device, tlas->handle, mode, 0, 0xFF, uint32_t(in.size()), in.data(), out.data()),
                  VK_SUCCESS);
        std::vector<Hit> hits;
        for (const VkasHit& h : out) hits.push_back(fromBatch(h));
        return hits;
    }

    // Builds `mesh` with no preference (the control) and with PREFER_FAST_TRACE, each under every instance transform,
    // and checks every ray path against the control. Returns the rays checked.
    size_t check(const Mesh& mesh, const Domain& domain, const char* name) {
        const std::vector<VkTransformMatrixKHR> transforms = {
            identityTransform(), randomTransform(rng, 0.3f, 4.0f, false, 20.0f),
            randomTransform(rng, 0.05f, 100.0f, true, 200.0f)};
        std::vector<std::vector<Float3>> objectTargets;
        for (const VkTransformMatrixKHR& t : transforms)
            objectTargets.push_back(targets(mesh, domain, std::max(1e-6, objectRoundoff(t)), rng, 1000, 300));
        size_t checked = 0, artifacts = 0;
        struct Setting {
            VkGeometryFlagsKHR geometryFlags;
            uint32_t rayFlags;  // of the queries; the batch runs with none
        };
        for (const Setting s : {Setting{VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR, 0}, Setting{0, 0},
                                Setting{VK_GEOMETRY_OPAQUE_BIT_KHR, 0}, Setting{VK_GEOMETRY_OPAQUE_BIT_KHR, kRayNoOpaque}}) {
            auto g = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, s.geometryFlags);
            AccelStruct* control = buildBlas(*g);
            BuildOptions fast;
            fast.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
            AccelStruct* cut = buildBlas(*g, fast);
            EXPECT_GT(fragmentCount(cut), 0u) << name << ": no triangle was cut, the test would prove nothing";
            const bool showsCandidates = !(s.geometryFlags & VK_GEOMETRY_OPAQUE_BIT_KHR) || (s.rayFlags & kRayNoOpaque);
            for (size_t ti = 0; ti < transforms.size(); ++ti) {
                Instance ic, ix;
                ic.transform = ix.transform = transforms[ti];
                ic.blas = control;
                ix.blas = cut;
                AccelStruct* tlasControl = buildTlas({ic});
                AccelStruct* tlasCut = buildTlas({ix});
                const std::vector<oracle::Ray> rays = raysThrough(objectTargets[ti], transforms[ti], rng);
                const std::vector<Hit> closest = batch(tlasCut, VKAS_TRACE_MODE_CLOSEST_HIT, rays);
                const std::vector<Hit> closestControl = batch(tlasControl, VKAS_TRACE_MODE_CLOSEST_HIT, rays);
                const std::vector<Hit> any = batch(tlasCut, VKAS_TRACE_MODE_ANY_HIT, rays);
                for (size_t i = 0; i < rays.size(); ++i) {
                    const std::string where = std::string(name) + " transform " + std::to_string(ti) + " flags " +
                                              std::to_string(s.geometryFlags) + "/" + std::to_string(s.rayFlags) +
                                              " ray " + std::to_string(i) + " " + describe(rays[i]);
                    const QueryTrace qc = query(tlasControl->handle, rays[i], s.rayFlags, 0xFF, Confirm::None);
                    const QueryTrace qx = query(tlasCut->handle, rays[i], s.rayFlags, 0xFF, Confirm::None);
                    EXPECT_TRUE(qx.problems.empty()) << where << ": " << qx.problems;
                    const auto expected = candidateSet(qc), got = candidateSet(qx);
                    const std::vector<Hit> ties =
                        query(tlasControl->handle, rays[i], kRayNoOpaque, 0xFF, Confirm::None).candidates;
                    if (showsCandidates) {
                        EXPECT_GE(expected.size(), 1u) << where << ": the control shows no candidate";
                        EXPECT_EQ(got.size(), qx.candidates.size()) << where << ": a triangle shown twice";
                        EXPECT_EQ(got, expected) << where << ": " << got.size() << " candidates, the control "
                                                 << expected.size();
                    } else {
                        EXPECT_TRUE(qx.candidates.empty()) << where;
                        EXPECT_TRUE(agreesWithControl(mesh, qx.committed, qc.committed, ties, artifacts))
                            << where << ": committed " << qx.committed.str() << ", the control " << qc.committed.str();
                        EXPECT_NE(qc.committed.type, uint32_t(VKAS_COMMITTED_INTERSECTION_NONE)) << where;
                    }
                    EXPECT_TRUE(agreesWithControl(mesh, closest[i], closestControl[i], ties, artifacts))
                        << where << ": closest " << closest[i].str() << ", the control " << closestControl[i].str();
                    EXPECT_NE(closestControl[i].type, uint32_t(VKAS_COMMITTED_INTERSECTION_NONE)) << where;
                    EXPECT_NE(any[i].type, uint32_t(VKAS_COMMITTED_INTERSECTION_NONE)) << where << ": any hit missed";
                    ++checked;
                    if (HasFailure()) return checked;  // one ray's story is enough
                }
            }
        }
        std::cout << artifacts << " committed hits of the control were float-t artifacts (see agreesWithControl)"
                  << std::endl;
        return checked;
    }
};

TEST_F(fragment_edges, height_fields_split_at_random_interior_points) {
    const size_t n = check(splitHeightField(1023, rng), Domain{}, "split height field");
    std::cout << n << " rays checked" << std::endl;
}

TEST_F(fragment_edges, strips_of_long_thin_triangles) {
    Mesh strips = thinStrips({300, 0, 300, 5, 300, 0, 300}, Domain{0.7}, rng);
    splitAtRandomInteriorPoints(strips, 300, rng);  // small triangles beside the long ones: the builder cuts these
    const size_t n = check(strips, Domain{0.7}, "thin strips");
    std::cout << n << " rays checked" << std::endl;
}

TEST_F(fragment_edges, a_vertex_of_high_valence) {
    Mesh fan = highValenceFan(300, Domain{0.7}, rng);
    splitAtRandomInteriorPoints(fan, 1000, rng);  // small triangles beside the long ones: the builder cuts these
    const size_t n = check(fan, Domain{0.7}, "fan");
    std::cout << n << " rays checked" << std::endl;
}

#ifdef VKAS_TEST_DATA_DIR
// Issue 35's reproducer (shared/repro/fast-trace-missed-candidate.obj, copied to tests/data): a sliver of a split
// height field whose float barycentrics put the hit point 0.02 from the ray, in a fragment the ray never visits.
TEST_F(fragment_edges, the_reproducer_of_issue_35_shows_its_one_candidate) {
    const Mesh mesh = readObj(std::string(VKAS_TEST_DATA_DIR) + "/fast_trace_missed_candidate.obj");
    ASSERT_EQ(mesh.triangleCount(), 2048u);
    auto g = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
    AccelStruct* blas = buildBlas(*g, opt);
    ASSERT_GT(fragmentCount(blas), 0u);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    oracle::Ray ray;
    ray.origin = {0x1.04760ap-1f, 0x1.134d64p-1f, 1.0f};
    ray.direction = {0, 0, -1};
    ray.tMin = 0;
    ray.tMax = 1000;
    const QueryTrace q = query(tlas->handle, ray, 0, 0xFF, Confirm::None);
    ASSERT_EQ(q.candidates.size(), 1u);
    EXPECT_EQ(q.candidates[0].primitiveIndex, 78);
    EXPECT_EQ(q.candidates[0].t, 0x1.1e6dfp+0f);
    // And the whole file, as the check above does it.
    const size_t n = check(mesh, Domain{}, "reproducer");
    std::cout << n << " rays checked" << std::endl;
}
#endif

}  // namespace
}  // namespace vt
