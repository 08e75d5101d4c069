#include "engine/refit.hpp"

#include <immintrin.h>

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

// A leaf's box while its records are refitted: x, y, z in lanes 0-2 (lane 3 is ignored). `extend` takes the
// new point first so that a NaN coordinate leaves the box as it was, as Aabb::extend does (std::min / std::max
// keep their first argument unless the second compares smaller / larger; so do these, ties included).
struct LeafBox {
    __m128 lower = _mm_set1_ps(kInf);
    __m128 upper = _mm_set1_ps(-kInf);
    void extend(__m128 p) {
        lower = _mm_min_ps(p, lower);
        upper = _mm_max_ps(p, upper);
    }
    void extend(const Aabb& b) {
        lower = _mm_min_ps(_mm_setr_ps(b.lower.x, b.lower.y, b.lower.z, 0.0f), lower);
        upper = _mm_max_ps(_mm_setr_ps(b.upper.x, b.upper.y, b.upper.z, 0.0f), upper);
    }
};

// Refitters (`leaves`) turn the source records of the leaf slots of one node into destination records (which may
// alias them) and set each leaf slot's box to the union of its new records' boxes. A record whose primitive is not valid any more (invalid
// usage that validation reports: it became inactive, its box is inverted, its instance names no structure) is
// kept but never hit, and adds nothing to the box. PerRecord adapts the refitters that work one record at a time.
template <class RecordRefitter>
struct PerRecord {
    RecordRefitter refit;
    explicit PerRecord(const RefitJob& job) : refit(job) {}
    void leaves(const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth], uint64_t recordCount,
                LeafBox boxes[kNodeWidth]) {
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            if (!isLeaf(refs[i])) continue;
            const uint64_t first = leafFirst(refs[i]), end = std::min(first + leafCount(refs[i]), recordCount);
            Aabb b;
            for (uint64_t j = first; j < end; ++j)
                refit(src + j * RecordRefitter::kSize, dst + j * RecordRefitter::kSize, b);
            boxes[i].extend(b);
        }
    }
};

// One float vertex in lanes 0-2 (z = 0 for two components), lane 3 zero. Reads exactly the vertex's bytes.
template <TriangleVertexKind V>
inline __m128 loadFloatVertex(const std::byte* p) {
    uint64_t xy;
    std::memcpy(&xy, p, 8);
    const __m128 lo = _mm_castsi128_ps(_mm_cvtsi64_si128(int64_t(xy)));
    if constexpr (V == TriangleVertexKind::Float3) return _mm_movelh_ps(lo, _mm_set_ss(loadUnaligned<float>(p + 8)));
    return lo;
}

// isDegenerateTriangle on vertices in registers: the same double differences and products, two lanes at a time
// (the middle component comes out negated, which keeps whether it is zero), so the decision is the build's.
inline bool isDegenerateTriangleSse(__m128 v0, __m128 v1, __m128 v2) {
    const __m128d a = _mm_cvtps_pd(v0), az = _mm_cvtps_pd(_mm_movehl_ps(v0, v0));
    const __m128d e1 = _mm_sub_pd(_mm_cvtps_pd(v1), a), e1z = _mm_sub_pd(_mm_cvtps_pd(_mm_movehl_ps(v1, v1)), az);
    const __m128d e2 = _mm_sub_pd(_mm_cvtps_pd(v2), a), e2z = _mm_sub_pd(_mm_cvtps_pd(_mm_movehl_ps(v2, v2)), az);
    const __m128d e2s = _mm_shuffle_pd(e2, e2, 1);  // (e2y, e2x)
    const __m128d t = _mm_mul_pd(e1, e2s);           // (e1x e2y, e1y e2x)
    const __m128d n2 = _mm_sub_sd(t, _mm_unpackhi_pd(t, t));
    // (e1y e2z - e1z e2y, e1x e2z - e1z e2x) = (n0, -n1)
    const __m128d n01 = _mm_sub_pd(_mm_mul_pd(_mm_shuffle_pd(e1, e1, 1), _mm_unpacklo_pd(e2z, e2z)),
                                   _mm_mul_pd(_mm_unpacklo_pd(e1z, e1z), e2s));
    const __m128d zero = _mm_setzero_pd();
    return _mm_movemask_pd(_mm_cmpeq_pd(n01, zero)) == 3 && (_mm_movemask_pd(_mm_cmpeq_sd(n2, zero)) & 1);
}

