#include "engine/refit.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "engine/format.hpp"
#include "engine/geometry_fetch.hpp"
#include "engine/motion.hpp"
#include "engine/sphere_fetch.hpp"

namespace vkas {

using namespace format;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();


Aabb ballsBox(const double lo[3], const double hi[3]) {
    Aabb b;
    b.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    b.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
    return b;
}

VkGeometryTypeKHR geometryTypeOf(const RefitJob& job, uint32_t g) { return buildGeometry(*job.info, g).geometryType; }

// Lazily constructed per-geometry input readers: records come in leaf order, so the geometry changes rarely for
// big geometries and constructing one reader per change stays cheap for many small ones (no per-geometry array:
// a structure may have a million geometries).
class TriangleInputs {
public:
    explicit TriangleInputs(const RefitJob& job) : job_(job) {}
    const TriangleSource* at(uint32_t g) {
        if (g >= job_.info->geometryCount) return nullptr;
        if (g != current_) {
            source_.emplace(buildGeometry(*job_.info, g).geometry.triangles, job_.ranges[g]);
            current_ = g;
        }
        return &*source_;
    }

private:
    const RefitJob& job_;
    std::optional<TriangleSource> source_;
    uint32_t current_ = UINT32_MAX;
};

// [NV-motion] Both times of a motion triangle geometry (time 1 from VkAccelerationStructureGeometryMotionTrianglesDataNV;
// without it the geometry does not move), as gatherMotionTriangles reads them.
class MotionTriangleInputs {
public:
    explicit MotionTriangleInputs(const RefitJob& job) : job_(job) {}
    bool at(uint32_t g, const TriangleSource*& t0, const TriangleSource*& t1) {
        if (g >= job_.info->geometryCount) return false;
        if (g != current_) {
            const auto& tri = buildGeometry(*job_.info, g).geometry.triangles;
            VkAccelerationStructureGeometryTrianglesDataKHR atOne = tri;
            const auto* m = motion::findMotionTriangles(tri);
            if (m && m->vertexData.hostAddress) atOne.vertexData = m->vertexData;
            t0_.emplace(tri, job_.ranges[g]);
            t1_.emplace(atOne, job_.ranges[g]);
            current_ = g;
        }
        t0 = &*t0_, t1 = &*t1_;
        return true;
    }

private:
    const RefitJob& job_;
    std::optional<TriangleSource> t0_, t1_;
    uint32_t current_ = UINT32_MAX;
};

class SweptInputs {
public:
    explicit SweptInputs(const RefitJob& job) : job_(job) {}
    const SweptSpheresSource* at(uint32_t g) {
        if (g >= job_.info->geometryCount) return nullptr;
        if (g != current_) {
            SweptSpheresData data;
            current_ = g;
            if (!sweptSpheresData(buildGeometry(*job_.info, g), data)) {
                source_.reset();
                return nullptr;
            }
            source_.emplace(data, job_.ranges[g]);
        }
        return source_ ? &*source_ : nullptr;
    }

private:
    const RefitJob& job_;
    std::optional<SweptSpheresSource> source_;
    uint32_t current_ = UINT32_MAX;
};

// Each refitter turns the source record `in` into the destination record `out` (which may alias `in`) and
// extends `box` by the new record's box. A record whose primitive is not valid any more (invalid usage that
// validation reports: it became inactive, its box is inverted, its instance names no structure) is kept but
// never hit, and adds nothing to the box.

struct TriangleRefitter {
    static constexpr size_t kSize = sizeof(TriangleRecord);
    TriangleInputs inputs;
    explicit TriangleRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        TriangleRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const TriangleSource* s = inputs.at(rec.geometryIndex);
        if (s && rec.primitiveIndex < s->primitiveCount()) {
            const bool active = s->fetch(rec.primitiveIndex, rec.v);
            // Degenerate is re-decided: a triangle that has area again is hit again, and vice versa.
            rec.flags &= ~kTriangleDegenerate;
            if (!active || isDegenerateTriangle(rec.v)) rec.flags |= kTriangleDegenerate;
            if (active)
                for (auto& v : rec.v) box.extend(Vec3{v[0], v[1], v[2]});
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct MotionTriangleRefitter {
    static constexpr size_t kSize = sizeof(MotionTriangleRecord);
    MotionTriangleInputs inputs;
    explicit MotionTriangleRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        MotionTriangleRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const TriangleSource *t0 = nullptr, *t1 = nullptr;
        if (inputs.at(rec.base.geometryIndex, t0, t1) && rec.base.primitiveIndex < t0->primitiveCount()) {
            const bool a = t0->fetch(rec.base.primitiveIndex, rec.base.v);
            const bool b = t1->fetch(rec.base.primitiveIndex, rec.v1);
            // Motion triangles are never marked degenerate (the intersection test rejects zero area); only an
            // invalid update (a triangle made inactive) sets the flag, so that it is never hit.
            rec.base.flags &= ~kTriangleDegenerate;
            if (a && b) {
                for (auto& v : rec.base.v) box.extend(Vec3{v[0], v[1], v[2]});
                for (auto& v : rec.v1) box.extend(Vec3{v[0], v[1], v[2]});
            } else {
                rec.base.flags |= kTriangleDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct AabbRefitter {
    static constexpr size_t kSize = sizeof(AabbRecord);
    const RefitJob& job;
    std::optional<AabbSource> source;
    uint32_t current = UINT32_MAX;
    explicit AabbRefitter(const RefitJob& j) : job(j) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        AabbRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const uint32_t g = rec.geometryIndex;
        if (g < job.info->geometryCount) {
            if (g != current) source.emplace(buildGeometry(*job.info, g).geometry.aabbs, job.ranges[g]), current = g;
            if (rec.primitiveIndex < source->primitiveCount()) {
                if (source->fetch(rec.primitiveIndex, rec.lower, rec.upper) && !isInvertedAabb(rec.lower, rec.upper)) {
                    box.extend(Vec3{rec.lower[0], rec.lower[1], rec.lower[2]});
                    box.extend(Vec3{rec.upper[0], rec.upper[1], rec.upper[2]});
                } else {  // invalid update: an empty box, never hit
                    for (int k = 0; k < 3; ++k) rec.lower[k] = kInf, rec.upper[k] = -kInf;
                }
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct SphereRefitter {
    static constexpr size_t kSize = sizeof(SphereRecord);
    SweptInputs inputs;
    explicit SphereRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        SphereRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const SweptSpheresSource* s = inputs.at(rec.geometryIndex);
        if (s && rec.primitiveIndex < s->primitiveCount()) {
            const bool active = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 0), rec.center, rec.radius);
            // Degenerate is re-decided: a sphere that has a radius again is hit again, one that loses it is not
            // (its centre still counts in the box, as in an ALLOW_UPDATE build).
            rec.flags &= ~kSweptDegenerate;
            if (active && rec.radius >= 0.0f) {
                if (rec.radius == 0.0f) rec.flags |= kSweptDegenerate;
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                extendBall(lo, hi, rec.center, rec.radius);
                box.extend(ballsBox(lo, hi));
            } else {
                rec.radius = -1.0f;  // invalid update: no ball, never hit
                rec.flags |= kSweptDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct LssRefitter {
    static constexpr size_t kSize = sizeof(LssRecord);
    SweptInputs inputs;
    explicit LssRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        LssRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const SweptSpheresSource* s = inputs.at(rec.geometryIndex);
        if (s && rec.primitiveIndex < s->primitiveCount()) {
            // The end caps stay as the build decided them: they follow from the index buffer, which an update
            // must not change.
            const bool a = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 0), rec.p0, rec.r0);
            const bool b = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 1), rec.p1, rec.r1);
            // Degenerate (both radii 0) is re-decided as for spheres.
            rec.flags &= ~kSweptDegenerate;
            if (a && b && rec.r0 >= 0.0f && rec.r1 >= 0.0f) {
                if (rec.r0 == 0.0f && rec.r1 == 0.0f) rec.flags |= kSweptDegenerate;
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                extendBall(lo, hi, rec.p0, rec.r0);
                extendBall(lo, hi, rec.p1, rec.r1);
                box.extend(ballsBox(lo, hi));
            } else {
                rec.r0 = rec.r1 = std::numeric_limits<float>::quiet_NaN();  // invalid update: never hit
                rec.flags |= kSweptDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct InstanceRefitter {
    static constexpr size_t kSize = sizeof(InstanceRecord);
    const RefitJob& job;
    std::optional<InstanceSource> source;
    explicit InstanceRefitter(const RefitJob& j) : job(j) {
        if (j.info->geometryCount == 1) source.emplace(buildGeometry(*j.info, 0).geometry.instances, j.ranges[0]);
    }
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        InstanceRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        if (source && rec.instanceId < source->count()) {
            const RawInstance inst = source->fetch(rec.instanceId);
            const std::byte* blas = inst.reference && job.resolver ? job.resolver(inst.reference) : nullptr;
            if (blas) {  // otherwise invalid (inactive now, or not a structure): kept with an empty box
                const uint32_t id = rec.instanceId;
                Aabb b;
                makeInstanceRecord(inst, id, blas, rec, b);
                box.extend(b);
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct MotionInstanceRefitter {
    static constexpr size_t kSize = sizeof(MotionInstanceRecord);
    const RefitJob& job;
    std::optional<motion::MotionInstanceSource> source;
    explicit MotionInstanceRefitter(const RefitJob& j) : job(j) {
        if (j.info->geometryCount == 1)
            source.emplace(buildGeometry(*j.info, 0).geometry.instances, j.ranges[0]);
    }
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        MotionInstanceRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        motion::RawMotionInstance inst;
        if (source && rec.base.instanceId < source->count() && source->fetch(rec.base.instanceId, inst) &&
            inst.type <= motion::kSrt && inst.reference != 0) {
            const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
            if (blas) {
                const uint32_t id = rec.base.instanceId;
                Aabb b;
                makeMotionInstanceRecord(inst, id, blas, rec, b);
                box.extend(b);
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

void setSlot(Node& n, uint32_t i, const Aabb& b) {
    n.lowerX[i] = b.lower.x, n.lowerY[i] = b.lower.y, n.lowerZ[i] = b.lower.z;
    n.upperX[i] = b.upper.x, n.upperY[i] = b.upper.y, n.upperZ[i] = b.upper.z;
}

Aabb nodeBox(const Node& n) {
    Aabb b;
    for (uint32_t i = 0; i < kNodeWidth; ++i) {
        Aabb s;
        s.lower = {n.lowerX[i], n.lowerY[i], n.lowerZ[i]};
        s.upper = {n.upperX[i], n.upperY[i], n.upperZ[i]};
        b.extend(s);
    }
    return b;
}

// The refit proper. Reads every node and record of src once and writes the same byte ranges of dst.
template <class Refitter>
void refitTree(const RefitJob& job, Refitter& refit) {
    Header h;
    std::memcpy(&h, job.src, sizeof h);
    const uint64_t nodeEnd = h.nodeOffset + uint64_t(h.nodeCount) * sizeof(Node);
    if (job.src != job.dst) {  // the parts a refit does not change: header, geometry table, the zeroed gaps
        std::memcpy(job.dst, job.src, h.nodeOffset);
        std::memcpy(job.dst + nodeEnd, job.src + nodeEnd, h.recordOffset - nodeEnd);
    }
    const auto* srcNodes = reinterpret_cast<const Node*>(job.src + h.nodeOffset);
    auto* dstNodes = reinterpret_cast<Node*>(job.dst + h.nodeOffset);
    const std::byte* srcRecords = job.src + h.recordOffset;
    std::byte* dstRecords = job.dst + h.recordOffset;
    auto leafBox = [&](ChildRef ref) {
        Aabb b;
        const uint64_t first = leafFirst(ref);
        const uint64_t end = std::min<uint64_t>(first + leafCount(ref), h.recordCount);
        for (uint64_t j = first; j < end; ++j)
            refit(srcRecords + j * Refitter::kSize, dstRecords + j * Refitter::kSize, b);
        return b;
    };
    // Preorder numbering: every child node has a larger index than its parent, so a reverse sweep finishes the
    // children first.
    for (uint64_t k = h.nodeCount; k-- > 0;) {
        Node n;
        std::memcpy(&n, &srcNodes[k], sizeof n);
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            const ChildRef ref = n.child[i];
            Aabb b;
            if (isLeaf(ref)) {
                b = leafBox(ref);
            } else if (isInternal(ref)) {
                const uint32_t c = nodeIndex(ref);
                if (c > k && c < h.nodeCount) b = nodeBox(dstNodes[c]);
            }
            setSlot(n, i, b);  // empty slots keep +inf / -inf
        }
        std::memcpy(&dstNodes[k], &n, sizeof n);
    }
    Aabb bounds;
    if (isLeaf(h.root))
        bounds = leafBox(h.root);
    else if (isInternal(h.root) && nodeIndex(h.root) < h.nodeCount)
        bounds = nodeBox(dstNodes[nodeIndex(h.root)]);
    h.bounds[0] = bounds.lower.x, h.bounds[1] = bounds.lower.y, h.bounds[2] = bounds.lower.z;
    h.bounds[3] = bounds.upper.x, h.bounds[4] = bounds.upper.y, h.bounds[5] = bounds.upper.z;
    std::memcpy(job.dst, &h, sizeof h);
}

template <class Refitter>
void runRefit(const RefitJob& job) {
    Refitter r(job);
    refitTree(job, r);
}

// The (geometry, primitive) a record names, for any record kind.
struct RecordKey {
    uint32_t geometry, primitive;
};

// Reads the active state of input primitives for checkUpdateActivity.
class ActivityProbe {
public:
    ActivityProbe(const RefitJob& job, bool topLevel, bool motion, VkGeometryTypeKHR type)
        : job_(job), top_(topLevel), motion_(motion), type_(type), tri_(job), motionTri_(job), swept_(job) {
        if (top_ && job.info->geometryCount == 1) {
            if (motion_)
                motionInstances_.emplace(buildGeometry(*job.info, 0).geometry.instances, job.ranges[0]);
            else
                instances_.emplace(buildGeometry(*job.info, 0).geometry.instances, job.ranges[0]);
        }
    }

    // active: not inactive by the spec's rules (NaN, reference 0). storable: what a build would store (active and
    // valid; degenerate triangles, spheres and LSS count, as ALLOW_UPDATE builds keep them).
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        active = storable = false;
        if (top_) {
            if (motion_) {
                motion::RawMotionInstance inst;
                active = motionInstances_ && motionInstances_->fetch(i, inst) && inst.type <= motion::kSrt &&
                         inst.reference != 0;
            } else {
                active = instances_ && instances_->fetch(i).reference != 0;
            }
            storable = active;
            return;
        }
        switch (uint32_t(type_)) {
            case VK_GEOMETRY_TYPE_TRIANGLES_KHR: {
                float v[3][3];
                if (motion_) {
                    const TriangleSource *t0, *t1;
                    if (!motionTri_.at(g, t0, t1)) return;
                    const bool a = t0->fetch(i, v);
                    const bool b = t1->fetch(i, v);
                    active = storable = a && b;
                } else {
                    const TriangleSource* t = tri_.at(g);
                    active = storable = t && t->fetch(i, v);
                }
                return;
            }
            case VK_GEOMETRY_TYPE_AABBS_KHR: {
                if (g != aabbGeometry_)
                    aabbs_.emplace(buildGeometry(*job_.info, g).geometry.aabbs, job_.ranges[g]), aabbGeometry_ = g;
                float lo[3], hi[3];
                active = aabbs_->fetch(i, lo, hi);
                storable = active && !isInvertedAabb(lo, hi);
                return;
            }
            case VK_GEOMETRY_TYPE_SPHERES_NV: {
                const SweptSpheresSource* s = swept_.at(g);
                if (!s) return;
                float c[3], r;
                active = s->fetchVertex(s->vertexNumber(i, 0), c, r);
                storable = active && r >= 0.0f;  // zero radius counts: ALLOW_UPDATE builds keep it
                return;
            }
            case VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV: {
                const SweptSpheresSource* s = swept_.at(g);
                if (!s) return;
                float p0[3], p1[3], r0, r1;
                const bool a = s->fetchVertex(s->vertexNumber(i, 0), p0, r0);
                const bool b = s->fetchVertex(s->vertexNumber(i, 1), p1, r1);
                active = a && b;
                storable = active && r0 >= 0.0f && r1 >= 0.0f;  // both radii 0 counts, as for spheres
                return;
            }
            default: return;
        }
    }

private:
    const RefitJob& job_;
    bool top_, motion_;
    VkGeometryTypeKHR type_;
    TriangleInputs tri_;
    MotionTriangleInputs motionTri_;
    SweptInputs swept_;
    std::optional<AabbSource> aabbs_;
    uint32_t aabbGeometry_ = UINT32_MAX;
    std::optional<InstanceSource> instances_;
    std::optional<motion::MotionInstanceSource> motionInstances_;
};

RecordKey recordKey(const std::byte* records, uint64_t j, bool top, bool motion, VkGeometryTypeKHR type) {
    if (top) {
        const size_t size = motion ? sizeof(MotionInstanceRecord) : sizeof(InstanceRecord);
        return {0, reinterpret_cast<const InstanceRecord*>(records + j * size)->instanceId};
    }
    switch (uint32_t(type)) {
        case VK_GEOMETRY_TYPE_AABBS_KHR: {
            const auto* r = reinterpret_cast<const AabbRecord*>(records) + j;
            return {r->geometryIndex, r->primitiveIndex};
        }
        case VK_GEOMETRY_TYPE_SPHERES_NV: {
            const auto* r = reinterpret_cast<const SphereRecord*>(records) + j;
            return {r->geometryIndex, r->primitiveIndex};
        }
        case VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV: {
            const auto* r = reinterpret_cast<const LssRecord*>(records) + j;
            return {r->geometryIndex, r->primitiveIndex};
        }
        default: {
            const size_t size = motion ? sizeof(MotionTriangleRecord) : sizeof(TriangleRecord);
            const auto* r = reinterpret_cast<const TriangleRecord*>(records + j * size);
            return {r->geometryIndex, r->primitiveIndex};
        }
    }
}

}  // namespace

bool refitShapeMatches(const RefitJob& job) {
    const Header* h = header(job.src);
    const auto& info = *job.info;
    if (h->magic != kMagic || h->version != kVersion) return false;
    const bool top = info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    if (h->type != uint32_t(top ? StructureType::TopLevel : StructureType::BottomLevel)) return false;
    if (h->geometryCount != info.geometryCount) return false;
    if (motion::isMotionBuild(h->buildFlags) != motion::isMotionBuild(info.flags)) return false;
    if (info.geometryCount != 0 && !info.pGeometries && !info.ppGeometries) return false;
    const GeometryDesc* descs = geometries(job.src);
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        if (descs[g].geometryType != uint32_t(geometryTypeOf(job, g))) return false;
        if (descs[g].primitiveCount != job.ranges[g].primitiveCount) return false;
    }
    return true;
}

VkResult refitAccelerationStructure(const RefitJob& job) {
    if (!refitShapeMatches(job)) return VK_ERROR_UNKNOWN;
    const Header* h = header(job.src);
    if (h->usedSize > job.dstSize) return VK_ERROR_UNKNOWN;
    const bool motion = motion::isMotionBuild(h->buildFlags);
    if (h->type == uint32_t(StructureType::TopLevel)) {
        if (motion)
            runRefit<MotionInstanceRefitter>(job);
        else
            runRefit<InstanceRefitter>(job);
        return VK_SUCCESS;
    }
    switch (h->primitiveType) {
        case VK_GEOMETRY_TYPE_AABBS_KHR: runRefit<AabbRefitter>(job); break;
        case VK_GEOMETRY_TYPE_SPHERES_NV: runRefit<SphereRefitter>(job); break;
        case VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV: runRefit<LssRefitter>(job); break;
        default:
            if (motion)
                runRefit<MotionTriangleRefitter>(job);
            else
                runRefit<TriangleRefitter>(job);
            break;
    }
    return VK_SUCCESS;
}

uint32_t referencedIndexHash(const VkAccelerationStructureGeometryTrianglesDataKHR& triangles,
                             const VkAccelerationStructureBuildRangeInfoKHR& range) {
    if (triangles.indexType != VK_INDEX_TYPE_UINT16 && triangles.indexType != VK_INDEX_TYPE_UINT32) return 0;
    if (!triangles.indexData.hostAddress) return 0;
    const auto* p = static_cast<const std::byte*>(triangles.indexData.hostAddress) + range.primitiveOffset;
    const uint64_t n = 3ull * range.primitiveCount;
    uint64_t hash = 0x9E37'79B9'7F4A'7C15ull ^ n;
    if (triangles.indexType == VK_INDEX_TYPE_UINT16) {
        for (uint64_t k = 0; k < n; ++k) hash = (hash ^ loadUnaligned<uint16_t>(p + 2 * k)) * 0x0000'0100'0000'01B3ull;
    } else {
        for (uint64_t k = 0; k < n; ++k) hash = (hash ^ loadUnaligned<uint32_t>(p + 4 * k)) * 0x0000'0100'0000'01B3ull;
    }
    hash ^= hash >> 33;
    hash *= 0xFF51'AFD7'ED55'8CCDull;
    hash ^= hash >> 33;
    return uint32_t(hash ^ (hash >> 32));
}

ActivityViolation checkUpdateActivity(const RefitJob& job) {
    ActivityViolation result;
    const Header* h = header(job.src);
    const auto& info = *job.info;
    const bool top = h->type == uint32_t(StructureType::TopLevel);
    const bool motion = motion::isMotionBuild(h->buildFlags);
    const auto type = VkGeometryTypeKHR(h->primitiveType);
    std::vector<uint64_t> base(info.geometryCount + 1, 0);
    for (uint32_t g = 0; g < info.geometryCount; ++g) base[g + 1] = base[g] + job.ranges[g].primitiveCount;
    std::vector<uint64_t> stored((base[info.geometryCount] + 63) / 64, 0);
    ActivityProbe probe(job, top, motion, type);
    const std::byte* records = job.src + h->recordOffset;
    for (uint64_t j = 0; j < h->recordCount; ++j) {
        const RecordKey key = recordKey(records, j, top, motion, type);
        if (key.geometry >= info.geometryCount || key.primitive >= job.ranges[key.geometry].primitiveCount) continue;
        const uint64_t bit = base[key.geometry] + key.primitive;
        stored[bit / 64] |= 1ull << (bit % 64);
        bool active, storable;
        probe.probe(key.geometry, key.primitive, active, storable);
        if (!active) return {3663, key.geometry, key.primitive};
    }
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        for (uint32_t i = 0; i < job.ranges[g].primitiveCount; ++i) {
            const uint64_t bit = base[g] + i;
            if (stored[bit / 64] & (1ull << (bit % 64))) continue;
            bool active, storable;
            probe.probe(g, i, active, storable);
            if (storable) return {3664, g, i};
        }
    }
    return result;
}

}  // namespace vkas
