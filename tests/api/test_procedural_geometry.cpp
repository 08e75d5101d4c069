// CTS `ray_query.procedural_geometry` (object_behind_bounding_boxes, triangle_in_between) and the AABB cases of
// `ray_query.builtin`: AABB geometries (VK_GEOMETRY_TYPE_AABBS_KHR) built from VkAabbPositionsKHR with any stride
// and primitiveOffset, AABB candidates from Proceed (ids, object ray, CandidateAABBOpaque), GenerateIntersection
// and its rule 06353, inactive (minX NaN) boxes among active ones, opacity, culling and Skip flags, termination,
// mixed top-level structures, vkasTraceRays (no intersection shader: AABBs never hit) and the build's valid usage
// for AABBs. Random scenes are checked against the brute-force oracle; every test prints its seed.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <tuple>

#include "meshes.hpp"

using namespace vt;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

VkAabbPositionsKHR box(float x0, float y0, float z0, float x1, float y1, float z1) { return {x0, y0, z0, x1, y1, z1}; }

// An inactive box: minX is NaN (of several kinds); the other fields are garbage that covers everything, so a
// builder that looked at them would be caught.
VkAabbPositionsKHR inactiveBox(Rng& rng) {
    VkAabbPositionsKHR b = box(0, -1e30f, -1e30f, 1e30f, 1e30f, 1e30f);
    const uint32_t kinds[3] = {0x7FC00000u, 0xFFC00001u, 0x7F800001u};  // quiet, negative, signalling
    const uint32_t bits = kinds[rng.below(3)];
    std::memcpy(&b.minX, &bits, 4);
    return b;
}

// Random boxes in [-1, 1]^3 with extents up to `size`; some flat on one axis, a few points.
std::vector<VkAabbPositionsKHR> aabbSoup(int count, Rng& rng, float size, double inactiveFraction = 0.0) {
    std::vector<VkAabbPositionsKHR> out;
    for (int i = 0; i < count; ++i) {
        if (rng.coin(inactiveFraction)) {
            out.push_back(inactiveBox(rng));
            continue;
        }
        float c[3], e[3];
        for (int k = 0; k < 3; ++k) c[k] = rng.uniformf(-1, 1), e[k] = size * rng.uniformf(0.05f, 1.0f);
        const uint32_t shape = rng.below(100);
        if (shape < 8) e[rng.below(3)] = 0;  // flat
        if (shape >= 98) e[0] = e[1] = e[2] = 0;  // a point
        out.push_back(box(c[0] - e[0], c[1] - e[1], c[2] - e[2], c[0] + e[0], c[1] + e[1], c[2] + e[2]));
    }
    return out;
}

// Where the boxes lie in the application's buffer.
struct AabbLayout {
    uint32_t stride = sizeof(VkAabbPositionsKHR);  // multiple of 8; 0 repeats one box
    uint32_t primitiveOffset = 0;                  // multiple of 8
    uint32_t misalign = 0;                         // bytes between the allocation and data.hostAddress
};

// Owns the memory an AABB geometry points to. Bytes between boxes are poisoned.
struct AabbData {
    std::vector<uint8_t> bytes;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
};

std::unique_ptr<AabbData> makeAabbs(const std::vector<VkAabbPositionsKHR>& boxes, VkGeometryFlagsKHR flags = 0,
                                    const AabbLayout& layout = {}) {
    auto d = std::make_unique<AabbData>();
    const size_t n = boxes.size();
    const size_t base = layout.misalign + layout.primitiveOffset;
    d->bytes.assign(base + (n ? uint64_t(layout.stride) * (n - 1) + sizeof(VkAabbPositionsKHR) : 1), 0xAB);
    for (size_t i = 0; i < n; ++i)
        std::memcpy(d->bytes.data() + base + uint64_t(layout.stride) * i, &boxes[i], sizeof boxes[i]);
    d->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    d->geometry.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    d->geometry.flags = flags;
    auto& a = d->geometry.geometry.aabbs;
    a.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    a.data.hostAddress = d->bytes.data() + layout.misalign;
    a.stride = layout.stride;
    d->range.primitiveCount = uint32_t(n);
    d->range.primitiveOffset = layout.primitiveOffset;
    return d;
}

oracle::Ray makeRay(std::array<float, 3> o, std::array<float, 3> d, float tMin = 0, float tMax = 100) {
    oracle::Ray r;
    r.origin = o;
    r.direction = d;
    r.tMin = tMin;
    r.tMax = tMax;
    return r;
}

bool hasVuid(const std::vector<std::string>& errors, const std::string& vuid) {
    for (const auto& e : errors)
        if (e.compare(0, vuid.size() + 1, vuid + ":") == 0) return true;
    return false;
}
std::string joined(const std::vector<std::string>& errors) {
    std::string s;
    for (const auto& e : errors) s += "\n  " + e;
    return s.empty() ? " (none)" : s;
}

double maxAbs3(const double* v) { return std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])}); }

constexpr uint32_t kOpacityFlags[5] = {0, VKAS_RAY_FLAG_OPAQUE, VKAS_RAY_FLAG_NO_OPAQUE, VKAS_RAY_FLAG_CULL_OPAQUE,
                                       VKAS_RAY_FLAG_CULL_NO_OPAQUE};
const char* kOpacityNames[5] = {"none", "opaque", "noopaque", "cullopaque", "cullnoopaque"};
constexpr uint32_t kInstanceOpacity[3] = {0, VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                          VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR};
const char* kInstanceOpacityNames[3] = {"noforce", "forceopaque", "forcenoopaque"};

}  // namespace

class procedural_geometry : public VkasTest {
  protected:
    AabbData* addAabbs(const std::vector<VkAabbPositionsKHR>& boxes, VkGeometryFlagsKHR flags = 0,
                       const AabbLayout& layout = {}) {
        aabbs_.push_back(makeAabbs(boxes, flags, layout));
        return aabbs_.back().get();
    }
    GeometryData* addTriangles(const Mesh& mesh, VkGeometryFlagsKHR flags = 0) {
        triangles_.push_back(makeGeometry(mesh, VK_INDEX_TYPE_UINT32, flags));
        return triangles_.back().get();
    }
    AccelStruct* buildAabbBlas(const std::vector<const AabbData*>& data, const BuildOptions& opt = {}) {
        std::vector<VkAccelerationStructureGeometryKHR> g;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
        for (const AabbData* d : data) g.push_back(d->geometry), r.push_back(d->range);
        return buildBlas(g, r, opt);
    }
    AccelStruct* buildAabbBlas(const AabbData* data, const BuildOptions& opt = {}) {
        return buildAabbBlas(std::vector<const AabbData*>{data}, opt);
    }