// Triangle records (non-motion). Each leaf's records are re-fetched with the reader specialised for their
// geometry's index type, vertex format and transform (TriangleSource::visit), and the leaf box is extended while
// each record is written. Float vertices without a transform stay in SSE registers from load to record.
class TriangleRefitter {
public:
    explicit TriangleRefitter(const RefitJob& job) : main_(job), other_(job) {}

    // Refits the records of the leaf slots of one node and sets their boxes. Records whose geometry has float
    // vertices and no transform are refitted in two steps over the whole node: first their indices are read and
    // their vertices' lines requested, then the vertices are read and the records written; so the cache misses of
    // many records overlap instead of forming one dependent chain per record.
    void leaves(const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth], uint64_t recordCount,
                LeafBox boxes[kNodeWidth]) {
        const TriangleSource* s = nullptr;
        uint32_t g = 0;
        for (uint32_t i = 0; i < kNodeWidth && !s; ++i)
            if (isLeaf(refs[i]) && leafFirst(refs[i]) < recordCount) {
                g = loadUnaligned<uint32_t>(src + leafFirst(refs[i]) * kSize + 36);
                s = main_.at(g);
            }
        if (s) {
            s->visit([&](auto reader) { batch(reader, g, src, dst, refs, recordCount, boxes); });
        } else {
            for (uint32_t i = 0; i < kNodeWidth; ++i)
                if (isLeaf(refs[i])) {
                    const uint64_t first = leafFirst(refs[i]), end = std::min(first + leafCount(refs[i]), recordCount);
                    for (uint64_t j = first; j < end; ++j) one(src, dst, j, boxes[i]);
                }
        }
    }

