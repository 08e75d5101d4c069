// The hits of structure format 1, pinned (tests/data/format1_hits/). Each reference file holds one scene (its build
// inputs: bottom levels of triangle geometries under a top level, with their build flags and updates), a set of
// rays, the ray-flag / cull-mask passes traced over them, and the committed hit of every ray of every pass under four
// ways of tracing: vkasTraceRays CLOSEST_HIT, vkasTraceRays ANY_HIT (terminate on first hit), a ray query that
// confirms every candidate and one that confirms none. The files were written by this test (writer mode, below)
// from the last commit of format 1; tests/data/format1_hits/README.md names it.
//
// The test rebuilds each scene from the inputs stored in its file (so the generators below, the standard library's
// distributions and libm matter only when writing), traces the stored rays the same four ways and compares with the
// file. A ray passes when its answer is bit-identical (type, instance, geometry and primitive index, t and
// barycentrics as float bits, front face). A differing answer passes only when it is a tie, decided by the
// double-precision oracle (support/oracle.hpp):
//   - closest hit: both answers are hits of different primitives, the oracle has both as candidates, and their t
//     (the oracle's, and the two float answers) agree within kTieRelative of the coordinates' magnitude: a shared
//     edge or vertex, duplicated instances, coplanar duplicated geometries; the new answer must also pass the
//     suite's closest-hit check (matchesClosest);
//   - first hit (ANY_HIT, or TERMINATE_ON_FIRST_HIT in the pass): both answers are hits, and the new one is an oracle
//     candidate with t in [tMin, tMax] that passes matchesAnyHit.
// A hit that became a miss (or the reverse), or the same primitive with other bits, is never a tie. Each failure
// prints the scene, its seed, the pass, the method, the ray in hex floats and both answers. Nothing here is random
// when comparing: the fixture's VKAS_TEST_SEED line is the suite's usual one and changes nothing.
// VKAS_FORMAT1_HITS_VERBOSE=1 prints every accepted tie.
//
// Writer mode: VKAS_WRITE_FORMAT1_HITS=<dir> vkas_test_format1_hits  builds the scenes from their generators (fixed
// seeds, kScenes below), makes the rays, traces them, checks every answer against the oracle, and writes
// <dir>/<scene>.bin instead of comparing.
#include <algorithm>
#include <array>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "engine/format/layout.hpp"  // the structure format this build writes, for the messages
#include "meshes.hpp"

#ifndef VKAS_TEST_DATA_DIR
#define VKAS_TEST_DATA_DIR "tests/data"
#endif

using namespace vt;

namespace {

// ---- What a reference file holds --------------------------------------------------------------------------------
struct GeometryDesc {
    uint32_t flags = 0;  // VkGeometryFlagsKHR
    uint32_t indexType = VK_INDEX_TYPE_UINT32;
    Mesh mesh;  // positions and indices (NONE: makeGeometry expands the indices)
    bool hasTransform = false;
    VkTransformMatrixKHR transform{};
};
struct BlasDesc {
    uint32_t buildFlags = 0;
    std::vector<GeometryDesc> geometries;
    std::vector<GeometryDesc> update;  // empty: none; else the inputs of an in-place MODE_UPDATE after the build
};
struct InstanceDesc {
    VkTransformMatrixKHR transform = identityTransform();
    uint32_t customIndex = 0, mask = 0xFF, sbtOffset = 0, flags = 0;
    int32_t blas = -1;  // -1: inactive (reference 0)
};
struct SceneDesc {
    uint32_t tlasFlags = 0;
    std::vector<BlasDesc> blases;
    std::vector<InstanceDesc> instances;
    std::vector<InstanceDesc> update;  // empty: none; else the instances of a MODE_UPDATE into a new structure
};

enum RayKind : uint8_t { kRandom, kTargeted, kVertex, kEdge, kWindow, kRayKindCount };
const char* const kRayKindNames[kRayKindCount] = {"random", "targeted", "at a vertex", "at an edge", "tMin/tMax window"};

struct Pass {
    uint32_t flags = 0, cullMask = 0xFF;
    uint32_t first = 0, step = 1;  // the rays first, first + step, ...
};

enum Method : uint32_t { kBatchClosest, kBatchAnyHit, kQueryAll, kQueryNone, kMethodCount };
const char* const kMethodNames[kMethodCount] = {"vkasTraceRays CLOSEST_HIT", "vkasTraceRays ANY_HIT",
                                                "ray query, every candidate confirmed",
                                                "ray query, no candidate confirmed"};

// One committed answer, as stored. A miss is all zero.
struct Rec {
    uint32_t type = 0;
    bool frontFace = false;
    uint32_t instanceId = 0, geometryIndex = 0, primitiveIndex = 0;
    uint32_t t = 0, b0 = 0, b1 = 0;  // float bits
    bool operator==(const Rec&) const = default;
};
uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}
float fromBits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
Rec toRec(const Hit& h) {
    Rec r;
    if (h.type == VKAS_COMMITTED_INTERSECTION_NONE) return r;
    r.type = h.type;
    r.frontFace = h.frontFace;
    r.instanceId = uint32_t(h.instanceId);
    r.geometryIndex = uint32_t(h.geometryIndex);
    r.primitiveIndex = uint32_t(h.primitiveIndex);
    r.t = bits(h.t);
    r.b0 = bits(h.bary[0]);
    r.b1 = bits(h.bary[1]);
    return r;
}
std::string str(const Rec& r) {
    if (r.type == 0) return "miss";
    char buf[256];
    std::snprintf(buf, sizeof buf, "type %u instance %u geometry %u primitive %u t %a (%.9g) bary (%a, %a) %s", r.type,
                  r.instanceId, r.geometryIndex, r.primitiveIndex, fromBits(r.t), fromBits(r.t), fromBits(r.b0),
                  fromBits(r.b1), r.frontFace ? "front" : "back");
    return buf;
}

struct SceneFile {
    uint32_t fileVersion = 0, structureFormat = 0;
    std::string name;
    uint64_t seed = 0;
    SceneDesc scene;
    std::vector<uint8_t> kinds;  // per ray
    std::vector<oracle::Ray> rays;
    std::vector<Pass> passes;
    // hits[p][k][m]: pass p, its k-th ray, method m
    std::vector<std::vector<std::array<Rec, kMethodCount>>> hits;
};

// ---- The file format (little-endian) ----------------------------------------------------------------------------
//   "VKASF1H\n", u32 file version (1), u32 structure format the hits were traced with, u32 offset of the hits
//   section, str name, u64 seed, the scene, the rays, the passes, the hits, "END\n".
//   str: u32 length + bytes. Scene: u32 tlasFlags, u32 blasCount, per blas {u32 buildFlags, geometries, u8 hasUpdate,
//   [geometries]}, instances, u8 hasUpdate, [instances]. Geometries: u32 count, per geometry {u32 flags, u32
//   indexType, u32 vertexCount, f32 xyz per vertex, u32 indexCount, u32 per index, u8 hasTransform, [12 f32]}.
//   Instances: u32 count, per instance {12 f32, u32 customIndex, mask, sbtOffset, flags, i32 blas}.
//   Rays: u32 count, per ray {u8 kind, f32 origin xyz, tMin, direction xyz, tMax}. Passes: u32 count, per pass
//   {u32 flags, cullMask, first, step}.
//   Hits: for each pass, each of its rays, each method, a tag byte: 0 miss; 1 + m: the same as method m of this ray
//   (m < this method); 0x80 | (front face ? 0x40 : 0) | type: a hit, then varint instance, geometry and primitive
//   index, u32 t, u32 barycentric 0, u32 barycentric 1 (float bits).
constexpr char kMagic[8] = {'V', 'K', 'A', 'S', 'F', '1', 'H', '\n'};
constexpr char kEnd[4] = {'E', 'N', 'D', '\n'};
constexpr uint32_t kFileVersion = 1;

