// Triangle geometries (VK_GEOMETRY_TYPE_TRIANGLES_KHR) without motion: format::TriangleRecord.
//   gather: every active triangle, fetched by chunks on several threads; degenerate ones only with ALLOW_UPDATE.
//   refit:  the records re-fetched leaf by leaf with the reader specialised for the geometry's kinds.
//   probe:  active = no NaN vertex X.
#include <immintrin.h>

#include <cstddef>
#include <cstring>
#include <optional>
#include <vector>

#include "engine/build/kinds/kind.hpp"
#include "engine/build/refit_tree.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/triangles.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

using namespace format;

namespace {

// Fetches the active triangles of every triangle geometry into temp[] and refs[]; returns how many.
// Triangle number k of the build (geometries in order) is fetched into temp[k] by chunks, on several threads when
// the job has a ParallelFor; then the refs of the kept triangles are packed in order. refs[j].index names the
// triangle's temp slot, so the output does not depend on the chunking.
uint32_t gatherTriangles(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<TriangleRecord*>(tempBytes);
    const auto& info = *job.info;
    const bool keepDegenerate = keepsDegenerate(info);
    struct Chunk {
        uint32_t geometry, begin, end;
        uint64_t base;  // build-wide number of the geometry's first triangle
    };
    constexpr uint32_t kChunk = 16384;
    std::vector<Chunk> chunks;
    uint64_t base = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const uint32_t count = job.ranges[g].primitiveCount;
        if (buildGeometry(info, g).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR)
            for (uint32_t b = 0; b < count; b += kChunk) chunks.push_back({g, b, std::min(count, b + kChunk), base});
        base += count;
    }
    auto fetchChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        const auto& geom = buildGeometry(info, ch.geometry);
        TriangleSource source(geom.geometry.triangles, job.ranges[ch.geometry]);
        const uint32_t flags = recordFlags(geom.flags);
        // The reader specialised for the geometry's index type, vertex format and transform (no per-vertex dispatch).
        source.visit([&](auto reader) {
            for (uint32_t i = ch.begin; i < ch.end; ++i) {
                const uint64_t k = ch.base + i;
                TriangleRecord& rec = temp[k];
                refs[k].pad = 0;  // not kept
                if (!reader.fetch(i, rec.v)) continue;  // inactive: never hit, never updated back to life
                rec.geometryIndex = ch.geometry;
                rec.primitiveIndex = i;
                rec.flags = flags;
                if (isDegenerateTriangle(rec.v)) {
                    if (!keepDegenerate) continue;
                    rec.flags |= kTriangleDegenerate;
                }
                Aabb b;
                for (auto& v : rec.v) b.extend(Vec3{v[0], v[1], v[2]});
                setPrimRef(refs[k], uint32_t(k), b);
                refs[k].pad = 1;  // kept
            }
        });
    };
    parallelFor(job.parallel, uint32_t(chunks.size()), fetchChunk);
    // Pack the refs of the kept triangles in order. The leading chunks whose triangles were all kept (usually all of
    // them) stay in place and only clear their flags, in parallel; the rest is packed serially.
    std::vector<uint8_t> whole(chunks.size());
    auto checkChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        bool all = true;
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) all = all && refs[k].pad != 0;
        if (all)
            for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) refs[k].pad = 0;
        whole[c] = all;
    };
    parallelFor(job.parallel, uint32_t(chunks.size()), checkChunk);
    uint32_t n = 0;
    size_t c = 0;
    for (; c < chunks.size() && whole[c] && chunks[c].base + chunks[c].begin == n; ++c)
        n += chunks[c].end - chunks[c].begin;
    for (; c < chunks.size(); ++c) {
        const Chunk& ch = chunks[c];
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k)
            if (whole[c] || refs[k].pad) {
                refs[n] = refs[k];
                refs[n++].pad = 0;
            }
    }
    return n;
}

// The triangle readers of an update's geometries, one geometry at a time (records come in leaf order, so the
// geometry changes rarely for big geometries and constructing one reader per change stays cheap for many small ones;
// no per-geometry array: a structure may have a million geometries).
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
                SimdBoxNanIgnored boxes[kNodeWidth]) {
        const TriangleSource* s = nullptr;
        uint32_t g = 0;
        for (uint32_t i = 0; i < kNodeWidth && !s; ++i)
            if (format::isLeaf(refs[i]) && format::leafFirst(refs[i]) < recordCount) {
                g = loadUnaligned<uint32_t>(src + format::leafFirst(refs[i]) * kSize + kIdsAt);
                s = main_.at(g);
            }
        if (s) {
            s->visit([&](auto reader) { batch(reader, g, src, dst, refs, recordCount, boxes); });
        } else {
            for (uint32_t i = 0; i < kNodeWidth; ++i)
                if (format::isLeaf(refs[i])) {
                    const uint64_t first = format::leafFirst(refs[i]), end = std::min(first + format::leafCount(refs[i]), recordCount);
                    for (uint64_t j = first; j < end; ++j) one(src, dst, j, boxes[i]);
                }
        }
    }