private:
    static constexpr size_t kSize = sizeof(TriangleRecord);
    static constexpr uint32_t kBatch = 64;

    struct Pending {
        const std::byte* vertex[3];
        uint64_t record;
        uint32_t primitive, flags, slot;
    };

    template <class Reader>
    static constexpr bool kFloats = Reader::kVertex != TriangleVertexKind::Other && !Reader::kTransform;

    // One record, through its own geometry's reader (other_, so that main_'s reader stays valid).
    void one(const std::byte* src, std::byte* dst, uint64_t j, LeafBox& box) {
        const uint32_t g = loadUnaligned<uint32_t>(src + j * kSize + 36);
        const TriangleSource* s = other_.at(g);
        if (!s) {  // names no geometry of the inputs: kept as it is
            if (src != dst) std::memcpy(dst + j * kSize, src + j * kSize, kSize);
            return;
        }
        s->visit([&](auto reader) { run(reader, src, dst, j, box); });
    }

    template <class Reader>
    void batch(const Reader& reader, uint32_t g, const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth],
               uint64_t recordCount, LeafBox boxes[kNodeWidth]) {
        Pending pending[kBatch];
        uint32_t n = 0;
        const uint32_t count = reader.primitiveCount();
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            if (!isLeaf(refs[i])) continue;
            const uint64_t first = leafFirst(refs[i]), end = std::min(first + leafCount(refs[i]), recordCount);
            for (uint64_t j = first; j < end; ++j) {
                uint32_t ids[2];  // geometryIndex, primitiveIndex
                std::memcpy(ids, src + j * kSize + 36, 8);
                if (ids[0] != g) {
                    one(src, dst, j, boxes[i]);
                } else if constexpr (!kFloats<Reader>) {
                    run(reader, src, dst, j, boxes[i]);
                } else if (ids[1] >= count) {  // not a primitive of the inputs: kept as it is
                    if (src != dst) std::memcpy(dst + j * kSize, src + j * kSize, kSize);
                } else {
                    Pending& p = pending[n++];
                    p.record = j, p.primitive = ids[1], p.slot = i;
                    std::memcpy(&p.flags, src + j * kSize + 44, 4);
                    for (uint32_t c = 0; c < 3; ++c) {
                        p.vertex[c] = reader.vertexPointer(ids[1], c);
                        __builtin_prefetch(p.vertex[c], 0, 3);
                    }
                    if (n == kBatch) finish<Reader::kVertex>(pending, n, src, dst, g, boxes), n = 0;
                }
            }
        }
        finish<Reader::kVertex>(pending, n, src, dst, g, boxes);
    }

    // The second step of batch: float vertices without a transform, in SSE registers from load to record.
    template <TriangleVertexKind V>
    static void finish(const Pending* pending, uint32_t n, const std::byte* src, std::byte* dst, uint32_t g,
                       LeafBox boxes[kNodeWidth]) {
        for (uint32_t k = 0; k < n; ++k) {
            const Pending& p = pending[k];
            std::byte* out = dst + p.record * kSize;
            __m128 v0 = loadFloatVertex<V>(p.vertex[0]);
            __m128 v1 = loadFloatVertex<V>(p.vertex[1]);
            __m128 v2 = loadFloatVertex<V>(p.vertex[2]);
            const __m128 u0 = _mm_cmpunord_ps(v0, v0), u1 = _mm_cmpunord_ps(v1, v1), u2 = _mm_cmpunord_ps(v2, v2);
            bool active = true;
            if (_mm_movemask_ps(_mm_or_ps(_mm_or_ps(u0, u1), u2))) {
                // rare: the general decode's double round trip quiets NaNs (roundTripFloat)
                const __m128 quiet = _mm_castsi128_ps(_mm_set1_epi32(0x0040'0000));
                v0 = _mm_or_ps(v0, _mm_and_ps(u0, quiet));
                v1 = _mm_or_ps(v1, _mm_and_ps(u1, quiet));
                v2 = _mm_or_ps(v2, _mm_and_ps(u2, quiet));
                active = ((_mm_movemask_ps(u0) | _mm_movemask_ps(u1) | _mm_movemask_ps(u2)) & 1) == 0;  // raw X
            }
            uint32_t flags = p.flags & ~kTriangleDegenerate;
            if (!active || isDegenerateTriangleSse(v0, v1, v2)) flags |= kTriangleDegenerate;
            // v0 v1 v2 as 9 consecutive floats: (x0 y0 z0 x1) (y1 z1 x2 y2) z2
            const __m128 t = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(0, 0, 2, 2));
            _mm_storeu_ps(reinterpret_cast<float*>(out), _mm_shuffle_ps(v0, t, _MM_SHUFFLE(2, 0, 1, 0)));
            _mm_storeu_ps(reinterpret_cast<float*>(out + 16), _mm_shuffle_ps(v1, v2, _MM_SHUFFLE(1, 0, 2, 1)));
            const float z2 = _mm_cvtss_f32(_mm_movehl_ps(v2, v2));
            std::memcpy(out + 32, &z2, 4);
            if (src != dst) {
                const uint32_t ids[2] = {g, p.primitive};
                std::memcpy(out + 36, ids, 8);
            }
            std::memcpy(out + 44, &flags, 4);
            if (active) {
                LeafBox& box = boxes[p.slot];
                box.extend(v0), box.extend(v1), box.extend(v2);
            }
        }
    }

    // Record j through any reader (whose geometry the record names).
    template <class Reader>
    static void run(const Reader& reader, const std::byte* src, std::byte* dst, uint64_t j, LeafBox& box) {
        const std::byte* in = src + j * kSize;
        std::byte* out = dst + j * kSize;
        uint32_t ids[2], flags;  // geometryIndex, primitiveIndex
        std::memcpy(ids, in + 36, 8);
        std::memcpy(&flags, in + 44, 4);
        if (ids[1] >= reader.primitiveCount()) {  // not a primitive of the inputs: kept as it is
            if (in != out) std::memcpy(out, in, kSize);
            return;
        }
        float v[3][3];
        const bool active = reader.fetch(ids[1], v);
        // Degenerate is re-decided: a triangle that has area again is hit again, and vice versa.
        flags &= ~kTriangleDegenerate;
        if (!active || isDegenerateTriangle(v)) flags |= kTriangleDegenerate;
        std::memcpy(out, v, sizeof v);
        if (in != out) std::memcpy(out + 36, ids, 8);
        std::memcpy(out + 44, &flags, 4);
        if (active)
            for (const auto& q : v) box.extend(_mm_setr_ps(q[0], q[1], q[2], 0.0f));
    }

    TriangleInputs main_, other_;
};

// The per-record refitters (used through PerRecord) turn the source record `in` into the destination record `out`
// (which may alias `in`) and extend `box` by the new record's box.

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