struct ByteWriter {
    std::vector<uint8_t> b;
    void u8(uint8_t v) { b.push_back(v); }
    void u32(uint32_t v) {
        for (int k = 0; k < 4; ++k) b.push_back(uint8_t(v >> (8 * k)));
    }
    void u64(uint64_t v) {
        for (int k = 0; k < 8; ++k) b.push_back(uint8_t(v >> (8 * k)));
    }
    void f32(float f) { u32(bits(f)); }
    void var(uint32_t v) {
        while (v >= 0x80) b.push_back(uint8_t(v | 0x80)), v >>= 7;
        b.push_back(uint8_t(v));
    }
    void raw(const char* p, size_t n) { b.insert(b.end(), p, p + n); }
    void str(const std::string& s) {
        u32(uint32_t(s.size()));
        raw(s.data(), s.size());
    }
};

// Every read is bounds-checked: the first problem is kept (with its offset) and later reads return zeros.
struct ByteReader {
    const std::vector<uint8_t>& b;
    size_t pos = 0;
    std::string error;
    explicit ByteReader(const std::vector<uint8_t>& bytes) : b(bytes) {}
    bool ok() const { return error.empty(); }
    bool fail(const std::string& why) {
        if (error.empty()) error = why + " (at byte " + std::to_string(pos) + " of " + std::to_string(b.size()) + ")";
        return false;
    }
    bool need(size_t n, const char* what) {
        if (!ok()) return false;
        if (b.size() - pos < n) return fail(std::string("the file ends inside ") + what);
        return true;
    }
    uint8_t u8(const char* what) { return need(1, what) ? b[pos++] : 0; }
    uint32_t u32(const char* what) {
        if (!need(4, what)) return 0;
        uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v |= uint32_t(b[pos++]) << (8 * k);
        return v;
    }
    uint64_t u64(const char* what) {
        if (!need(8, what)) return 0;
        uint64_t v = 0;
        for (int k = 0; k < 8; ++k) v |= uint64_t(b[pos++]) << (8 * k);
        return v;
    }
    float f32(const char* what) { return fromBits(u32(what)); }
    uint32_t var(const char* what) {
        uint32_t v = 0;
        for (int shift = 0; shift < 35; shift += 7) {
            const uint8_t byte = u8(what);
            if (!ok()) return 0;
            v |= uint32_t(byte & 0x7F) << shift;
            if (!(byte & 0x80)) return v;
        }
        fail(std::string("an overlong varint in ") + what);
        return 0;
    }
    // A count of items of at least minBytes bytes each: never more than the bytes left can hold.
    uint32_t count(size_t minBytes, const char* what) {
        const uint32_t n = u32(what);
        if (ok() && uint64_t(n) * minBytes > b.size() - pos) {
            fail(std::string("a count of ") + std::to_string(n) + " " + what + " that the file cannot hold");
            return 0;
        }
        return n;
    }
    bool expect(const char* bytes, size_t n, const char* what) {
        if (!need(n, what)) return false;
        if (std::memcmp(b.data() + pos, bytes, n) != 0) return fail(std::string("no ") + what);
        pos += n;
        return true;
    }
};

void writeTransform(ByteWriter& w, const VkTransformMatrixKHR& m) {
    for (const auto& row : m.matrix)
        for (float v : row) w.f32(v);
}
VkTransformMatrixKHR readTransform(ByteReader& r) {
    VkTransformMatrixKHR m{};
    for (auto& row : m.matrix)
        for (float& v : row) v = r.f32("a transform");
    return m;
}

void writeGeometries(ByteWriter& w, const std::vector<GeometryDesc>& gs) {
    w.u32(uint32_t(gs.size()));
    for (const GeometryDesc& g : gs) {
        w.u32(g.flags);
        w.u32(g.indexType);
        w.u32(uint32_t(g.mesh.positions.size()));
        for (const Float3& p : g.mesh.positions)
            for (float v : p) w.f32(v);
        w.u32(uint32_t(g.mesh.indices.size()));
        for (uint32_t i : g.mesh.indices) w.u32(i);
        w.u8(g.hasTransform);
        if (g.hasTransform) writeTransform(w, g.transform);
    }
}
std::vector<GeometryDesc> readGeometries(ByteReader& r) {
    std::vector<GeometryDesc> gs(r.count(17, "geometries"));
    for (GeometryDesc& g : gs) {
        g.flags = r.u32("geometry flags");
        g.indexType = r.u32("an index type");
        if (r.ok() && g.indexType != VK_INDEX_TYPE_NONE_KHR && g.indexType != VK_INDEX_TYPE_UINT16 &&
            g.indexType != VK_INDEX_TYPE_UINT32)
            r.fail("an unknown index type " + std::to_string(g.indexType));
        if (r.ok() && (g.flags & ~uint32_t(VK_GEOMETRY_OPAQUE_BIT_KHR | VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR)))
            r.fail("unknown geometry flags");
        g.mesh.positions.resize(r.count(12, "vertices"));
        for (Float3& p : g.mesh.positions)
            for (float& v : p) v = r.f32("vertices");
        g.mesh.indices.resize(r.count(4, "indices"));
        for (uint32_t& i : g.mesh.indices) i = r.u32("indices");
        if (!r.ok()) return {};
        if (g.mesh.indices.size() % 3 != 0) r.fail("an index count that is not a multiple of 3");
        for (uint32_t i : g.mesh.indices)
            if (i >= g.mesh.positions.size()) r.fail("an index past the vertices");
        if (g.indexType == VK_INDEX_TYPE_UINT16 && g.mesh.positions.size() > 65536) r.fail("too many vertices for UINT16");
        g.hasTransform = r.u8("a transform flag") != 0;
        if (g.hasTransform) g.transform = readTransform(r);
    }
    return r.ok() ? gs : std::vector<GeometryDesc>{};
}

void writeInstances(ByteWriter& w, const std::vector<InstanceDesc>& is) {
    w.u32(uint32_t(is.size()));
    for (const InstanceDesc& in : is) {
        writeTransform(w, in.transform);
        w.u32(in.customIndex);
        w.u32(in.mask);
        w.u32(in.sbtOffset);
        w.u32(in.flags);
        w.u32(uint32_t(in.blas));
    }
}
std::vector<InstanceDesc> readInstances(ByteReader& r, size_t blasCount) {
    std::vector<InstanceDesc> is(r.count(68, "instances"));
    for (InstanceDesc& in : is) {
        in.transform = readTransform(r);
        in.customIndex = r.u32("an instance");
        in.mask = r.u32("an instance");
        in.sbtOffset = r.u32("an instance");
        in.flags = r.u32("an instance");
        in.blas = int32_t(r.u32("an instance"));
        if (r.ok() && (in.customIndex > 0xFFFFFF || in.mask > 0xFF || in.sbtOffset > 0xFFFFFF || in.flags > 0xF ||
                       in.blas < -1 || in.blas >= int32_t(blasCount)))
            r.fail("an instance with fields out of range");
    }
    return r.ok() ? is : std::vector<InstanceDesc>{};
}