    // Runs each ray without generating anything and checks the AABB candidates against the oracle: each reported
    // one is an oracle candidate with the oracle's opacity and object ray, reported once; every required oracle
    // AABB that the ray enters before the final committed t (opaque triangles still commit) was reported.
    void checkCandidateSets(const AccelStruct* tlas, const std::vector<oracle::Ray>& rays, uint32_t flags,
                            uint32_t cullMask = 0xFF) {
        size_t failures = 0;
        size_t reported = 0;
        for (const auto& ray : rays) {
            const oracle::Result ex = oracle::trace(*tlas->scene, ray, flags, cullMask);
            std::ostringstream why;
            std::set<std::tuple<int32_t, int32_t, int32_t>> seen;
            VkasRayQuery q;
            vkasRayQueryInitialize(&q, tlas->handle, flags, cullMask, ray.origin.data(), ray.tMin, ray.direction.data(),
                                   ray.tMax);
            while (vkasRayQueryProceed(&q)) {
                const Hit c = readHit(q, false);
                if (c.type != VKAS_CANDIDATE_INTERSECTION_AABB) continue;  // triangles: not confirmed
                ++reported;
                if (!seen.insert({c.instanceId, c.geometryIndex, c.primitiveIndex}).second)
                    why << "AABB " << c.str() << " reported twice; ";
                const oracle::Candidate* oc = ex.find(c.instanceId, c.geometryIndex, c.primitiveIndex);
                if (!oc || !oc->aabb) {
                    why << "AABB " << c.str() << " is not an oracle candidate; ";
                    continue;
                }
                if (c.aabbOpaque != oc->opaque) why << "CandidateAABBOpaque of " << c.str() << " differs; ";
                if (!(std::fabs(c.t - oc->t) <= 1e-4 * std::fabs(oc->t) + 10 * oc->tTolerance + 1e-6))
                    why << "candidate T " << c.t << " of " << c.str() << " is not the entry point " << oc->t << "; ";
                float oo[3], od[3];
                vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, oo);
                vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, od);
                const double worldOrigin[3] = {ray.origin[0], ray.origin[1], ray.origin[2]};
                const double otol = 1e-5 * (maxAbs3(oc->objectOrigin) + maxAbs3(worldOrigin) + 1.0);
                const double dtol = 1e-5 * (maxAbs3(oc->objectDirection) + 1e-3);
                for (int k = 0; k < 3; ++k)
                    if (!(std::fabs(oo[k] - oc->objectOrigin[k]) <= otol && std::fabs(od[k] - oc->objectDirection[k]) <= dtol)) {
                        why << "object ray of " << c.str() << " differs from the oracle's; ";
                        break;
                    }
            }
            const bool hasCommitted = vkasRayQueryGetIntersectionType(&q, VK_TRUE) != VKAS_COMMITTED_INTERSECTION_NONE;
            const double end = hasCommitted ? vkasRayQueryGetIntersectionT(&q, VK_TRUE) : ray.tMax;
            // An opaque triangle with TerminateOnFirstHit may end traversal before nearer boxes were visited.
            const bool complete = !(hasCommitted && (flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT));
            for (const oracle::Candidate& oc : ex.candidates)
                if (complete && oc.aabb && !oc.optional && oc.t + oc.tTolerance < end &&
                    !seen.count({oc.instanceId, oc.geometryIndex, oc.primitiveIndex}))
                    why << "required AABB inst " << oc.instanceId << " geom " << oc.geometryIndex << " prim "
                        << oc.primitiveIndex << " (t " << oc.t << ") was not reported; ";
            if (!why.str().empty() && ++failures <= 10)
                ADD_FAILURE() << "flags 0x" << std::hex << flags << std::dec << " ray " << describe(ray) << "\n  "
                              << why.str() << "\n  seed " << seed;
        }
        if (failures > 10) ADD_FAILURE() << failures << " rays failed in total, seed " << seed;
        RecordProperty("aabb_candidates", std::to_string(reported));
    }

    // An instance of a BLAS of random boxes, several geometries with different layouts.
    AccelStruct* randomAabbBlas(int geometries, int boxesPerGeometry, double inactiveFraction, bool opaqueMix) {
        std::vector<const AabbData*> data;
        const uint32_t strides[4] = {24, 32, 48, 40};
        for (int g = 0; g < geometries; ++g) {
            AabbLayout layout;
            layout.stride = strides[rng.below(4)];
            layout.primitiveOffset = 8 * rng.below(4);
            layout.misalign = rng.below(8);  // host pointers need no alignment (03714 is for device builds)
            const VkGeometryFlagsKHR flags =
                (opaqueMix ? (rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0) : 0) |
                (rng.coin(0.3) ? VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR : 0);
            data.push_back(addAabbs(aabbSoup(boxesPerGeometry, rng, 0.2f, inactiveFraction), flags, layout));
        }
        BuildOptions opt;
        opt.usePointers = rng.coin();
        if (rng.coin(0.3)) opt.flags |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        return buildAabbBlas(data, opt);
    }

    std::vector<std::unique_ptr<AabbData>> aabbs_;
    std::vector<std::unique_ptr<GeometryData>> triangles_;
};

// ---- exact cases: touching, grazing, flat and point boxes, inclusive t bounds ----------------------------------
TEST_F(procedural_geometry, exact_boundaries) {
    // Boxes: 0 the unit cube, 1 a point, 2 a flat square at z = 5, 3 a cube far along +x.
    AabbData* d = addAabbs({box(0, 0, 0, 1, 1, 1), box(0.5f, 0.25f, -3, 0.5f, 0.25f, -3), box(-1, -1, 5, 1, 1, 5),
                            box(10, 0, 0, 11, 1, 1)});
    AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(d));
    struct Case {
        const char* what;
        oracle::Ray ray;
        std::vector<int32_t> expected;  // primitive indices, in any order
    };
    const Case cases[] = {
        {"through the cube", makeRay({0.5f, 0.5f, 2}, {0, 0, -1}), {0}},
        {"through the point box (and the cube)", makeRay({0.5f, 0.25f, 2}, {0, 0, -1}), {0, 1}},
        {"head-on through the flat box", makeRay({0.5f, 0.5f, 7}, {0, 0, -1}), {2, 0}},
        {"along a face of the cube (x = 0)", makeRay({0, 0.5f, 3}, {0, 0, -1}), {0}},
        {"along an edge of the cube", makeRay({1, 1, 3}, {0, 0, -1}), {0}},
        {"touching an edge at one point", makeRay({2, 0, 0.5f}, {-1, 1, 0}), {0}},
        {"in the plane of the flat box", makeRay({-3, 0, 5}, {1, 0, 0}), {2}},
        {"from inside the cube", makeRay({0.5f, 0.5f, 0.5f}, {0, 1, 0}), {0}},
        {"from inside the cube, away from it", makeRay({0.5f, 0.5f, 0.5f}, {0, 0, 1}), {0, 2}},
        {"missing beside the cube", makeRay({1.0001f, 0.5f, 3}, {0, 0, -1}), {}},
        {"leaving the cube exactly at tMin", makeRay({0.5f, 0.5f, 0.5f}, {0, 0, 1}, 0.5f, 1.0f), {0}},
        {"entering the far cube exactly at tMax", makeRay({0, 0.5f, 0.5f}, {1, 0, 0}, 2.0f, 10.0f), {3}},
        {"cube entirely before tMin", makeRay({0.5f, 0.5f, 3}, {0, 0, -1}, 3.5f, 4.0f), {}},
        {"cube entirely after tMax", makeRay({0.5f, 0.5f, 3}, {0, 0, -1}, 0.0f, 1.99f), {}},
        {"zero-length window inside the cube", makeRay({0.5f, 0.5f, 3}, {0, 0, -1}, 2.5f, 2.5f), {0}},
    };
    for (const Case& c : cases) {
        const QueryTrace tr = query(tlas->handle, c.ray, 0, 0xFF, Confirm::None, tlas->scene.get());
        EXPECT_EQ(tr.problems, "") << c.what;
        std::multiset<int32_t> got, want(c.expected.begin(), c.expected.end());
        for (const Hit& h : tr.candidates) {
            EXPECT_EQ(h.type, VKAS_CANDIDATE_INTERSECTION_AABB) << c.what;
            got.insert(h.primitiveIndex);
        }
        EXPECT_EQ(got, want) << c.what << ": " << describe(c.ray);
        EXPECT_EQ(tr.committed.type, VKAS_COMMITTED_INTERSECTION_NONE) << "nothing is committed without a generate";
        // The oracle has them too (touching cases only as optional ones).
        const oracle::Result ex = oracle::trace(*tlas->scene, c.ray, 0, 0xFF);
        for (int32_t p : c.expected) {
            const oracle::Candidate* oc = ex.find(0, 0, p);
            EXPECT_NE(oc, nullptr) << c.what << " prim " << p;
        }
    }
}