// All eight slots at once: lanes 0-2 of the boxes transposed into the node's arrays.
void setSlots(Node& n, const LeafBox boxes[kNodeWidth]) {
    for (uint32_t half = 0; half < 2; ++half) {
        const LeafBox* b = boxes + 4 * half;
        __m128 l0 = b[0].lower, l1 = b[1].lower, l2 = b[2].lower, l3 = b[3].lower;
        _MM_TRANSPOSE4_PS(l0, l1, l2, l3);
        _mm_storeu_ps(n.lowerX + 4 * half, l0), _mm_storeu_ps(n.lowerY + 4 * half, l1);
        _mm_storeu_ps(n.lowerZ + 4 * half, l2);
        __m128 u0 = b[0].upper, u1 = b[1].upper, u2 = b[2].upper, u3 = b[3].upper;
        _MM_TRANSPOSE4_PS(u0, u1, u2, u3);
        _mm_storeu_ps(n.upperX + 4 * half, u0), _mm_storeu_ps(n.upperY + 4 * half, u1);
        _mm_storeu_ps(n.upperZ + 4 * half, u2);
    }
}

// The union of a node's eight slots (empty slots are +inf / -inf; slot boxes never hold a NaN: they come from
// LeafBox or from this function). The lanes are combined pairwise, so the sign of a zero coordinate may differ
// from a sequential union's; no box test can tell (docs/FORMAT.md, "Update (refit)").
LeafBox nodeBox(const Node& n) {
    auto lowest = [](const float* a) {
        __m128 m = _mm_min_ps(_mm_loadu_ps(a), _mm_loadu_ps(a + 4));
        m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        return _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    };
    auto highest = [](const float* a) {
        __m128 m = _mm_max_ps(_mm_loadu_ps(a), _mm_loadu_ps(a + 4));
        m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        return _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    };
    LeafBox b;
    b.lower = _mm_movelh_ps(_mm_unpacklo_ps(lowest(n.lowerX), lowest(n.lowerY)), lowest(n.lowerZ));
    b.upper = _mm_movelh_ps(_mm_unpacklo_ps(highest(n.upperX), highest(n.upperY)), highest(n.upperZ));
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
    // Preorder numbering: every child node has a larger index than its parent, so a reverse sweep finishes the
    // children first.
    for (uint64_t k = h.nodeCount; k-- > 0;) {
        Node n;
        std::memcpy(&n, &srcNodes[k], sizeof n);
        LeafBox boxes[kNodeWidth];
        refit.leaves(srcRecords, dstRecords, n.child, h.recordCount, boxes);
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            const ChildRef ref = n.child[i];
            if (isInternal(ref)) {
                const uint32_t c = nodeIndex(ref);
                if (c > k && c < h.nodeCount) boxes[i] = nodeBox(dstNodes[c]);
            }
        }
        setSlots(n, boxes);  // empty slots keep +inf / -inf
        std::memcpy(&dstNodes[k], &n, sizeof n);
    }
    LeafBox bounds;
    if (isLeaf(h.root)) {
        ChildRef refs[kNodeWidth] = {h.root};
        LeafBox boxes[kNodeWidth];
        refit.leaves(srcRecords, dstRecords, refs, h.recordCount, boxes);
        bounds = boxes[0];
    } else if (isInternal(h.root) && nodeIndex(h.root) < h.nodeCount) {
        bounds = nodeBox(dstNodes[nodeIndex(h.root)]);
    }
    alignas(16) float lo[4], up[4];
    _mm_store_ps(lo, bounds.lower);
    _mm_store_ps(up, bounds.upper);
    h.bounds[0] = lo[0], h.bounds[1] = lo[1], h.bounds[2] = lo[2];
    h.bounds[3] = up[0], h.bounds[4] = up[1], h.bounds[5] = up[2];
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
            runRefit<PerRecord<MotionInstanceRefitter>>(job);
        else
            runRefit<PerRecord<InstanceRefitter>>(job);
        return VK_SUCCESS;
    }
    switch (h->primitiveType) {
        case VK_GEOMETRY_TYPE_AABBS_KHR: runRefit<PerRecord<AabbRefitter>>(job); break;
        case VK_GEOMETRY_TYPE_SPHERES_NV: runRefit<PerRecord<SphereRefitter>>(job); break;
        case VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV: runRefit<PerRecord<LssRefitter>>(job); break;
        default:
            if (motion)
                runRefit<PerRecord<MotionTriangleRefitter>>(job);
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