std::vector<uint8_t> encode(const SceneFile& f) {
    ByteWriter w;
    w.raw(kMagic, 8);
    w.u32(kFileVersion);
    w.u32(f.structureFormat);
    const size_t hitsOffsetAt = w.b.size();
    w.u32(0);
    w.str(f.name);
    w.u64(f.seed);
    w.u32(f.scene.tlasFlags);
    w.u32(uint32_t(f.scene.blases.size()));
    for (const BlasDesc& b : f.scene.blases) {
        w.u32(b.buildFlags);
        writeGeometries(w, b.geometries);
        w.u8(!b.update.empty());
        if (!b.update.empty()) writeGeometries(w, b.update);
    }
    writeInstances(w, f.scene.instances);
    w.u8(!f.scene.update.empty());
    if (!f.scene.update.empty()) writeInstances(w, f.scene.update);
    w.u32(uint32_t(f.rays.size()));
    for (size_t i = 0; i < f.rays.size(); ++i) {
        const oracle::Ray& ray = f.rays[i];
        w.u8(f.kinds[i]);
        for (float v : ray.origin) w.f32(v);
        w.f32(ray.tMin);
        for (float v : ray.direction) w.f32(v);
        w.f32(ray.tMax);
    }
    w.u32(uint32_t(f.passes.size()));
    for (const Pass& p : f.passes) {
        w.u32(p.flags);
        w.u32(p.cullMask);
        w.u32(p.first);
        w.u32(p.step);
    }
    const uint32_t hitsOffset = uint32_t(w.b.size());
    for (int k = 0; k < 4; ++k) w.b[hitsOffsetAt + k] = uint8_t(hitsOffset >> (8 * k));
    for (const auto& pass : f.hits)
        for (const auto& recs : pass)
            for (uint32_t m = 0; m < kMethodCount; ++m) {
                const Rec& r = recs[m];
                if (r.type == 0) {
                    w.u8(0);
                    continue;
                }
                uint32_t same = 0;
                while (same < m && !(recs[same] == r)) ++same;
                if (same < m) {
                    w.u8(uint8_t(1 + same));
                    continue;
                }
                w.u8(uint8_t(0x80 | (r.frontFace ? 0x40 : 0) | r.type));
                w.var(r.instanceId);
                w.var(r.geometryIndex);
                w.var(r.primitiveIndex);
                w.u32(r.t);
                w.u32(r.b0);
                w.u32(r.b1);
            }
    w.raw(kEnd, 4);
    return w.b;
}

// Parses a whole reference file; on any problem returns false with a message (never reads out of bounds).
bool decode(const std::vector<uint8_t>& bytes, SceneFile& f, std::string& error) {
    ByteReader r(bytes);
    f = SceneFile{};
    r.expect(kMagic, 8, "magic \"VKASF1H\" at the start");
    f.fileVersion = r.u32("the header");
    if (r.ok() && f.fileVersion != kFileVersion) r.fail("file version " + std::to_string(f.fileVersion) + ", expected 1");
    f.structureFormat = r.u32("the header");
    const uint32_t hitsOffset = r.u32("the header");
    const uint32_t nameLength = r.count(1, "name bytes");
    if (r.need(nameLength, "the name")) {
        f.name.assign(reinterpret_cast<const char*>(bytes.data() + r.pos), nameLength);
        r.pos += nameLength;
    }
    f.seed = r.u64("the seed");
    f.scene.tlasFlags = r.u32("the scene");
    f.scene.blases.resize(r.count(9, "bottom levels"));
    for (BlasDesc& b : f.scene.blases) {
        b.buildFlags = r.u32("a bottom level");
        b.geometries = readGeometries(r);
        if (r.u8("an update flag")) {
            b.update = readGeometries(r);
            if (r.ok() && b.update.size() != b.geometries.size()) r.fail("an update with another geometry count");
            for (size_t g = 0; r.ok() && g < b.update.size(); ++g)
                if (b.update[g].mesh.indices != b.geometries[g].mesh.indices ||
                    b.update[g].indexType != b.geometries[g].indexType || b.update[g].flags != b.geometries[g].flags ||
                    b.update[g].hasTransform != b.geometries[g].hasTransform ||
                    b.update[g].mesh.positions.size() != b.geometries[g].mesh.positions.size())
                    r.fail("an update that changes more than vertices and transforms");
        }
    }
    f.scene.instances = readInstances(r, f.scene.blases.size());
    if (r.u8("an update flag")) {
        f.scene.update = readInstances(r, f.scene.blases.size());
        if (r.ok() && f.scene.update.size() != f.scene.instances.size()) r.fail("an instance update with another count");
        for (size_t i = 0; r.ok() && i < f.scene.update.size(); ++i)
            if ((f.scene.update[i].blas < 0) != (f.scene.instances[i].blas < 0))
                r.fail("an instance update that changes whether an instance is active");
    }
    const uint32_t rayCount = r.count(33, "rays");
    f.rays.resize(rayCount);
    f.kinds.resize(rayCount);
    for (uint32_t i = 0; i < rayCount && r.ok(); ++i) {
        f.kinds[i] = r.u8("a ray");
        if (r.ok() && f.kinds[i] >= kRayKindCount) r.fail("an unknown ray kind");
        oracle::Ray& ray = f.rays[i];
        for (float& v : ray.origin) v = r.f32("a ray");
        ray.tMin = r.f32("a ray");
        for (float& v : ray.direction) v = r.f32("a ray");
        ray.tMax = r.f32("a ray");
    }
    f.passes.resize(r.count(16, "passes"));
    for (Pass& p : f.passes) {
        p.flags = r.u32("a pass");
        p.cullMask = r.u32("a pass");
        p.first = r.u32("a pass");
        p.step = r.u32("a pass");
        if (r.ok() && (p.step == 0 || p.first >= p.step || p.cullMask > 0xFF || p.flags > 0x3FF))
            r.fail("a pass with fields out of range");
    }
    if (r.ok() && r.pos != hitsOffset) r.fail("the hits section is not where the header says");
    f.hits.resize(f.passes.size());
    for (size_t p = 0; p < f.passes.size() && r.ok(); ++p) {
        const Pass& pass = f.passes[p];
        const size_t n = rayCount > pass.first ? (rayCount - pass.first + pass.step - 1) / pass.step : 0;
        if (n * kMethodCount > r.b.size() - r.pos) r.fail("a pass with more rays than the file has hits");
        f.hits[p].resize(r.ok() ? n : 0);
        for (auto& recs : f.hits[p]) {
            for (uint32_t m = 0; m < kMethodCount && r.ok(); ++m) {
                const uint8_t tag = r.u8("the hits");
                Rec& rec = recs[m];
                if (tag == 0) continue;
                if (tag < 0x80) {
                    if (uint32_t(tag - 1) >= m) r.fail("a hit that refers to a later method");
                    else rec = recs[tag - 1];
                    continue;
                }
                rec.type = tag & 0x0F;
                rec.frontFace = tag & 0x40;
                if ((tag & 0x30) || (rec.type != VKAS_COMMITTED_INTERSECTION_TRIANGLE)) r.fail("a hit with an unknown tag");
                rec.instanceId = r.var("a hit");
                rec.geometryIndex = r.var("a hit");
                rec.primitiveIndex = r.var("a hit");
                rec.t = r.u32("a hit");
                rec.b0 = r.u32("a hit");
                rec.b1 = r.u32("a hit");
            }
            if (!r.ok()) break;
        }
    }
    r.expect(kEnd, 4, "end marker \"END\" (the file is truncated or damaged)");
    if (r.ok() && r.pos != bytes.size()) r.fail("bytes after the end marker");
    error = r.error;
    return r.ok();
}

bool readFile(const std::string& path, std::vector<uint8_t>& out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return true;
}

// ---- The scenes (generators: used only when writing) -----------------------------------------------------------
constexpr VkBuildAccelerationStructureFlagsKHR kFastTrace = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
constexpr VkBuildAccelerationStructureFlagsKHR kFastBuild = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
constexpr VkBuildAccelerationStructureFlagsKHR kAllowUpdate = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
constexpr uint32_t kOpaque = VK_GEOMETRY_OPAQUE_BIT_KHR;
constexpr uint32_t kCullDisable = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
constexpr uint32_t kFlip = VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR;
constexpr uint32_t kForceOpaque = VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR;
constexpr uint32_t kForceNoOpaque = VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR;