TEST_F(procedural_geometry, candidate_and_generated_values) {
    // Two geometries, the second with primitiveOffset and a wide stride; an instance with every id field set.
    AabbLayout wide;
    wide.stride = 64;
    wide.primitiveOffset = 40;
    wide.misalign = 3;
    AabbData* g0 = addAabbs({box(-5, -5, -5, -4, -4, -4)}, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AabbData* g1 = addAabbs({box(9, 9, 9, 9.5f, 9.5f, 9.5f), box(-1, -1, -1, 1, 1, 1)}, 0, wide);
    AccelStruct* blas = buildAabbBlas({g0, g1});
    Instance inst;
    inst.transform = compose(translation(3, -2, 7), randomTransform(rng, 0.5f, 2.0f, true, 0));
    inst.customIndex = 0xABCDEF;
    inst.sbtOffset = 0x123456;
    inst.mask = 0x81;
    inst.blas = blas;
    Instance other = inst;
    other.blas = nullptr;  // inactive: instance 1 still counts
    AccelStruct* tlas = buildTlas({other, other, inst});
    // A ray from far away through the object-space origin of the instance.
    const Float3 center = transformPoint(inst.transform, {0, 0, 0});
    const oracle::Ray ray = makeRay({center[0] + 20, center[1] + 5, center[2] - 3}, {-20, -5, 3}, 0.0f, 1e30f);

    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas->handle, 0, 0x01, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
    // The ray may graze the instance's other boxes too; wait for the one it passes through.
    Hit c;
    while (vkasRayQueryProceed(&q)) {
        c = readHit(q, false);
        if (c.geometryIndex == 1 && c.primitiveIndex == 1) break;
    }
    ASSERT_EQ(c.primitiveIndex, 1) << "the box around the instance's origin was not reported";
    EXPECT_EQ(c.type, VKAS_CANDIDATE_INTERSECTION_AABB);
    EXPECT_EQ(c.instanceId, 2);
    EXPECT_EQ(c.customIndex, 0xABCDEF);
    EXPECT_EQ(c.sbtOffset, 0x123456u);
    EXPECT_EQ(c.geometryIndex, 1);
    EXPECT_EQ(c.primitiveIndex, 1);
    EXPECT_FALSE(c.aabbOpaque);
    EXPECT_FALSE(c.frontFace);
    EXPECT_EQ(c.bary[0], 0.0f);
    EXPECT_EQ(c.bary[1], 0.0f);
    const oracle::Result ex = oracle::trace(*tlas->scene, ray, 0, 0x01);
    const oracle::Candidate* oc = ex.find(2, 1, 1);
    ASSERT_NE(oc, nullptr);
    float oo[3], od[3];
    vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, oo);
    vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, od);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(oo[k], oc->objectOrigin[k], 1e-4 * (1 + std::fabs(oc->objectOrigin[k])));
        EXPECT_NEAR(od[k], oc->objectDirection[k], 1e-4 * (1 + std::fabs(oc->objectDirection[k])));
    }
    EXPECT_NEAR(c.t, oc->t, 1e-4 * oc->t) << "candidate T of an AABB is where the ray enters the box";
    // Position fetch has nothing to return for a box (invalid usage): zeros, no crash.
    float pos[3][3];
    std::memset(pos, 0x55, sizeof pos);
    vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_FALSE, pos);
    for (auto& v : pos)
        for (float x : v) EXPECT_EQ(x, 0.0f);
    // Confirm does nothing to an AABB candidate.
    vkasRayQueryConfirmIntersection(&q);
    EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
    // Generate commits it with the candidate's ids at tHit.
    const float tHit = c.t + 0.25f;
    vkasRayQueryGenerateIntersection(&q, tHit);
    const Hit h = readHit(q, true);
    EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_GENERATED);
    EXPECT_EQ(h.t, tHit);
    EXPECT_EQ(h.instanceId, 2);
    EXPECT_EQ(h.customIndex, 0xABCDEF);
    EXPECT_EQ(h.sbtOffset, 0x123456u);
    EXPECT_EQ(h.geometryIndex, 1);
    EXPECT_EQ(h.primitiveIndex, 1);
    EXPECT_FALSE(h.frontFace);
    EXPECT_EQ(h.bary[0], 0.0f);
    EXPECT_EQ(h.bary[1], 0.0f);
    float co[3], cd[3], o2w[3][4], w2o[3][4];
    vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_TRUE, co);
    vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_TRUE, cd);
    EXPECT_EQ(std::memcmp(co, oo, sizeof co), 0);
    EXPECT_EQ(std::memcmp(cd, od, sizeof cd), 0);
    vkasRayQueryGetIntersectionObjectToWorld(&q, VK_TRUE, o2w);
    EXPECT_EQ(std::memcmp(o2w, &inst.transform, sizeof o2w), 0);
    vkasRayQueryGetIntersectionWorldToObject(&q, VK_TRUE, w2o);
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(w2o[r][k], tlas->scene->instances[2].toObject[r][k], 1e-5 * (1 + std::fabs(w2o[r][k])));
    vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_TRUE, pos);
    for (auto& v : pos)
        for (float x : v) EXPECT_EQ(x, 0.0f);
    // Whatever else comes is not generated: the committed hit stays.
    while (vkasRayQueryProceed(&q)) {
    }
    EXPECT_EQ(readHit(q, true).t, tHit);
    EXPECT_EQ(readHit(q, true).primitiveIndex, 1);
}

// ---- CTS ray_query.procedural_geometry ---------------------------------------------------------------------------
// Spheres inside boxes: the application's "intersection shader" generates a hit only where the ray meets the sphere,
// so a ray through a box corner goes on to what is behind.
class procedural_geometry_spheres : public procedural_geometry {
  protected:
    struct Sphere {
        double c[3], r;
    };
    // Sphere entry t along (o, d), or -1.
    static double sphereT(const Sphere& s, const double o[3], const double d[3]) {
        double oc[3] = {o[0] - s.c[0], o[1] - s.c[1], o[2] - s.c[2]};
        const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
        const double cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - s.r * s.r;
        const double disc = b * b - a * cc;
        if (disc < 0) return -1;
        return (-b - std::sqrt(disc)) / a;
    }
    // Runs the query with the sphere shader and triangle confirmation; returns the committed hit.
    Hit traceSpheres(const AccelStruct* tlas, const std::vector<Sphere>& spheres, const oracle::Ray& ray,
                     uint32_t flags, std::string& problems) {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, flags, 0xFF, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
        while (vkasRayQueryProceed(&q)) {
            const uint32_t type = vkasRayQueryGetIntersectionType(&q, VK_FALSE);
            if (type == VKAS_CANDIDATE_INTERSECTION_TRIANGLE) {
                vkasRayQueryConfirmIntersection(&q);
                continue;
            }
            const int32_t p = vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
            if (p < 0 || size_t(p) >= spheres.size()) {
                problems += "bad AABB primitive index; ";
                continue;
            }
            float of[3], df[3];
            vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, of);
            vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, df);
            const double o[3] = {of[0], of[1], of[2]}, d[3] = {df[0], df[1], df[2]};
            const double t = sphereT(spheres[size_t(p)], o, d);
            const float committedT = vkasRayQueryGetIntersectionType(&q, VK_TRUE) != VKAS_COMMITTED_INTERSECTION_NONE
                                         ? vkasRayQueryGetIntersectionT(&q, VK_TRUE)
                                         : ray.tMax;
            // As a shader must: only a t within [tMin, committed t] may be generated (06353).
            if (t >= ray.tMin && float(t) <= committedT) vkasRayQueryGenerateIntersection(&q, float(t));
        }
        return readHit(q, true);
    }
};

TEST_F(procedural_geometry_spheres, object_behind_bounding_boxes) {
    // A 6 x 6 grid of unit boxes at z in [0, 1], each with a sphere of radius 0.4 inside; an opaque triangle floor at
    // z = -1 behind them. Rays from above: a ray through a sphere hits it; a ray through a box but beside its sphere
    // must reach the floor (the box must not hide it).
    std::vector<VkAabbPositionsKHR> boxes;
    std::vector<Sphere> spheres;
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) {
            boxes.push_back(box(float(i), float(j), 0, float(i + 1), float(j + 1), 1));
            spheres.push_back({{i + 0.5, j + 0.5, 0.5}, 0.4});
        }
    AccelStruct* aabbBlas = buildAabbBlas(addAabbs(boxes, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
    Mesh floor;
    floor.positions = {{-1, -1, -1}, {7, -1, -1}, {7, 7, -1}, {-1, 7, -1}};
    floor.indices = {0, 1, 2, 0, 2, 3};
    AccelStruct* floorBlas = buildBlas(*addTriangles(floor, VK_GEOMETRY_OPAQUE_BIT_KHR));
    const VkTransformMatrixKHR xf = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
    Instance a{xf, 7, 0xFF, 0, 0, aabbBlas}, f{xf, 9, 0xFF, 0, 0, floorBlas};
    const bool floorFirst = rng.coin();
    AccelStruct* tlas = buildTlas(floorFirst ? std::vector<Instance>{f, a} : std::vector<Instance>{a, f});
    const int floorId = floorFirst ? 0 : 1;
    size_t sphereHits = 0, floorHits = 0;
    for (int n = 0; n < 600; ++n) {
        const double x = rng.uniform(0.02, 5.98), y = rng.uniform(0.02, 5.98);
        const Float3 o = transformPoint(xf, {float(x), float(y), 3});
        const Float3 target = transformPoint(xf, {float(x + rng.uniform(-0.3, 0.3)), float(y + rng.uniform(-0.3, 0.3)), 0.5f});
        const oracle::Ray ray = makeRay(o, {target[0] - o[0], target[1] - o[1], target[2] - o[2]}, 0.0f, 1e30f);
        // Expected, in double with the exact object ray.
        const auto& toObj = tlas->scene->instances[0].toObject;
        double oo[3], od[3];
        for (int r = 0; r < 3; ++r) {
            oo[r] = toObj[r][0] * o[0] + toObj[r][1] * o[1] + toObj[r][2] * o[2] + toObj[r][3];
            od[r] = toObj[r][0] * ray.direction[0] + toObj[r][1] * ray.direction[1] + toObj[r][2] * ray.direction[2];
        }
        double best = std::numeric_limits<double>::infinity();
        int bestPrim = -1;
        for (size_t s = 0; s < spheres.size(); ++s) {
            const double t = sphereT(spheres[s], oo, od);
            if (t >= 0 && t < best) best = t, bestPrim = int(s);
        }
        // Skip rays that graze a sphere (the float object ray may decide either way).
        bool ambiguous = false;
        for (const Sphere& s : spheres) {
            const Sphere grown{{s.c[0], s.c[1], s.c[2]}, s.r + 1e-4}, shrunk{{s.c[0], s.c[1], s.c[2]}, s.r - 1e-4};
            if ((sphereT(grown, oo, od) >= 0) != (sphereT(shrunk, oo, od) >= 0)) ambiguous = true;
        }
        if (ambiguous) continue;
        std::string problems;
        const Hit h = traceSpheres(tlas, spheres, ray, 0, problems);
        EXPECT_EQ(problems, "");
        if (bestPrim >= 0) {
            ++sphereHits;
            EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_GENERATED) << describe(ray);
            EXPECT_EQ(h.primitiveIndex, bestPrim) << describe(ray);
            EXPECT_EQ(h.customIndex, 7);
            EXPECT_NEAR(h.t, best, 1e-4 * best) << describe(ray);
        } else {
            ++floorHits;
            EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE) << "the floor behind the boxes is hidden: " << describe(ray);
            EXPECT_EQ(h.instanceId, floorId);
            EXPECT_EQ(h.customIndex, 9);
        }
    }
    EXPECT_GT(sphereHits, 100u);
    EXPECT_GT(floorHits, 50u);
}