private:
    static constexpr size_t kSize = sizeof(TriangleRecord);
    // Where a record's fields are: the refit reads and writes records as bytes (they may alias across src and dst).
    static constexpr size_t kIdsAt = offsetof(TriangleRecord, geometryIndex);  // geometryIndex, primitiveIndex
    static constexpr size_t kFlagsAt = offsetof(TriangleRecord, flags);
    static constexpr size_t kLastCoordinateAt = offsetof(TriangleRecord, v) + 8 * sizeof(float);  // v[2][2]
    static_assert(offsetof(TriangleRecord, primitiveIndex) == kIdsAt + 4);
    static constexpr uint32_t kBatch = 64;

    struct Pending {
        const std::byte* vertex[3];
        uint64_t record;
        uint32_t primitive, flags, slot;
    };

    template <class Reader>
    static constexpr bool kFloats = Reader::kVertex != TriangleVertexKind::Other && !Reader::kTransform;

    // One record, through its own geometry's reader (other_, so that main_'s reader stays valid).
    void one(const std::byte* src, std::byte* dst, uint64_t j, SimdBoxNanIgnored& box) {
        const uint32_t g = loadUnaligned<uint32_t>(src + j * kSize + kIdsAt);
        const TriangleSource* s = other_.at(g);
        if (!s) {  // names no geometry of the inputs: kept as it is
            if (src != dst) std::memcpy(dst + j * kSize, src + j * kSize, kSize);
            return;
        }
        s->visit([&](auto reader) { run(reader, src, dst, j, box); });
    }

    template <class Reader>
    void batch(const Reader& reader, uint32_t g, const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth],
               uint64_t recordCount, SimdBoxNanIgnored boxes[kNodeWidth]) {
        Pending pending[kBatch];
        uint32_t n = 0;
        const uint32_t count = reader.primitiveCount();
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            if (!format::isLeaf(refs[i])) continue;
            const uint64_t first = format::leafFirst(refs[i]), end = std::min(first + format::leafCount(refs[i]), recordCount);
            for (uint64_t j = first; j < end; ++j) {
                uint32_t ids[2];  // geometryIndex, primitiveIndex
                std::memcpy(ids, src + j * kSize + kIdsAt, 8);
                if (ids[0] != g) {
                    one(src, dst, j, boxes[i]);
                } else if constexpr (!kFloats<Reader>) {
                    run(reader, src, dst, j, boxes[i]);
                } else if (ids[1] >= count) {  // not a primitive of the inputs: kept as it is
                    if (src != dst) std::memcpy(dst + j * kSize, src + j * kSize, kSize);
                } else {
                    Pending& p = pending[n++];
                    p.record = j, p.primitive = ids[1], p.slot = i;
                    std::memcpy(&p.flags, src + j * kSize + kFlagsAt, 4);
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
                       SimdBoxNanIgnored boxes[kNodeWidth]) {
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
            std::memcpy(out + kLastCoordinateAt, &z2, 4);
            if (src != dst) {
                const uint32_t ids[2] = {g, p.primitive};
                std::memcpy(out + kIdsAt, ids, 8);
            }
            std::memcpy(out + kFlagsAt, &flags, 4);
            if (active) {
                SimdBoxNanIgnored& box = boxes[p.slot];
                box.extend(v0), box.extend(v1), box.extend(v2);
            }
        }
    }

    // Record j through any reader (whose geometry the record names).
    template <class Reader>
    static void run(const Reader& reader, const std::byte* src, std::byte* dst, uint64_t j, SimdBoxNanIgnored& box) {
        const std::byte* in = src + j * kSize;
        std::byte* out = dst + j * kSize;
        uint32_t ids[2], flags;  // geometryIndex, primitiveIndex
        std::memcpy(ids, in + kIdsAt, 8);
        std::memcpy(&flags, in + kFlagsAt, 4);
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
        if (in != out) std::memcpy(out + kIdsAt, ids, 8);
        std::memcpy(out + kFlagsAt, &flags, 4);
        if (active)
            for (const auto& q : v) box.extend(_mm_setr_ps(q[0], q[1], q[2], 0.0f));
    }

    TriangleInputs main_, other_;
};

struct TriangleProbe {
    TriangleInputs inputs;
    explicit TriangleProbe(const RefitJob& job) : inputs(job) {}
    refit::RecordKey key(const std::byte* records, uint64_t j) const { return refit::recordKeyOf<TriangleRecord>(records, j); }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        float v[3][3];
        const TriangleSource* t = inputs.at(g);
        active = storable = t && t->fetch(i, v);
    }
};

void refitTriangles(const RefitJob& job) { refit::runRefit<TriangleRefitter>(job); }

ActivityViolation triangleActivity(const RefitJob& job) {
    TriangleProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kTriangleKind{gatherTriangles, refitTriangles, triangleActivity};

}  // namespace vkas