GeometryDesc geometry(Mesh mesh, uint32_t indexType, uint32_t flags, const VkTransformMatrixKHR* transform = nullptr) {
    GeometryDesc g;
    g.mesh = std::move(mesh);
    g.indexType = indexType;
    g.flags = flags;
    if (transform) g.hasTransform = true, g.transform = *transform;
    return g;
}
InstanceDesc instance(int32_t blas, const VkTransformMatrixKHR& t, uint32_t flags = 0, uint32_t mask = 0xFF,
                      uint32_t customIndex = 0, uint32_t sbtOffset = 0) {
    InstanceDesc in;
    in.blas = blas;
    in.transform = t;
    in.flags = flags;
    in.mask = mask;
    in.customIndex = customIndex;
    in.sbtOffset = sbtOffset;
    return in;
}
Mesh deformed(const Mesh& m, Rng& rng, float amount) {
    Mesh out = m;
    for (auto& p : out.positions)
        for (float& c : p) c += rng.uniformf(-amount, amount);
    return out;
}

struct SceneSpec {
    const char* name;
    uint64_t seed;
    const char* what;
};
void PrintTo(const SceneSpec& spec, std::ostream* os) { *os << spec.name; }

// The fixed seeds. Changing one (or a generator) changes nothing until the files are written again.
const SceneSpec kScenes[] = {
    {"instances_mixed", 0x1F0A'7001, "soups, a sphere, a transformed grid, a torus knot; 10 instances: rotated, "
                                     "scaled, mirrored, every instance flag, masks, an inactive one, a duplicate; "
                                     "default (SAH) builds"},
    {"closed_meshes_fast_trace", 0x1F0A'7002, "closed meshes with shared edges (icosphere, torus knot), a closed fan and "
                                              "a watertight tessellation; PREFER_FAST_TRACE"},
    {"grid_terrain_fast_build", 0x1F0A'7003, "a 32x32 grid at integer coordinates (exact vertex and edge rays) and a "
                                             "terrain, under exact and rotated transforms; PREFER_FAST_BUILD"},
    {"many_geometries", 0x1F0A'7004, "bottom levels of 12 and 6 geometries: index types, geometry transforms, mixed "
                                     "opacity, coplanar duplicates, inactive and degenerate triangles"},
    {"update_before", 0x1F0A'7005, "ALLOW_UPDATE bottom levels (default, PREFER_FAST_BUILD, PREFER_FAST_TRACE) and "
                                   "top level, as built"},
    {"update_after", 0x1F0A'7005, "the same scene after MODE_UPDATE: moved vertices and a new geometry transform "
                                  "(in place), new instance transforms, masks and ids (into a new structure)"},
};