TEST_F(procedural_geometry_spheres, triangle_in_between) {
    // One box [0,1]^3 with a sphere of radius 0.45 at its centre, and a non-opaque triangle plane at z = 0.5 cutting
    // through the box (and the sphere). Rays straight down from z = 3: where a ray meets the sphere, the sphere's
    // entry (t in [2.05, 2.5)) is nearer than the plane (t = 2.5); elsewhere the box is entered (t = 2) but only the
    // plane is hit. Whichever the instance order, the committed hit is the nearer one, and a correct shader never
    // generates beyond the committed t.
    const std::vector<Sphere> spheres = {{{0.5, 0.5, 0.5}, 0.45}};
    AccelStruct* aabbBlas = buildAabbBlas(addAabbs({box(0, 0, 0, 1, 1, 1)}));
    Mesh plane;
    plane.positions = {{-1, -1, 0.5f}, {2, -1, 0.5f}, {2, 2, 0.5f}, {-1, 2, 0.5f}};
    plane.indices = {0, 1, 2, 0, 2, 3};
    AccelStruct* planeBlas = buildBlas(*addTriangles(plane, 0));
    for (int order = 0; order < 2; ++order) {
        Instance a{identityTransform(), 1, 0xFF, 0, 0, aabbBlas}, p{identityTransform(), 2, 0xFF, 0, 0, planeBlas};
        AccelStruct* tlas = buildTlas(order ? std::vector<Instance>{a, p} : std::vector<Instance>{p, a});
        for (int n = 0; n < 200; ++n) {
            const float x = rng.uniformf(0.1f, 0.9f), y = rng.uniformf(0.1f, 0.9f);
            const oracle::Ray ray = makeRay({x, y, 3}, {0, 0, -1});
            const double o[3] = {x, y, 3}, d[3] = {0, 0, -1};
            const double ts = sphereT(spheres[0], o, d);
            const double r2 = (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5);
            if (std::fabs(std::sqrt(r2) - 0.45) < 1e-4) continue;
            std::string problems;
            const Hit h = traceSpheres(tlas, spheres, ray, 0, problems);
            EXPECT_EQ(problems, "");
            if (ts >= 0) {
                EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_GENERATED) << describe(ray);
                EXPECT_EQ(h.customIndex, 1);
                EXPECT_NEAR(h.t, ts, 1e-5);
            } else {
                EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE) << describe(ray);
                EXPECT_EQ(h.customIndex, 2);
                EXPECT_FLOAT_EQ(h.t, 2.5f);
            }
        }
        EXPECT_TRUE(takeValidationErrors().empty()) << "a correct shader never breaks 06353";
    }
}

// ---- random soups against the oracle -----------------------------------------------------------------------------
struct SoupParam {
    int instances;
    int geometries;
    double inactive;
    uint32_t flags;
    const char* name;
};

class procedural_geometry_soup : public procedural_geometry, public ::testing::WithParamInterface<SoupParam> {};

TEST_P(procedural_geometry_soup, random) {
    const SoupParam& P = GetParam();
    std::vector<AccelStruct*> blases;
    for (int b = 0; b < 2; ++b) blases.push_back(randomAabbBlas(P.geometries, 60 + int(rng.below(120)), P.inactive, true));
    std::vector<Instance> instances;
    for (int i = 0; i < P.instances; ++i) {
        Instance inst;
        inst.transform = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 2.5f);
        inst.customIndex = rng.u32() & 0xFFFFFF;
        inst.sbtOffset = rng.u32() & 0xFFFFFF;
        inst.mask = rng.coin(0.8) ? 0xFF : (1u << rng.below(8));
        const uint32_t flagChoices[5] = {0, VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                         VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR,
                                         VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR,
                                         VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR};
        inst.flags = flagChoices[rng.below(5)];
        inst.blas = i > 0 && rng.coin(0.1) ? nullptr : blases[rng.below(2)];  // some inactive instances
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances);
    auto rays = randomRays(*tlas->scene, 150);
    const auto targeted = targetedRays(*tlas->scene, 1000000);  // every active box of every instance
    rays.insert(rays.end(), targeted.begin(), targeted.end());
    const uint32_t cullMask = rng.coin(0.8) ? 0xFF : (rng.u32() & 0xFF);
    const size_t hits = checkRays(tlas, rays, P.flags, cullMask);  // generate at the entry point, and batch
    checkCandidateSets(tlas, rays, P.flags, cullMask);
    if (P.flags & VKAS_RAY_FLAG_SKIP_AABBS) {
        EXPECT_EQ(hits, 0u);
    }
    if (!(P.flags & (VKAS_RAY_FLAG_SKIP_AABBS | VKAS_RAY_FLAG_CULL_OPAQUE | VKAS_RAY_FLAG_CULL_NO_OPAQUE)) && cullMask == 0xFF) {
        EXPECT_GT(hits, targeted.size() / 2) << "targeted rays should mostly hit";
    }
}

INSTANTIATE_TEST_SUITE_P(
    cpu_built, procedural_geometry_soup,
    ::testing::Values(SoupParam{1, 1, 0.0, 0, "one_instance"}, SoupParam{6, 3, 0.0, 0, "instances"},
                      SoupParam{6, 2, 0.3, 0, "inactive"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_OPAQUE, "opaque"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_NO_OPAQUE, "noopaque"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_CULL_OPAQUE, "cullopaque"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_CULL_NO_OPAQUE, "cullnoopaque"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT, "terminateonfirsthit"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_SKIP_TRIANGLES, "skiptriangles"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_SKIP_AABBS, "skipaabbs"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES, "cullbackfacingtriangles"},
                      SoupParam{4, 2, 0.1, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, "cullfrontfacingtriangles"}),
    [](const auto& info) { return std::string(info.param.name); });

// ---- inactive boxes among active ones ----------------------------------------------------------------------------
TEST_F(procedural_geometry, inactive_aabbs_keep_neighbours_visible) {
    // A row of 64 touching unit boxes along x; a random half is inactive (minX NaN, the other fields covering
    // everything). Every active box must stay a candidate, with its own primitive index; no inactive one ever is.
    std::vector<VkAabbPositionsKHR> boxes;
    std::vector<bool> active;
    for (int i = 0; i < 64; ++i) {
        const bool on = rng.coin();
        boxes.push_back(on ? box(float(i), 0, 0, float(i + 1), 1, 1) : inactiveBox(rng));
        active.push_back(on);
    }
    boxes[0] = inactiveBox(rng), active[0] = false;  // inactive at both ends too
    boxes[63] = inactiveBox(rng), active[63] = false;
    AabbLayout layout;
    layout.stride = rng.coin() ? 24 : 32;
    AccelStruct* blas = buildAabbBlas(addAabbs(boxes, 0, layout));
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    // One ray along the whole row, through the boxes' interiors.
    const oracle::Ray along = makeRay({-5, 0.5f, 0.5f}, {1, 0, 0});
    QueryTrace tr = query(tlas->handle, along, 0, 0xFF, Confirm::None, tlas->scene.get());
    EXPECT_EQ(tr.problems, "");
    std::set<int32_t> got;
    for (const Hit& h : tr.candidates) got.insert(h.primitiveIndex);
    for (int i = 0; i < 64; ++i) EXPECT_EQ(got.count(i), active[i] ? 1u : 0u) << "box " << i;
    // One ray across each box: exactly that box (and its touching neighbours when the ray is on the shared face).
    for (int i = 0; i < 64; ++i) {
        const oracle::Ray across = makeRay({i + rng.uniformf(0.05f, 0.95f), rng.uniformf(0.05f, 0.95f), 5}, {0, 0, -1});
        tr = query(tlas->handle, across, 0, 0xFF, Confirm::All, tlas->scene.get());
        EXPECT_EQ(tr.problems, "");
        if (active[i]) {
            EXPECT_EQ(tr.committed.type, VKAS_COMMITTED_INTERSECTION_GENERATED) << "box " << i;
            EXPECT_EQ(tr.committed.primitiveIndex, i);
            EXPECT_FLOAT_EQ(tr.committed.t, 4.0f);
        } else {
            EXPECT_EQ(tr.candidates.size(), 0u) << "inactive box " << i << " was reported";
        }
    }
    checkCandidateSets(tlas, targetedRays(*tlas->scene, 1000), 0);
    checkRays(tlas, randomRays(*tlas->scene, 200), 0);
}

// ---- opacity: geometry x instance x ray ---------------------------------------------------------------------------
struct OpacityParam {
    int rayOpacity;
    bool geometryOpaque;
    int instanceOpacity;
};
class procedural_geometry_opacity : public procedural_geometry, public ::testing::WithParamInterface<OpacityParam> {};