SceneDesc generate(const std::string& name, uint64_t seed) {
    Rng rng(seed);
    SceneDesc s;
    if (name == "instances_mixed") {
        const VkTransformMatrixKHR gridShrink = compose(translation(-0.75f, -0.75f, 0.3f), randomTransform(rng, 0.25f, 0.25f, false, 0.0f));
        s.blases.resize(3);
        s.blases[0].geometries.push_back(geometry(triangleSoup(500, rng, 0.2f), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[0].geometries.push_back(geometry(triangleSoup(300, rng, 0.25f), VK_INDEX_TYPE_NONE_KHR, 0));
        s.blases[1].geometries.push_back(geometry(icosphere(2), VK_INDEX_TYPE_UINT16, 0));
        s.blases[1].geometries.push_back(geometry(grid(6, 6), VK_INDEX_TYPE_UINT32, kOpaque, &gridShrink));
        s.blases[2].geometries.push_back(geometry(torusKnot(64, 8), VK_INDEX_TYPE_UINT32, kOpaque));
        const VkTransformMatrixKHR knot = randomTransform(rng, 0.8f, 1.5f, false, 2.5f);
        s.instances.push_back(instance(0, identityTransform(), 0, 0xFF, 0, 0));
        s.instances.push_back(instance(0, randomTransform(rng, 0.5f, 1.5f, false, 3.0f), 0, 0x0F, 0x123456, 7));
        s.instances.push_back(instance(1, randomTransform(rng, 0.6f, 1.4f, true, 3.0f), kFlip, 0xF0, 42, 1));
        s.instances.push_back(instance(1, randomTransform(rng, 0.6f, 1.4f, false, 3.0f), kCullDisable, 0x81, 43, 2));
        s.instances.push_back(instance(2, knot, kForceOpaque, 0x3C, 44, 3));
        s.instances.push_back(instance(2, randomTransform(rng, 0.5f, 1.2f, true, 3.0f), kForceNoOpaque, 0xFF, 45, 4));
        s.instances.push_back(instance(-1, identityTransform(), 0, 0xFF, 46, 5));
        s.instances.push_back(instance(2, knot, 0, 0xFF, 47, 6));  // the same as instance 4: every hit a tie
        s.instances.push_back(instance(0, randomTransform(rng, 0.2f, 3.0f, true, 3.0f), kFlip | kCullDisable, 0x01, 48, 8));
        s.instances.push_back(instance(1, translation(2.0f, -2.0f, 1.0f), 0, 0xFF, 49, 9));
    } else if (name == "closed_meshes_fast_trace") {
        s.tlasFlags = kFastTrace;
        s.blases.resize(3);
        for (auto& b : s.blases) b.buildFlags = kFastTrace;
        s.blases[0].geometries.push_back(geometry(icosphere(3), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[1].geometries.push_back(geometry(torusKnot(96, 10), VK_INDEX_TYPE_UINT16, 0));
        s.blases[2].geometries.push_back(geometry(closedFan(48, rng), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[2].geometries.push_back(
            geometry(randomSquareTessellation(300, rng, TessellationLimits{1000.0, 1e-5}), VK_INDEX_TYPE_UINT32, 0));
        s.instances.push_back(instance(0, identityTransform()));
        s.instances.push_back(instance(0, randomTransform(rng, 0.4f, 1.0f, true, 2.0f), 0, 0xFF, 1, 1));
        s.instances.push_back(instance(1, randomTransform(rng, 0.8f, 1.6f, false, 2.0f), 0, 0xFF, 2, 2));
        s.instances.push_back(instance(1, randomTransform(rng, 0.8f, 1.6f, true, 2.0f), kForceOpaque, 0x0F, 3, 3));
        s.instances.push_back(instance(2, randomTransform(rng, 1.0f, 2.0f, false, 2.0f), 0, 0xF0, 4, 4));
        s.instances.push_back(instance(2, randomTransform(rng, 1.0f, 2.0f, true, 2.0f), kCullDisable, 0xFF, 5, 5));
    } else if (name == "grid_terrain_fast_build") {
        s.tlasFlags = kFastBuild;
        s.blases.resize(2);
        for (auto& b : s.blases) b.buildFlags = kFastBuild;
        s.blases[0].geometries.push_back(geometry(grid(32, 32), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[1].geometries.push_back(geometry(terrain(24, rng), VK_INDEX_TYPE_UINT16, 0));
        VkTransformMatrixKHR quarterTurnMirror{};  // x' = -y + 64, y' = -x, z' = z - 0.5: exact in float
        quarterTurnMirror.matrix[0][1] = -1, quarterTurnMirror.matrix[0][3] = 64;
        quarterTurnMirror.matrix[1][0] = -1;
        quarterTurnMirror.matrix[2][2] = 1, quarterTurnMirror.matrix[2][3] = -0.5f;
        VkTransformMatrixKHR terrainScale = identityTransform();
        terrainScale.matrix[0][0] = terrainScale.matrix[1][1] = terrainScale.matrix[2][2] = 16;
        terrainScale.matrix[0][3] = terrainScale.matrix[1][3] = 16;
        s.instances.push_back(instance(0, identityTransform(), 0, 0xFF, 10, 0));
        s.instances.push_back(instance(0, translation(0.5f, 0.25f, -1.0f), kFlip, 0x0F, 11, 1));
        s.instances.push_back(instance(0, quarterTurnMirror, 0, 0xFF, 12, 2));
        s.instances.push_back(instance(1, terrainScale, 0, 0xF0, 13, 3));
        s.instances.push_back(instance(1, compose(translation(16, 16, 2), randomTransform(rng, 6.0f, 12.0f, false, 0.0f)),
                                       kForceOpaque, 0xFF, 14, 4));
    } else if (name == "many_geometries") {
        s.tlasFlags = kFastTrace;
        s.blases.resize(2);
        s.blases[1].buildFlags = kFastBuild;
        const uint32_t indexTypes[3] = {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32};
        for (int g = 0; g < 12; ++g) {
            const uint32_t it = indexTypes[g % 3], flags = g % 2 ? kOpaque : 0;
            if (g == 5) {  // geometry 4 again, coplanar, with the other opacity: ties within one bottom level
                GeometryDesc dup = s.blases[0].geometries[4];
                dup.flags = flags;
                s.blases[0].geometries.push_back(dup);
                continue;
            }
            if (g % 4 == 2) {
                const VkTransformMatrixKHR t = randomTransform(rng, 0.2f, 0.5f, rng.coin(), 1.0f);
                s.blases[0].geometries.push_back(geometry(grid(3 + g / 4, 3), it, flags, &t));
            } else {
                Mesh m = triangleSoup(40 + int(rng.below(80)), rng, 0.3f);
                if (g == 7) {  // two inactive triangles (NaN x) and a degenerate one
                    m.positions.push_back({std::numeric_limits<float>::quiet_NaN(), 0, 0});
                    m.indices[1] = m.indices[10] = uint32_t(m.positions.size() - 1);
                    m.indices[6] = m.indices[7] = m.indices[8];
                }
                const VkTransformMatrixKHR t = randomTransform(rng, 0.7f, 1.3f, false, 0.5f);
                s.blases[0].geometries.push_back(geometry(m, it, flags, g % 3 == 1 ? &t : nullptr));
            }
        }
        for (int g = 0; g < 6; ++g) {
            const VkTransformMatrixKHR t = randomTransform(rng, 0.3f, 0.8f, g % 2 == 0, 1.0f);
            s.blases[1].geometries.push_back(
                geometry(g % 2 ? icosphere(1) : triangleSoup(60, rng, 0.25f), indexTypes[(g + 1) % 3], g % 3 ? kOpaque : 0, &t));
        }
        s.instances.push_back(instance(0, identityTransform(), 0, 0xFF, 100, 0));
        s.instances.push_back(instance(1, identityTransform(), 0, 0xFF, 101, 1));
        s.instances.push_back(instance(0, randomTransform(rng, 0.5f, 1.5f, true, 2.5f), kFlip, 0x3C, 102, 2));
        s.instances.push_back(instance(1, randomTransform(rng, 0.5f, 1.5f, false, 2.5f), kForceNoOpaque, 0xC3, 103, 3));
        s.instances.push_back(instance(0, randomTransform(rng, 0.5f, 1.5f, false, 2.5f), kCullDisable, 0xFF, 104, 4));
    } else if (name == "update_before" || name == "update_after") {
        s.tlasFlags = kAllowUpdate;
        s.blases.resize(3);
        s.blases[0].buildFlags = kAllowUpdate;
        s.blases[1].buildFlags = kAllowUpdate | kFastBuild;
        s.blases[2].buildFlags = kAllowUpdate | kFastTrace;
        const VkTransformMatrixKHR sphereAt = randomTransform(rng, 0.4f, 0.6f, false, 0.5f);
        s.blases[0].geometries.push_back(geometry(triangleSoup(400, rng, 0.2f), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[0].geometries.push_back(geometry(icosphere(2), VK_INDEX_TYPE_UINT16, 0, &sphereAt));
        s.blases[1].geometries.push_back(geometry(terrain(20, rng), VK_INDEX_TYPE_UINT32, kOpaque));
        s.blases[2].geometries.push_back(geometry(torusKnot(48, 8), VK_INDEX_TYPE_NONE_KHR, 0));
        for (int i = 0; i < 7; ++i)
            s.instances.push_back(instance(i % 3, randomTransform(rng, 0.5f, 1.5f, i % 3 == 1, 2.5f),
                                           i == 4 ? kForceOpaque : i == 5 ? kFlip : 0, i == 3 ? 0x0F : 0xFF,
                                           uint32_t(200 + i), uint32_t(i)));
        s.instances.push_back(instance(-1, identityTransform(), 0, 0xFF, 207, 7));
        if (name == "update_after") {
            for (BlasDesc& b : s.blases)
                for (const GeometryDesc& g : b.geometries) {
                    GeometryDesc moved = g;
                    moved.mesh = deformed(g.mesh, rng, 0.1f);
                    if (g.hasTransform) moved.transform = randomTransform(rng, 0.4f, 0.6f, true, 0.5f);
                    b.update.push_back(moved);
                }
            s.update = s.instances;
            for (InstanceDesc& in : s.update) {
                in.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 2.5f);
                in.mask = rng.coin(0.7) ? 0xFF : rng.u32() & 0xFF;
                in.customIndex = rng.u32() & 0xFFFFFF;
            }
        }
    }
    return s;
}

// The passes every scene is traced with: all rays plainly, and each quarter of them under two of eight flag / cull
// mask variants.
std::vector<Pass> standardPasses() {
    return {
        {0, 0xFF, 0, 1},
        {VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES, 0xFF, 0, 4},
        {VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, 0xFF, 1, 4},
        {VKAS_RAY_FLAG_OPAQUE, 0x0F, 2, 4},
        {VKAS_RAY_FLAG_NO_OPAQUE, 0xFF, 3, 4},
        {VKAS_RAY_FLAG_CULL_OPAQUE, 0xF0, 0, 4},
        {VKAS_RAY_FLAG_CULL_NO_OPAQUE | VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES, 0xFF, 1, 4},
        {VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT, 0xFF, 2, 4},
        {VKAS_RAY_FLAG_NO_OPAQUE | VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT | VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, 0x3C, 3, 4},
    };
}

// How many rays of each kind a scene gets when written.
constexpr size_t kRandomRays = 600, kTargetedRays = 400, kVertexRays = 300, kEdgeRays = 300, kWindowRays = 200;

// Within this fraction of the magnitude of the coordinates (ray origin and hit point), two hits are at the same
// place: a tie. About 8 float ulps.
constexpr double kTieRelative = 1e-6;

oracle::Result opaqueOnly(const oracle::Result& r) {
    oracle::Result out;
    for (const oracle::Candidate& c : r.candidates)
        if (c.opaque) out.candidates.push_back(c);
    return out;
}

std::string oracleSummary(const oracle::Result& r) {
    std::vector<const oracle::Candidate*> v;
    for (const auto& c : r.candidates) v.push_back(&c);
    std::sort(v.begin(), v.end(), [](auto* a, auto* b) { return a->t < b->t; });
    std::ostringstream s;
    s << r.candidates.size() << " oracle candidate(s)";
    for (size_t i = 0; i < v.size() && i < 6; ++i) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "\n      t %.9g (tol %.2g) instance %d geometry %d primitive %d bary (%.6g %.6g) %s %s%s",
                      v[i]->t, v[i]->tTolerance, v[i]->instanceId, v[i]->geometryIndex, v[i]->primitiveIndex,
                      v[i]->bary[0], v[i]->bary[1], v[i]->frontFace ? "front" : "back",
                      v[i]->opaque ? "opaque" : "non-opaque", v[i]->optional ? " (optional)" : "");
        s << buf;
    }
    return s.str();
}

}  // namespace

// ---- The test ---------------------------------------------------------------------------------------------------
class format1_hits : public VkasTest, public ::testing::WithParamInterface<SceneSpec> {
  protected:
    std::vector<std::unique_ptr<GeometryData>> keep;

    AccelStruct* submitUpdate(PreparedBuild& pb, AccelStruct* src, AccelStruct* dst) {
        pb.info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb.info.srcAccelerationStructure = src->handle;
        pb.info.scratchData.hostAddress = nullptr;
        if (dst) {
            pb.as = dst;
            pb.info.dstAccelerationStructure = dst->handle;
        }
        submit({&pb});
        return pb.as;
    }
    std::vector<const GeometryData*> makeGeometries(const std::vector<GeometryDesc>& gs) {
        std::vector<const GeometryData*> out;
        for (const GeometryDesc& g : gs) {
            keep.push_back(makeGeometry(g.mesh, VkIndexType(g.indexType), g.flags, g.hasTransform ? &g.transform : nullptr));
            out.push_back(keep.back().get());
        }
        return out;
    }
    std::vector<Instance> makeInstances(const std::vector<InstanceDesc>& is, const std::vector<AccelStruct*>& blases) {
        std::vector<Instance> out;
        for (const InstanceDesc& d : is) {
            Instance in;
            in.transform = d.transform;
            in.customIndex = d.customIndex;
            in.mask = d.mask;
            in.sbtOffset = d.sbtOffset;
            in.flags = d.flags;
            in.blas = d.blas < 0 ? nullptr : blases[size_t(d.blas)];
            out.push_back(in);
        }
        return out;
    }
    // Builds (and updates) the scene through the Vulkan commands; the oracle's view comes with it.
    AccelStruct* buildScene(const SceneDesc& s) {
        std::vector<AccelStruct*> blases;
        for (const BlasDesc& b : s.blases) {
            BuildOptions opt;
            opt.flags = b.buildFlags;
            AccelStruct* as = buildBlas(makeGeometries(b.geometries), opt);
            if (!b.update.empty()) {
                auto pb = prepareBlas(makeGeometries(b.update), opt);
                as = submitUpdate(*pb, as, as);  // in place
            }
            blases.push_back(as);
        }
        BuildOptions opt;
        opt.flags = s.tlasFlags;
        AccelStruct* tlas = buildTlas(makeInstances(s.instances, blases), opt);
        if (!s.update.empty()) {
            auto pb = prepareTlas(makeInstances(s.update, blases), opt);
            tlas = submitUpdate(*pb, tlas, nullptr);  // into a new structure
        }
        return tlas;
    }

    // Every pass, every method: the committed answers.
    std::vector<std::vector<std::array<Hit, kMethodCount>>> traceAll(const AccelStruct* tlas,
                                                                      const std::vector<oracle::Ray>& rays,
                                                                      const std::vector<Pass>& passes) {
        std::vector<std::vector<std::array<Hit, kMethodCount>>> out(passes.size());
        for (size_t p = 0; p < passes.size(); ++p) {
            const Pass& pass = passes[p];
            std::vector<VkasRay> batch;
            std::vector<size_t> index;
            for (size_t i = pass.first; i < rays.size(); i += pass.step) {
                VkasRay r{};
                for (int k = 0; k < 3; ++k) r.origin[k] = rays[i].origin[k], r.direction[k] = rays[i].direction[k];
                r.tMin = rays[i].tMin;
                r.tMax = rays[i].tMax;
                batch.push_back(r);
                index.push_back(i);
            }
            out[p].resize(batch.size());
            for (Method m : {kBatchClosest, kBatchAnyHit}) {
                std::vector<VkasHit> hits(batch.size());
                EXPECT_EQ(vkasTraceRays(device, tlas->handle, m == kBatchClosest ? VKAS_TRACE_MODE_CLOSEST_HIT : VKAS_TRACE_MODE_ANY_HIT,
                                        pass.flags, pass.cullMask, uint32_t(batch.size()), batch.data(), hits.data()),
                          VK_SUCCESS);
                for (size_t k = 0; k < batch.size(); ++k) out[p][k][m] = fromBatch(hits[k]);
            }
            for (size_t k = 0; k < batch.size(); ++k) {
                for (Method m : {kQueryAll, kQueryNone}) {
                    const QueryTrace tr = query(tlas->handle, rays[index[k]], pass.flags, pass.cullMask,
                                                m == kQueryAll ? Confirm::All : Confirm::None, tlas->scene.get());
                    EXPECT_EQ(tr.problems, "") << describe(rays[index[k]]);
                    out[p][k][m] = tr.committed;
                }
            }
        }
        return out;
    }

    // What the oracle says the method may commit for the ray, and whether the method stops at the first hit.
    oracle::Result expectedFor(const AccelStruct* tlas, const oracle::Ray& ray, const Pass& pass, Method m, bool& firstHit) {
        const uint32_t flags = pass.flags | (m == kBatchAnyHit ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0u);
        firstHit = flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT;
        const oracle::Result ex = oracle::trace(*tlas->scene, ray, flags, pass.cullMask);
        return m == kQueryNone ? opaqueOnly(ex) : ex;  // without confirmation only opaque candidates commit
    }

    // Writer mode: the rays of a scene (kinds in `kinds`).
    std::vector<oracle::Ray> makeRays(const AccelStruct* tlas, std::vector<uint8_t>& kinds);
    void write(const SceneSpec& spec, const std::string& dir);
    void compare(const SceneSpec& spec, const std::string& path);
};

std::vector<oracle::Ray> format1_hits::makeRays(const AccelStruct* tlas, std::vector<uint8_t>& kinds) {
    const oracle::Scene& scene = *tlas->scene;
    std::vector<oracle::Ray> rays;
    auto add = [&](const std::vector<oracle::Ray>& more, RayKind kind) {
        rays.insert(rays.end(), more.begin(), more.end());
        kinds.insert(kinds.end(), more.size(), uint8_t(kind));
    };
    add(randomRays(scene, kRandomRays), kRandom);
    add(targetedRays(scene, kTargetedRays), kTargeted);
    // Rays through a vertex or an edge point of a random active triangle: from a random direction, or along an axis
    // (then the origin is the point moved by a power of two along the axis, exact for the grid at integer
    // coordinates under its identity instance).
    auto aimed = [&](size_t count, bool edge) {
        std::vector<oracle::Ray> out;
        size_t guard = 0;
        while (out.size() < count && ++guard < 100 * count) {
            const auto& inst = scene.instances[rng.below(uint32_t(scene.instances.size()))];
            if (!inst.blas) continue;
            const auto& geoms = inst.blas->geometries;
            const auto& geom = geoms[rng.below(uint32_t(geoms.size()))];
            if (geom.triangles.empty()) continue;
            const oracle::Triangle& tri = geom.triangles[rng.below(uint32_t(geom.triangles.size()))];
            if (!tri.active) continue;
            const int k = int(rng.below(3));
            const double s = edge ? (rng.coin() ? 0.5 : rng.uniform(0, 1)) : 0.0;
            double p[3], w[3];
            for (int c = 0; c < 3; ++c) p[c] = tri.v[k][c] + s * (tri.v[(k + 1) % 3][c] - tri.v[k][c]);
            for (int r = 0; r < 3; ++r)
                w[r] = inst.toWorld[r][0] * p[0] + inst.toWorld[r][1] * p[1] + inst.toWorld[r][2] * p[2] + inst.toWorld[r][3];
            if (!std::isfinite(w[0]) || !std::isfinite(w[1]) || !std::isfinite(w[2])) continue;
            oracle::Ray ray;
            ray.tMin = 0;
            ray.tMax = std::numeric_limits<float>::infinity();
            if (rng.coin()) {
                const int axis = int(rng.below(3));
                const float sign = rng.coin() ? 1.0f : -1.0f, dist = float(1 << rng.below(3));
                for (int c = 0; c < 3; ++c) ray.origin[c] = float(w[c]), ray.direction[c] = 0;
                ray.direction[axis] = -sign;
                ray.origin[axis] = float(w[axis]) + sign * dist;
            } else {
                double d[3], len;
                do {
                    for (double& x : d) x = rng.uniform(-1, 1);
                    len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                } while (len > 1 || len < 0.1);
                const double dist = rng.uniform(0.5, 3.0), scale = std::exp(rng.uniform(-1.0, 1.0));
                for (int c = 0; c < 3; ++c) {
                    ray.origin[c] = float(w[c] + d[c] / len * dist);
                    ray.direction[c] = float(-d[c] / len * scale);
                }
            }
            out.push_back(ray);
        }
        return out;
    };
    add(aimed(kVertexRays, false), kVertex);
    add(aimed(kEdgeRays, true), kEdge);
    // tMin / tMax windows that cut at the first hit of a targeted ray: exactly at its t, one float step either side
    // (the bounds are exclusive for triangles), and past it or short of it by a margin.
    std::vector<oracle::Ray> windows = targetedRays(scene, kWindowRays);
    std::vector<VkasRay> batch(windows.size());
    for (size_t i = 0; i < windows.size(); ++i) {
        for (int k = 0; k < 3; ++k) batch[i].origin[k] = windows[i].origin[k], batch[i].direction[k] = windows[i].direction[k];
        batch[i].tMin = windows[i].tMin;
        batch[i].tMax = windows[i].tMax;
    }
    std::vector<VkasHit> first(windows.size());
    EXPECT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(batch.size()), batch.data(),
                            first.data()),
              VK_SUCCESS);
    const float inf = std::numeric_limits<float>::infinity();
    for (size_t i = 0; i < windows.size(); ++i) {
        oracle::Ray& r = windows[i];
        const float t = first[i].type ? first[i].t : 1.0f;
        switch (rng.below(6)) {
            case 0: r.tMax = t; break;
            case 1: r.tMin = t; break;
            case 2: r.tMax = std::nextafter(t, inf); break;
            case 3: r.tMin = std::nextafter(t, inf); break;
            case 4: r.tMin = t * 1.001f, r.tMax = t * rng.uniformf(1.01f, 4.0f); break;
            default: r.tMin = t * rng.uniformf(0.0f, 0.5f), r.tMax = t * 0.999f; break;
        }
    }
    add(windows, kWindow);
    return rays;
}

void format1_hits::write(const SceneSpec& spec, const std::string& dir) {
    SceneFile f;
    f.structureFormat = vkas::format::kVersion;
    f.name = spec.name;
    f.seed = spec.seed;
    f.scene = generate(spec.name, spec.seed);
    // The file's bytes are what the test reads back: build from the decoded scene, as the test does.
    {
        SceneFile probe = f;
        probe.passes = {};
        std::string error;
        ASSERT_TRUE(decode(encode(probe), probe, error)) << error;
        f.scene = probe.scene;
    }
    AccelStruct* tlas = buildScene(f.scene);
    rng = Rng(spec.seed ^ 0x9E37'79B9'7F4A'7C15ull);  // the rays' seed
    f.rays = makeRays(tlas, f.kinds);
    f.passes = standardPasses();
    const auto hits = traceAll(tlas, f.rays, f.passes);
    // The reference must be right: every answer against the oracle.
    size_t checked = 0, wrong = 0, hitCount = 0;
    f.hits.resize(f.passes.size());
    for (size_t p = 0; p < f.passes.size(); ++p) {
        const Pass& pass = f.passes[p];
        f.hits[p].resize(hits[p].size());
        for (size_t k = 0; k < hits[p].size(); ++k) {
            const oracle::Ray& ray = f.rays[pass.first + k * pass.step];
            for (uint32_t m = 0; m < kMethodCount; ++m) {
                const Hit& h = hits[p][k][m];
                f.hits[p][k][m] = toRec(h);
                hitCount += h.type != 0;
                bool firstHit = false;
                const oracle::Result ex = expectedFor(tlas, ray, pass, Method(m), firstHit);
                const auto res = firstHit ? matchesAnyHit(ex, ray, h) : matchesClosest(ex, ray, h);
                ++checked;
                if (!res && ++wrong <= 10)
                    ADD_FAILURE() << spec.name << ": the format " << vkas::format::kVersion << " answer disagrees with the oracle, "
                                  << kMethodNames[m] << ", pass " << p << ": " << res.message();
            }
        }
    }
    EXPECT_EQ(wrong, 0u) << "answers that disagree with the oracle; nothing is written";
    if (wrong) return;
    const std::vector<uint8_t> bytes = encode(f);
    const std::string path = dir + "/" + spec.name + ".bin";
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    ASSERT_TRUE(out.good()) << path;
    size_t triangles = 0;
    for (const auto& b : f.scene.blases)
        for (const auto& g : b.geometries) triangles += g.mesh.triangleCount();
    std::cout << "[  WRITE   ] " << path << ": " << bytes.size() << " bytes, " << triangles << " triangles in "
              << f.scene.blases.size() << " bottom levels, " << f.scene.instances.size() << " instances, "
              << f.rays.size() << " rays, " << f.passes.size() << " passes, " << checked << " answers (" << hitCount
              << " hits) checked against the oracle" << std::endl;
}

void format1_hits::compare(const SceneSpec& spec, const std::string& path) {
    std::vector<uint8_t> bytes;
    ASSERT_TRUE(readFile(path, bytes)) << "cannot read the reference file " << path;
    SceneFile f;
    std::string error;
    ASSERT_TRUE(decode(bytes, f, error)) << path << ": " << error;
    ASSERT_EQ(f.name, spec.name) << path;
    std::cout << "[  SCENE   ] " << f.name << " seed 0x" << std::hex << f.seed << std::dec << " (" << spec.what << "): "
              << f.rays.size() << " rays, " << f.passes.size() << " passes; reference traced with structure format "
              << f.structureFormat << ", this build writes format " << vkas::format::kVersion << std::endl;
    AccelStruct* tlas = buildScene(f.scene);
    ASSERT_FALSE(HasFailure()) << "the scene of " << path << " did not build";
    const auto now = traceAll(tlas, f.rays, f.passes);
    size_t compared = 0, identical = 0, ties = 0, firstHitOthers = 0, failures = 0;
    const char* verboseEnv = std::getenv("VKAS_FORMAT1_HITS_VERBOSE");  // set: print every accepted tie
    const bool verbose = verboseEnv && *verboseEnv && *verboseEnv != '0';
    for (size_t p = 0; p < f.passes.size(); ++p) {
        const Pass& pass = f.passes[p];
        for (size_t k = 0; k < f.hits[p].size(); ++k) {
            const size_t rayIndex = pass.first + k * pass.step;
            const oracle::Ray& ray = f.rays[rayIndex];
            for (uint32_t m = 0; m < kMethodCount; ++m) {
                ++compared;
                const Rec& ref = f.hits[p][k][m];
                const Hit& got = now[p][k][m];
                const Rec rec = toRec(got);
                if (rec == ref) {
                    ++identical;
                    continue;
                }
                bool firstHit = false;
                const oracle::Result ex = expectedFor(tlas, ray, pass, Method(m), firstHit);
                std::string why;  // empty: a tie
                if (ref.type == 0 || rec.type == 0) {
                    why = ref.type == 0 ? "a miss became a hit" : "a hit became a miss";
                } else if (ref.instanceId == rec.instanceId && ref.geometryIndex == rec.geometryIndex &&
                           ref.primitiveIndex == rec.primitiveIndex) {
                    why = "the same primitive with other t, barycentrics or facing";
                } else {
                    const oracle::Candidate* cNow = ex.find(got.instanceId, got.geometryIndex, got.primitiveIndex);
                    const oracle::Candidate* cRef = ex.find(int32_t(ref.instanceId), int32_t(ref.geometryIndex), int32_t(ref.primitiveIndex));
                    // The reference answer as a Hit (its custom index and SBT offset are the oracle's: not stored).
                    Hit refHit;
                    refHit.type = ref.type;
                    refHit.instanceId = int32_t(ref.instanceId);
                    refHit.geometryIndex = int32_t(ref.geometryIndex);
                    refHit.primitiveIndex = int32_t(ref.primitiveIndex);
                    refHit.t = fromBits(ref.t);
                    refHit.bary[0] = fromBits(ref.b0);
                    refHit.bary[1] = fromBits(ref.b1);
                    refHit.frontFace = ref.frontFace;
                    if (cRef) refHit.customIndex = int32_t(cRef->customIndex), refHit.sbtOffset = cRef->sbtOffset;
                    const auto refRes = matchesAnyHit(ex, ray, refHit);
                    if (!cNow) {
                        why = "the new hit is not an oracle candidate";
                    } else if (cRef && !refRes) {
                        why = std::string("the reference answer disagrees with the oracle (a damaged reference?): ") + refRes.message();
                    } else if (firstHit) {
                        const auto res = matchesAnyHit(ex, ray, got);
                        if (!(got.t >= ray.tMin && got.t <= ray.tMax)) why = "the new hit is outside [tMin, tMax]";
                        else if (!res) why = std::string("the new first hit fails the oracle check: ") + res.message();
                    } else if (!cRef) {
                        why = "the reference hit is not an oracle candidate (and the new one is another primitive)";
                    } else {
                        double o2 = 0, d2 = 0;
                        for (int c = 0; c < 3; ++c) o2 += double(ray.origin[c]) * ray.origin[c], d2 += double(ray.direction[c]) * ray.direction[c];
                        const double tRef = fromBits(ref.t), tNow = got.t;
                        const double tol = kTieRelative * (std::sqrt(o2) + std::max(std::fabs(tRef), std::fabs(tNow)) * std::sqrt(d2)) / std::sqrt(d2);
                        const auto res = matchesClosest(ex, ray, got);
                        char buf[200];
                        if (std::fabs(cRef->t - cNow->t) > tol) {
                            std::snprintf(buf, sizeof buf, "not a tie: the oracle's t of the two primitives differ by %.3g (tolerance %.3g)",
                                          std::fabs(cRef->t - cNow->t), tol);
                            why = buf;
                        } else if (std::fabs(tRef - tNow) > tol) {
                            std::snprintf(buf, sizeof buf, "not a tie: the two answers' t differ by %.3g (tolerance %.3g)",
                                          std::fabs(tRef - tNow), tol);
                            why = buf;
                        } else if (!res) {
                            why = std::string("the new closest hit fails the oracle check: ") + res.message();
                        }
                    }
                }
                if (why.empty()) {
                    ++(firstHit ? firstHitOthers : ties);
                    if (verbose)
                        std::cout << "[   TIE    ] " << f.name << " pass " << p << ", " << kMethodNames[m] << ", ray #" << rayIndex
                                  << " (" << kRayKindNames[f.kinds[rayIndex]] << "): " << describe(ray) << "\n    reference: "
                                  << str(ref) << "\n    now:       " << str(rec) << "\n    " << oracleSummary(ex) << std::endl;
                    continue;
                }
                if (++failures <= 20)
                    ADD_FAILURE() << f.name << " (seed 0x" << std::hex << f.seed << "), pass " << p << " (flags 0x" << pass.flags
                                  << " cullMask 0x" << pass.cullMask << std::dec << "), " << kMethodNames[m] << ", ray #"
                                  << rayIndex << " (" << kRayKindNames[f.kinds[rayIndex]] << "):\n  " << why << "\n  ray: "
                                  << describe(ray) << "\n  reference (format " << f.structureFormat << "): " << str(ref)
                                  << "\n  this build (format " << vkas::format::kVersion << "): " << str(rec) << "\n  " << oracleSummary(ex);
            }
        }
    }
    std::cout << "[  SCENE   ] " << f.name << ": " << compared << " answers, " << identical << " identical, " << ties
              << " closest-hit ties, " << firstHitOthers << " other first hits, " << failures << " failures" << std::endl;
    EXPECT_EQ(failures, 0u) << f.name << " (seed 0x" << std::hex << f.seed << std::dec << "): " << failures
                            << " answers differ from the format " << f.structureFormat << " reference and are not ties"
                            << (failures > 20 ? " (the first 20 are shown)" : "");
}

TEST_P(format1_hits, matches_reference) {
    const SceneSpec& spec = GetParam();
    std::cout << "[   SEED   ] scene " << spec.name << " seed 0x" << std::hex << spec.seed << std::dec << std::endl;
    if (const char* dir = std::getenv("VKAS_WRITE_FORMAT1_HITS"); dir && *dir) {
        write(spec, dir);
        return;
    }
    compare(spec, std::string(VKAS_TEST_DATA_DIR) + "/format1_hits/" + spec.name + ".bin");
}

INSTANTIATE_TEST_SUITE_P(scenes, format1_hits, ::testing::ValuesIn(kScenes),
                         [](const auto& info) { return std::string(info.param.name); });

// The parser on damaged copies of the committed files: every truncation, a byte more, a damaged count and tag, each
// rejected with a message (and without reading out of bounds: the sanitizer build runs this too).
TEST(format1_hits_file, damaged_files_are_rejected) {
    for (const SceneSpec& spec : kScenes) {
        const std::string path = std::string(VKAS_TEST_DATA_DIR) + "/format1_hits/" + spec.name + ".bin";
        std::vector<uint8_t> bytes;
        ASSERT_TRUE(readFile(path, bytes)) << path;
        SceneFile f;
        std::string error;
        ASSERT_TRUE(decode(bytes, f, error)) << path << ": " << error;
        // Truncations: every length up to 64 bytes, then 200 spread over the file, and the last 16.
        std::vector<size_t> lengths;
        for (size_t n = 0; n < std::min<size_t>(64, bytes.size()); ++n) lengths.push_back(n);
        for (size_t k = 1; k < 200; ++k) lengths.push_back(bytes.size() * k / 200);
        for (size_t n = bytes.size() > 16 ? bytes.size() - 16 : 0; n < bytes.size(); ++n) lengths.push_back(n);
        for (size_t n : lengths) {
            const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + std::ptrdiff_t(n));
            EXPECT_FALSE(decode(cut, f, error)) << path << " truncated to " << n << " bytes was accepted";
            EXPECT_FALSE(error.empty());
        }
        std::vector<uint8_t> longer = bytes;
        longer.push_back(0);
        EXPECT_FALSE(decode(longer, f, error)) << "a byte after the end marker was accepted";
        std::vector<uint8_t> badMagic = bytes;
        badMagic[0] ^= 1;
        EXPECT_FALSE(decode(badMagic, f, error));
        std::vector<uint8_t> hugeCount = bytes;  // the bottom-level count (after the header, name, seed, tlasFlags)
        const size_t at = 20 + 4 + std::strlen(spec.name) + 8 + 4;
        for (int k = 0; k < 4; ++k) hugeCount[at + size_t(k)] = 0xFF;
        EXPECT_FALSE(decode(hugeCount, f, error)) << "a bottom-level count of 2^32-1 was accepted";
        EXPECT_NE(error.find("cannot hold"), std::string::npos) << error;
        if (bytes.size() > 64) {
            const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + std::ptrdiff_t(bytes.size() / 2));
            decode(cut, f, error);
            std::cout << "  " << spec.name << " cut in half: " << error << std::endl;
        }
    }
}