TEST_P(procedural_geometry_opacity, candidate_aabb_opaque) {
    const OpacityParam& P = GetParam();
    const uint32_t rayFlags = kOpacityFlags[P.rayOpacity];
    AccelStruct* blas = buildAabbBlas(addAabbs({box(-1, -1, -1, 1, 1, 0)}, P.geometryOpaque ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
    AccelStruct* tlas = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, kInstanceOpacity[P.instanceOpacity], blas}});
    bool opaque = P.geometryOpaque;
    if (P.instanceOpacity == 1) opaque = true;
    if (P.instanceOpacity == 2) opaque = false;
    if (rayFlags == VKAS_RAY_FLAG_OPAQUE) opaque = true;
    if (rayFlags == VKAS_RAY_FLAG_NO_OPAQUE) opaque = false;
    const bool culled = (rayFlags == VKAS_RAY_FLAG_CULL_OPAQUE && opaque) || (rayFlags == VKAS_RAY_FLAG_CULL_NO_OPAQUE && !opaque);
    for (int i = 0; i < 10; ++i) {
        const oracle::Ray r = makeRay({rng.uniformf(-0.9f, 0.9f), rng.uniformf(-0.9f, 0.9f), 1}, {0, 0, -1});
        // Opaque or not, an AABB comes back from Proceed: only the application knows what is inside.
        const QueryTrace none = query(tlas->handle, r, rayFlags, 0xFF, Confirm::None, tlas->scene.get());
        EXPECT_EQ(none.problems, "");
        ASSERT_EQ(none.candidates.size(), culled ? 0u : 1u);
        if (!culled) {
            EXPECT_EQ(none.candidates[0].aabbOpaque, opaque);
        }
        EXPECT_EQ(none.committed.type, VKAS_COMMITTED_INTERSECTION_NONE) << "an AABB is committed only by a generate";
        const QueryTrace all = query(tlas->handle, r, rayFlags, 0xFF, Confirm::All, tlas->scene.get());
        EXPECT_EQ(all.problems, "");
        EXPECT_EQ(all.committed.type, culled ? VKAS_COMMITTED_INTERSECTION_NONE : VKAS_COMMITTED_INTERSECTION_GENERATED);
        if (!culled) {
            EXPECT_FLOAT_EQ(all.committed.t, 1.0f);
        }
    }
    checkCandidateSets(tlas, randomRays(*tlas->scene, 50), rayFlags);
}

INSTANTIATE_TEST_SUITE_P(cpu_built, procedural_geometry_opacity, ::testing::ValuesIn([] {
                             std::vector<OpacityParam> v;
                             for (int r = 0; r < 5; ++r)
                                 for (bool g : {false, true})
                                     for (int i = 0; i < 3; ++i) v.push_back({r, g, i});
                             return v;
                         }()),
                         [](const auto& info) {
                             const auto& p = info.param;
                             return std::string(kOpacityNames[p.rayOpacity]) +
                                    (p.geometryOpaque ? "_opaquegeometry" : "_noopaquegeometry") + "_" +
                                    kInstanceOpacityNames[p.instanceOpacity];
                         });

// ---- mixed top-level structures: triangles and boxes, Skip and facing flags -----------------------------------------
class procedural_geometry_mixed : public procedural_geometry, public ::testing::WithParamInterface<uint32_t> {
  protected:
    AccelStruct* mixedScene() {
        AccelStruct* tri = buildBlas(*addTriangles(triangleSoup(150, rng, 0.3f), rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        AccelStruct* tri2 = buildBlas(*addTriangles(icosphere(2), VK_GEOMETRY_OPAQUE_BIT_KHR));
        AccelStruct* boxes = randomAabbBlas(2, 100, 0.1, true);
        std::vector<Instance> instances;
        AccelStruct* kinds[3] = {tri, tri2, boxes};
        for (int i = 0; i < 9; ++i) {
            Instance inst;
            inst.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 2.0f);
            inst.customIndex = uint32_t(i);
            inst.flags = rng.below(4) == 0 ? VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR : 0;
            inst.blas = kinds[i % 3];
            instances.push_back(inst);
        }
        return buildTlas(instances);
    }
};

TEST_P(procedural_geometry_mixed, random_scene) {
    const uint32_t flags = GetParam();
    AccelStruct* tlas = mixedScene();
    auto rays = randomRays(*tlas->scene, 250);
    const auto t = targetedRays(*tlas->scene, 250);
    rays.insert(rays.end(), t.begin(), t.end());
    checkRays(tlas, rays, flags);
    checkCandidateSets(tlas, rays, flags);
    // Counting candidates by kind: Skip flags remove exactly their kind; facing culls never remove boxes.
    size_t aabbCandidates = 0, triangleCandidates = 0;
    for (const auto& r : rays) {
        const QueryTrace tr = query(tlas->handle, r, flags | VKAS_RAY_FLAG_NO_OPAQUE, 0xFF, Confirm::None, tlas->scene.get());
        for (const Hit& h : tr.candidates)
            (h.type == VKAS_CANDIDATE_INTERSECTION_AABB ? aabbCandidates : triangleCandidates)++;
    }
    if (flags & VKAS_RAY_FLAG_SKIP_AABBS)
        EXPECT_EQ(aabbCandidates, 0u);
    else
        EXPECT_GT(aabbCandidates, 0u);
    if (flags & VKAS_RAY_FLAG_SKIP_TRIANGLES)
        EXPECT_EQ(triangleCandidates, 0u);
    else
        EXPECT_GT(triangleCandidates, 0u);
}

INSTANTIATE_TEST_SUITE_P(cpu_built, procedural_geometry_mixed,
                         ::testing::Values(0u, uint32_t(VKAS_RAY_FLAG_SKIP_AABBS), uint32_t(VKAS_RAY_FLAG_SKIP_TRIANGLES),
                                           uint32_t(VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES),
                                           uint32_t(VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES),
                                           uint32_t(VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT),
                                           uint32_t(VKAS_RAY_FLAG_SKIP_AABBS | VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT)),
                         [](const auto& info) {
                             const uint32_t f = info.param;
                             std::string n = "flags";
                             if (f & VKAS_RAY_FLAG_SKIP_AABBS) n += "_skipaabbs";
                             if (f & VKAS_RAY_FLAG_SKIP_TRIANGLES) n += "_skiptriangles";
                             if (f & VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES) n += "_cullbackfacingtriangles";
                             if (f & VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES) n += "_cullfrontfacingtriangles";
                             if (f & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT) n += "_terminateonfirsthit";
                             return f ? n : std::string("none");
                         });

// ---- generate: termination, validity rule 06353, candidates after a generate ------------------------------------
TEST_F(procedural_geometry, terminate_on_first_hit_after_generate) {
    // Five boxes in a column under the ray, at t = 1, 3, 5, 7, 9.
    std::vector<VkAabbPositionsKHR> boxes;
    for (int k = 0; k < 5; ++k) boxes.push_back(box(-1, -1, -2.0f * k - 1, 1, 1, -2.0f * k));
    AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(addAabbs(boxes)));
    const oracle::Ray ray = makeRay({0, 0, 1}, {0, 0, -1});
    // Without TerminateOnFirstHit: generating at each box's exit leaves later boxes (entry <= committed t) coming.
    {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, ray.origin.data(), 0, ray.direction.data(), 100);
        int candidates = 0;
        while (vkasRayQueryProceed(&q)) {
            ++candidates;
            const int32_t p = vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
            vkasRayQueryGenerateIntersection(&q, 2.0f * p + 2.0f);  // the box's far side
        }
        EXPECT_GE(candidates, 1);
        EXPECT_EQ(readHit(q, true).type, VKAS_COMMITTED_INTERSECTION_GENERATED);
        EXPECT_LE(readHit(q, true).t, 2.0f) << "the nearest box's far side bounds the committed t";
    }
    // With it: traversal ends right after the first generate.
    for (int rep = 0; rep < 5; ++rep) {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT, 0xFF, ray.origin.data(), 0,
                               ray.direction.data(), 100);
        // Skip a few candidates first (not generating), then generate on the next one.
        const int skip = rep % 3;
        int seen = 0;
        int32_t generated = -1;
        float tHit = 0;
        while (vkasRayQueryProceed(&q)) {
            ASSERT_EQ(generated, -1) << "Proceed went on after a generate with TerminateOnFirstHit";
            if (seen++ < skip) continue;
            generated = vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
            tHit = vkasRayQueryGetIntersectionT(&q, VK_FALSE);
            vkasRayQueryGenerateIntersection(&q, tHit);
        }
        ASSERT_NE(generated, -1);
        const Hit h = readHit(q, true);
        EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_GENERATED);
        EXPECT_EQ(h.primitiveIndex, generated);
        EXPECT_EQ(h.t, tHit);
    }
}

TEST_F(procedural_geometry, generate_validation) {
    // Two boxes under the ray: t in [2, 4] and [7, 9].
    AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(addAabbs({box(-1, -1, -3, 1, 1, -1), box(-1, -1, -8, 1, 1, -6)})));
    const oracle::Ray ray = makeRay({0, 0, 1}, {0, 0, -1}, 0.5f, 50.0f);
    const std::string vuid = "VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06353";
    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
    ASSERT_TRUE(vkasRayQueryProceed(&q));
    ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_FALSE), VKAS_CANDIDATE_INTERSECTION_AABB);
    const int32_t first = vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
    // Below tMin, above tMax, NaN, infinite: each reported, none committed.
    for (float bad : {0.25f, 50.5f, kNaN, -1.0f, std::numeric_limits<float>::infinity()}) {
        vkasRayQueryGenerateIntersection(&q, bad);
        const auto errors = takeValidationErrors();
        EXPECT_TRUE(hasVuid(errors, vuid)) << "Hit T " << bad << ":" << joined(errors);
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE) << bad;
    }
    // A valid Hit T (the candidate is still pending after the rejected ones).
    vkasRayQueryGenerateIntersection(&q, 8.0f);
    EXPECT_TRUE(takeValidationErrors().empty());
    EXPECT_EQ(readHit(q, true).type, VKAS_COMMITTED_INTERSECTION_GENERATED);
    EXPECT_EQ(readHit(q, true).t, 8.0f);
    EXPECT_EQ(readHit(q, true).primitiveIndex, first);
    // The other box still meets [tMin, 8]; now the committed t bounds Hit T.
    ASSERT_TRUE(vkasRayQueryProceed(&q));
    const int32_t second = vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
    EXPECT_NE(second, first);
    vkasRayQueryGenerateIntersection(&q, 8.5f);
    auto errors = takeValidationErrors();
    EXPECT_TRUE(hasVuid(errors, vuid)) << "Hit T beyond the committed t:" << joined(errors);
    EXPECT_EQ(readHit(q, true).primitiveIndex, first);
    // Equal to the committed t is valid (inclusive), and replaces the committed hit.
    vkasRayQueryGenerateIntersection(&q, 8.0f);
    EXPECT_TRUE(takeValidationErrors().empty());
    EXPECT_EQ(readHit(q, true).primitiveIndex, second);
    EXPECT_EQ(readHit(q, true).t, 8.0f);
    EXPECT_FALSE(vkasRayQueryProceed(&q));
    // Without a pending AABB candidate a generate does nothing and reports nothing.
    vkasRayQueryGenerateIntersection(&q, 1.0f);
    EXPECT_EQ(readHit(q, true).t, 8.0f);
    EXPECT_TRUE(takeValidationErrors().empty());
    // tMin itself is valid (inclusive).
    vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
    ASSERT_TRUE(vkasRayQueryProceed(&q));
    vkasRayQueryGenerateIntersection(&q, ray.tMin);
    EXPECT_TRUE(takeValidationErrors().empty());
    EXPECT_EQ(readHit(q, true).t, ray.tMin);
    EXPECT_FALSE(vkasRayQueryProceed(&q)) << "no box meets [tMin, tMin] after that";
}

TEST_F(procedural_geometry, generate_on_triangle_candidate_does_nothing) {
    Mesh m;
    m.positions = {{-2, -2, 0}, {2, -2, 0}, {0, 2, 0}};
    m.indices = {0, 1, 2};
    AccelStruct* tlas = buildSingleInstanceTlas(buildBlas(*addTriangles(m, 0)));
    const oracle::Ray ray = makeRay({0, 0, 1}, {0, 0, -1});
    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, ray.origin.data(), 0, ray.direction.data(), 10);
    ASSERT_TRUE(vkasRayQueryProceed(&q));
    ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_FALSE), VKAS_CANDIDATE_INTERSECTION_TRIANGLE);
    vkasRayQueryGenerateIntersection(&q, 0.5f);
    EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_NONE);
    vkasRayQueryConfirmIntersection(&q);
    EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), VKAS_COMMITTED_INTERSECTION_TRIANGLE);
    EXPECT_TRUE(takeValidationErrors().empty());
}

TEST_F(procedural_geometry, closest_generated_wins_in_any_order) {
    // Overlapping boxes along the ray; generating at each entry leaves the nearest entry committed, whatever the
    // order traversal found them in.
    std::vector<VkAabbPositionsKHR> boxes;
    std::vector<float> entries;
    for (int k = 0; k < 40; ++k) {
        const float z1 = rng.uniformf(-10, 0), z0 = z1 - rng.uniformf(0.1f, 3);
        boxes.push_back(box(-1 - rng.uniformf(0, 1), -1, z0, 1, 1 + rng.uniformf(0, 1), z1));
        entries.push_back(1 - z1);
    }
    AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(addAabbs(boxes)));
    const oracle::Ray ray = makeRay({0, 0, 1}, {0, 0, -1}, 0, 1000);
    const QueryTrace tr = query(tlas->handle, ray, 0, 0xFF, Confirm::All, tlas->scene.get());
    EXPECT_EQ(tr.problems, "");
    const size_t nearest = size_t(std::min_element(entries.begin(), entries.end()) - entries.begin());
    EXPECT_EQ(tr.committed.type, VKAS_COMMITTED_INTERSECTION_GENERATED);
    EXPECT_EQ(tr.committed.primitiveIndex, int32_t(nearest));
    EXPECT_FLOAT_EQ(tr.committed.t, entries[nearest]);
}

// ---- vkasTraceRays: no intersection shader ---------------------------------------------------------------------
TEST_F(procedural_geometry, batch_never_hits_aabbs) {
    AccelStruct* boxes = randomAabbBlas(2, 200, 0.1, true);
    Mesh m;
    m.positions = {{-3, -3, -3}, {3, -3, -3}, {0, 3, -3}};
    m.indices = {0, 1, 2};
    AccelStruct* tri = buildBlas(*addTriangles(m, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* onlyBoxes = buildSingleInstanceTlas(boxes);
    std::vector<VkasRay> rays(300);
    for (auto& r : rays) {
        r = VkasRay{{rng.uniformf(-0.8f, 0.8f), rng.uniformf(-0.8f, 0.8f), 5}, 0, {0, 0, -1}, 100};
    }
    for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
        std::vector<VkasHit> out(rays.size());
        ASSERT_EQ(vkasTraceRays(device, onlyBoxes->handle, mode, 0, 0xFF, uint32_t(rays.size()), rays.data(), out.data()),
                  VK_SUCCESS);
        for (const VkasHit& h : out) EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_NONE);
    }
    // Boxes in front of a triangle do not hide it.
    AccelStruct* mixed = buildTlas({Instance{identityTransform(), 0, 0xFF, 0, 0, boxes},
                                    Instance{identityTransform(), 1, 0xFF, 0, 0, tri}});
    std::vector<VkasHit> out(rays.size());
    ASSERT_EQ(vkasTraceRays(device, mixed->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                            rays.data(), out.data()),
              VK_SUCCESS);
    for (const VkasHit& h : out) {
        EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_TRIANGLE);
        EXPECT_EQ(h.instanceId, 1);
        EXPECT_FLOAT_EQ(h.t, 8.0f);
    }
    // SkipTriangles leaves nothing a batch can hit.
    ASSERT_EQ(vkasTraceRays(device, mixed->handle, VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_RAY_FLAG_SKIP_TRIANGLES, 0xFF,
                            uint32_t(rays.size()), rays.data(), out.data()),
              VK_SUCCESS);
    for (const VkasHit& h : out) EXPECT_EQ(h.type, VKAS_COMMITTED_INTERSECTION_NONE);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// ---- builds: sizes, determinism, update, stride 0 ------------------------------------------------------------------
TEST_F(procedural_geometry, build_sizes_match_triangles) {
    // AABB records are 48 bytes; format 2 stores a triangle in 44 bytes of its leaf with a 4-byte tail after the last
    // (docs/FORMAT.md), so the sizes differ by exactly 4 (n - 1) bytes and the scratch (gathered 48-byte records) not.
    const auto boxData = makeAabbs({box(0, 0, 0, 1, 1, 1)});
    for (uint32_t n : {0u, 1u, 4u, 5u, 33u, 1000u, 100000u}) {
        VkAccelerationStructureGeometryKHR a = boxData->geometry;
        Mesh m;
        m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        m.indices = {0, 1, 2};
        auto t = makeGeometry(m, VK_INDEX_TYPE_UINT32);
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.geometryCount = 1;
        VkAccelerationStructureBuildSizesInfoKHR sa{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR}, st = sa;
        info.pGeometries = &a;
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &n, &sa);
        info.pGeometries = &t->geometry;
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &n, &st);
        EXPECT_EQ(sa.accelerationStructureSize, st.accelerationStructureSize + (n ? 4ull * (n - 1) : 0)) << n;
        EXPECT_EQ(sa.buildScratchSize, st.buildScratchSize) << n;
        EXPECT_EQ(sa.updateScratchSize, st.updateScratchSize) << n;
    }
    // Builds of every count fit the sizes they asked for (the fixture checks the canaries around each).
    for (int n : {0, 1, 3, 4, 5, 17, 64, 65, 2000}) {
        AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(addAabbs(aabbSoup(n, rng, 0.3f, 0.2))));
        checkRays(tlas, randomRays(*tlas->scene, 30), 0);
    }
    // A large soup: traversal agrees with the oracle on a deep tree.
    AccelStruct* big = buildSingleInstanceTlas(buildAabbBlas(addAabbs(aabbSoup(20000, rng, 0.02f, 0.05))));
    checkRays(big, randomRays(*big->scene, 100), 0);
}

TEST_F(procedural_geometry, deterministic_bytes) {
    const auto boxes = aabbSoup(500, rng, 0.2f, 0.1);
    AccelStruct* a = buildAabbBlas(addAabbs(boxes));
    AabbLayout other;
    other.stride = 40;
    other.primitiveOffset = 16;
    other.misalign = 5;
    BuildOptions opt;
    opt.memoryPoison = 0x3C;
    opt.scratchPoison = 0x77;
    AccelStruct* b = buildAabbBlas(addAabbs(boxes, 0, other), opt);
    ASSERT_EQ(a->size, b->size);
    // The used size is in the header (offset 16); compare exactly those bytes.
    uint64_t used = 0;
    std::memcpy(&used, a->data() + 16, 8);
    ASSERT_GT(used, 256u);
    ASSERT_LE(used, a->size);
    EXPECT_EQ(std::memcmp(a->data(), b->data(), used), 0) << "the same boxes give the same bytes, whatever the layout";
}

TEST_F(procedural_geometry, zero_stride_repeats_one_box) {
    AabbLayout layout;
    layout.stride = 0;  // not forbidden (spec Q9): every primitive reads the same box
    AabbData* d = addAabbs({box(-1, -1, -1, 1, 1, 1)}, 0, layout);
    d->range.primitiveCount = 5;
    AccelStruct* tlas = buildSingleInstanceTlas(buildAabbBlas(d));
    const QueryTrace tr = query(tlas->handle, makeRay({0, 0, 5}, {0, 0, -1}), 0, 0xFF, Confirm::None, tlas->scene.get());
    EXPECT_EQ(tr.problems, "");
    std::set<int32_t> prims;
    for (const Hit& h : tr.candidates) prims.insert(h.primitiveIndex);
    EXPECT_EQ(prims, (std::set<int32_t>{0, 1, 2, 3, 4}));
}

TEST_F(procedural_geometry, update_moves_boxes) {
    std::vector<VkAabbPositionsKHR> boxes = aabbSoup(100, rng, 0.2f, 0.1);
    AabbData* d = addAabbs(boxes);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
    auto pb = prepareBlas({d->geometry}, {d->range}, opt);
    submit({pb.get()});
    AccelStruct* blas = pb->as;
    // Move every active box (inactive ones stay inactive: VUID 03663/03664).
    for (size_t i = 0; i < boxes.size(); ++i) {
        if (std::isnan(boxes[i].minX)) continue;
        const float dx = rng.uniformf(-0.5f, 0.5f);
        boxes[i].minX += dx, boxes[i].maxX += dx;
    }
    AabbData* moved = addAabbs(boxes);
    VkAccelerationStructureBuildGeometryInfoKHR info = pb->info;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = blas->handle;
    info.pGeometries = &moved->geometry;
    std::vector<uint8_t> scratch(blas->sizes.updateScratchSize + 1);
    info.scratchData.hostAddress = scratch.data();
    const VkAccelerationStructureBuildRangeInfoKHR* ranges = &moved->range;
    ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &ranges), VK_SUCCESS);
    auto updated = std::make_shared<oracle::Blas>();
    updated->geometries.push_back(oracle::fetchGeometry(moved->geometry, moved->range));
    updated->computeBounds();
    blasRegistry[blas->reference()] = updated;
    blas->blas = updated;
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    checkRays(tlas, targetedRays(*tlas->scene, 200), 0);
    checkCandidateSets(tlas, randomRays(*tlas->scene, 100), 0);
}

// ---- build valid usage -------------------------------------------------------------------------------------------
class procedural_geometry_validation : public procedural_geometry {
  protected:
    // Builds `geometries` into a fresh BLAS of ample size; returns the validation messages.
    std::vector<std::string> tryBuild(const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                                      const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
        EXPECT_TRUE(takeValidationErrors().empty());
        BuildOptions opt;
        AccelStruct* as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 1 << 16, opt);
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.dstAccelerationStructure = as->handle;
        info.geometryCount = uint32_t(geometries.size());
        info.pGeometries = geometries.data();
        std::vector<uint8_t> scratch(1 << 16);
        info.scratchData.hostAddress = scratch.data();
        const VkAccelerationStructureBuildRangeInfoKHR* r = ranges.data();
        const VkResult result = vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &r);
        auto errors = takeValidationErrors();
        EXPECT_EQ(result == VK_ERROR_VALIDATION_FAILED_EXT, !errors.empty()) << "result " << result << joined(errors);
        return errors;
    }
};

TEST_F(procedural_geometry_validation, valid_build_reports_nothing) {
    AabbLayout layout;
    layout.stride = 32;
    layout.primitiveOffset = 8;
    layout.misalign = 4;  // the data pointer needs no alignment on the host (03714 is a device-build rule)
    AabbData* d = addAabbs(aabbSoup(20, rng, 0.3f, 0.2), VK_GEOMETRY_OPAQUE_BIT_KHR, layout);
    EXPECT_TRUE(tryBuild({d->geometry}, {d->range}).empty());
}

TEST_F(procedural_geometry_validation, stride_multiple_of_8) {
    AabbLayout layout;
    layout.stride = 28;
    AabbData* d = addAabbs(aabbSoup(4, rng, 0.3f), 0, layout);
    const auto errors = tryBuild({d->geometry}, {d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03545")) << joined(errors);
    // The sizes query checks the structure too.
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.geometryCount = 1;
    info.pGeometries = &d->geometry;
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    const uint32_t count = 4;
    vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
    const auto sizeErrors = takeValidationErrors();
    EXPECT_TRUE(hasVuid(sizeErrors, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03545")) << joined(sizeErrors);
}

TEST_F(procedural_geometry_validation, stride_at_most_2_pow_32_minus_1) {
    AabbData* d = addAabbs({box(0, 0, 0, 1, 1, 1)});
    VkAccelerationStructureGeometryKHR g = d->geometry;
    g.geometry.aabbs.stride = (1ull << 32) + 8;  // a multiple of 8, but too large
    const auto errors = tryBuild({g}, {d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03820")) << joined(errors);
}

TEST_F(procedural_geometry_validation, primitive_offset_multiple_of_8) {
    AabbLayout layout;
    layout.primitiveOffset = 12;
    AabbData* d = addAabbs(aabbSoup(4, rng, 0.3f), 0, layout);
    const auto errors = tryBuild({d->geometry}, {d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03659")) << joined(errors);
}

TEST_F(procedural_geometry_validation, data_address) {
    AabbData* d = addAabbs(aabbSoup(4, rng, 0.3f));
    VkAccelerationStructureGeometryKHR g = d->geometry;
    g.geometry.aabbs.data.hostAddress = nullptr;
    const auto errors = tryBuild({g}, {d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03774")) << joined(errors);
    // With no primitives the pointer is never read: NULL is fine.
    VkAccelerationStructureBuildRangeInfoKHR empty{};
    EXPECT_TRUE(tryBuild({g}, {empty}).empty());
}

TEST_F(procedural_geometry_validation, one_geometry_type_per_blas) {
    AabbData* d = addAabbs(aabbSoup(4, rng, 0.3f));
    GeometryData* t = addTriangles(triangleSoup(4, rng, 0.3f));
    const auto errors = tryBuild({t->geometry, d->geometry}, {t->range, d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03792")) << joined(errors);
}

TEST_F(procedural_geometry_validation, sType) {
    AabbData* d = addAabbs(aabbSoup(4, rng, 0.3f));
    VkAccelerationStructureGeometryKHR g = d->geometry;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    const auto errors = tryBuild({g}, {d->range});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-sType-sType")) << joined(errors);
}

TEST_F(procedural_geometry_validation, min_not_greater_than_max) {
    const char* vuids[3] = {"VUID-VkAabbPositionsKHR-minX-03546", "VUID-VkAabbPositionsKHR-minY-03547",
                            "VUID-VkAabbPositionsKHR-minZ-03548"};
    for (int axis = 0; axis < 3; ++axis) {
        auto boxes = aabbSoup(10, rng, 0.3f, 0.2);
        float* b = &boxes[5].minX;
        b[0] = 0, b[1] = 0, b[2] = 0, b[3] = 1, b[4] = 1, b[5] = 1;
        std::swap(b[axis], b[axis + 3]);  // min > max on this axis
        const AabbData* d = addAabbs(boxes);
        const auto errors = tryBuild({d->geometry}, {d->range});
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(hasVuid(errors, vuids[k]), k == axis) << "axis " << axis << joined(errors);
    }
    // Inactive boxes are exempt: their other fields may hold anything.
    std::vector<VkAabbPositionsKHR> boxes = {inactiveBox(rng), box(0, 0, 0, 1, 1, 1)};
    boxes[0].minY = 5, boxes[0].maxY = -5;
    const AabbData* d = addAabbs(boxes);
    EXPECT_TRUE(tryBuild({d->geometry}, {d->range}).empty());
}

TEST_F(procedural_geometry_validation, primitive_count_limit) {
    // 2^29 AABBs (one more than maxPrimitiveCount) with stride 0 over a single box: reported before any data is read.
    AabbLayout layout;
    layout.stride = 0;
    AabbData* d = addAabbs({box(0, 0, 0, 1, 1, 1)}, 0, layout);
    VkAccelerationStructureBuildRangeInfoKHR r = d->range;
    r.primitiveCount = 1u << 29;
    const auto errors = tryBuild({d->geometry}, {r});
    EXPECT_TRUE(hasVuid(errors, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03794")) << joined(errors);
    EXPECT_FALSE(hasVuid(errors, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03795"))
        << "03795 is the triangle rule";
}

// Without validation, invalid boxes are never hit and never crash the build or the traversal.
TEST_F(procedural_geometry, inverted_boxes_without_validation) {
    VkasDeviceCreateInfo ci{};
    ci.disableValidation = VK_TRUE;
    ci.workerThreadCount = 1;
    VkDevice dev = VK_NULL_HANDLE;
    ASSERT_EQ(vkasCreateDevice(&ci, &dev), VK_SUCCESS);
#define GET(name) auto name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(dev, #name))
    GET(vkCreateBuffer);
    GET(vkGetBufferMemoryRequirements);
    GET(vkAllocateMemory);
    GET(vkBindBufferMemory);
    GET(vkGetAccelerationStructureBuildSizesKHR);
    GET(vkCreateAccelerationStructureKHR);
    GET(vkBuildAccelerationStructuresKHR);
#undef GET
    auto makeAs = [&](VkAccelerationStructureTypeKHR type, VkDeviceSize size) {
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = size;
        bci.usage = kAsBufferUsage;
        VkBuffer buf;
        EXPECT_EQ(vkCreateBuffer(dev, &bci, nullptr, &buf), VK_SUCCESS);
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(dev, buf, &req);
        VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flagsInfo};
        mai.allocationSize = req.size;
        VkDeviceMemory mem;
        EXPECT_EQ(vkAllocateMemory(dev, &mai, nullptr, &mem), VK_SUCCESS);
        EXPECT_EQ(vkBindBufferMemory(dev, buf, mem, 0), VK_SUCCESS);
        VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        aci.buffer = buf;
        aci.size = size;
        aci.type = type;
        VkAccelerationStructureKHR as;
        EXPECT_EQ(vkCreateAccelerationStructureKHR(dev, &aci, nullptr, &as), VK_SUCCESS);
        return as;
    };
    // Box 0 inverted on x, 1 NaN in maxY (undefined behaviour), 2 valid; all under the ray.
    std::vector<VkAabbPositionsKHR> boxes = {box(1, -1, -1, -1, 1, 0), box(-1, -1, -3, 1, kNaN, -2),
                                             box(-1, -1, -5, 1, 1, -4)};
    AabbData* d = addAabbs(boxes);
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.geometryCount = 1;
    info.pGeometries = &d->geometry;
    const uint32_t count = 3;
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
    VkAccelerationStructureKHR blas = makeAs(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sizes.accelerationStructureSize);
    std::vector<uint8_t> scratch(sizes.buildScratchSize);
    info.dstAccelerationStructure = blas;
    info.scratchData.hostAddress = scratch.data();
    const VkAccelerationStructureBuildRangeInfoKHR* r = &d->range;
    ASSERT_EQ(vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &info, &r), VK_SUCCESS);
    Instance inst;
    inst.blas = nullptr;
    uint8_t bytes[64];
    packInstance(inst, bytes);
    const uint64_t ref = uint64_t(blas);
    std::memcpy(bytes + 56, &ref, 8);
    VkAccelerationStructureGeometryKHR ig{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    ig.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    ig.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    ig.geometry.instances.data.hostAddress = bytes;
    VkAccelerationStructureBuildGeometryInfoKHR tinfo{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    tinfo.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    tinfo.geometryCount = 1;
    tinfo.pGeometries = &ig;
    const uint32_t one = 1;
    vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &tinfo, &one, &sizes);
    VkAccelerationStructureKHR tlas = makeAs(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize);
    std::vector<uint8_t> tscratch(sizes.buildScratchSize);
    tinfo.dstAccelerationStructure = tlas;
    tinfo.scratchData.hostAddress = tscratch.data();
    VkAccelerationStructureBuildRangeInfoKHR trange{};
    trange.primitiveCount = 1;
    const VkAccelerationStructureBuildRangeInfoKHR* tr = &trange;
    ASSERT_EQ(vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &tinfo, &tr), VK_SUCCESS);
    const float o[3] = {0, 0, 1}, dir[3] = {0, 0, -1};
    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas, 0, 0xFF, o, 0, dir, 100);
    std::vector<int32_t> prims;
    while (vkasRayQueryProceed(&q)) prims.push_back(vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE));
    EXPECT_EQ(prims, std::vector<int32_t>{2}) << "only the valid box is a candidate";
    vkasDestroyDevice(dev);
}

// ---- vkasTraceRaysProcedural: the intersection step as a callback ----------------------------------------------
namespace {
struct ProceduralContext {
    const oracle::Scene* scene;
    std::atomic<uint64_t> calls{0};
};

// What an intersection shader for the box itself computes (as the fixture's query() does): the entry point of the
// object-space ray, clamped to tMin.
VkBool32 VKAPI_PTR intersectBox(void* user, const VkasAabbCandidate* c, float* tHit) {
    auto* ctx = static_cast<ProceduralContext*>(user);
    ++ctx->calls;
    const oracle::Aabb& box = ctx->scene->instances.at(size_t(c->instanceId))
                                  .blas->geometries.at(size_t(c->geometryIndex))
                                  .aabbs.at(size_t(c->primitiveIndex));
    double t0, t1;
    const oracle::Vec3 o{c->objectRayOrigin[0], c->objectRayOrigin[1], c->objectRayOrigin[2]};
    const oracle::Vec3 d{c->objectRayDirection[0], c->objectRayDirection[1], c->objectRayDirection[2]};
    if (!oracle::boxInterval(o, d, box.lo, box.hi, t0, t1)) return VK_FALSE;
    const double entry = std::max(t0, double(c->tMin));
    if (!(entry <= double(c->tMax)) || t1 < double(c->tMin)) return VK_FALSE;
    *tHit = float(entry);
    return VK_TRUE;
}
}  // namespace

TEST_P(procedural_geometry_mixed, batch_procedural_matches_ray_queries) {
    const uint32_t flags = GetParam() & ~uint32_t(VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT);
    AccelStruct* tlas = mixedScene();
    auto rays = randomRays(*tlas->scene, 400);
    const auto t = targetedRays(*tlas->scene, 400);
    rays.insert(rays.end(), t.begin(), t.end());
    std::vector<VkasRay> batch;
    for (const auto& r : rays) batch.push_back({{r.origin[0], r.origin[1], r.origin[2]}, r.tMin,
                                                {r.direction[0], r.direction[1], r.direction[2]}, r.tMax});
    for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
        ProceduralContext ctx{tlas->scene.get()};
        std::vector<VkasHit> out(batch.size());
        ASSERT_EQ(vkasTraceRaysProcedural(device, tlas->handle, mode, flags, 0xFF, uint32_t(batch.size()), batch.data(),
                                          out.data(), intersectBox, &ctx),
                  VK_SUCCESS);
        const uint32_t queryFlags = flags | (mode == VKAS_TRACE_MODE_ANY_HIT ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0u);
        size_t generated = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            // The ray query with the same step, checked against the oracle by checkRays in random_scene.
            const QueryTrace tr = query(tlas->handle, rays[i], queryFlags, 0xFF, Confirm::All, tlas->scene.get());
            ASSERT_EQ(tr.problems, "") << describe(rays[i]);
            const Hit got = fromBatch(out[i]);
            ASSERT_TRUE(identical(got, tr.committed))
                << "mode " << mode << " " << describe(rays[i]) << "\n  batch " << got.str() << "\n  query "
                << tr.committed.str() << "\n  seed " << seed;
            generated += out[i].type == VKAS_COMMITTED_INTERSECTION_GENERATED;
        }
        if (!(flags & VKAS_RAY_FLAG_SKIP_AABBS)) {
            EXPECT_GT(ctx.calls.load(), 0u);
            EXPECT_GT(generated, 0u) << "mode " << mode;
        } else {
            EXPECT_EQ(ctx.calls.load(), 0u);
        }
    }
    // Without a callback, AABBs never hit (as in vkasTraceRays).
    std::vector<VkasHit> a(batch.size()), b(batch.size());
    ASSERT_EQ(vkasTraceRaysProcedural(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, flags, 0xFF,
                                      uint32_t(batch.size()), batch.data(), a.data(), nullptr, nullptr),
              VK_SUCCESS);
    ASSERT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, flags, 0xFF, uint32_t(batch.size()),
                            batch.data(), b.data()),
              VK_SUCCESS);
    for (size_t i = 0; i < batch.size(); ++i) {
        EXPECT_TRUE(identical(fromBatch(a[i]), fromBatch(b[i])));
        EXPECT_NE(a[i].type, VKAS_COMMITTED_INTERSECTION_GENERATED);
    }
    EXPECT_TRUE(takeValidationErrors().empty());
}
