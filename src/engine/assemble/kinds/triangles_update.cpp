// The update (VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) of triangle geometries without motion; their gather
// and table row are in triangles.cpp.
//   gather: every active triangle, fetched by chunks on several threads; degenerate ones only with ALLOW_UPDATE.
//   refit:  the leaves re-fetched with the reader specialised for the geometry's kinds.
//   probe:  active = no NaN vertex X.
#include <immintrin.h>

#include <cstddef>
#include <cstring>
#include <optional>
#include <vector>

#include "engine/assemble/kinds/triangles_update.hpp"

#include "engine/util/host_memory.hpp"
#include "engine/assemble/kinds/triangle_vertices.hpp"
#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"
#include "engine/input/triangles.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

using namespace format;
namespace {

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

// One triangle of a leaf: the leaf in the source and destination (they may be the same bytes) and its lane.
struct LaneRef {
    ConstTriangleLeaf src;
    MutableTriangleLeaf dst;
    uint32_t lane;
    uint32_t primitive() const { return src.primitiveIndex()[lane]; }
    uint32_t geometry() const { return src.geometryIndex(lane); }
    uint32_t flags() const { return src.flags(lane); }
    // Writes the lane's positions, its indices (unless src and dst are one) and its flags.
    void write(const float (*v)[3], uint32_t flags) const {
        dst.setPositions(lane, v);
        if (static_cast<const void*>(src.base) != static_cast<const void*>(dst.base))
            dst.primitiveIndex()[lane] = primitive();
        dst.geometryAndFlags()[lane] = packGeometryAndFlags(geometry(), flags);
    }
    void keep() const {  // the lane as it is
        if (static_cast<const void*>(src.base) == static_cast<const void*>(dst.base)) return;
        for (uint32_t r = 0; r < kTriangleRows; ++r) dst.row(r)[lane] = src.row(r)[lane];
        dst.primitiveIndex()[lane] = primitive();
        dst.geometryAndFlags()[lane] = src.geometryAndFlags()[lane];
    }
};

// Format-2 triangle leaves (non-motion). Each leaf's triangles are re-fetched with the reader specialised for their
// geometry's index type, vertex format and transform (TriangleSource::visit), and the leaf box is extended while
// each triangle is written. Float vertices without a transform stay in SSE registers from load to leaf.
class TriangleRefitter {
public:
    explicit TriangleRefitter(const RefitJob& job) : main_(job), other_(job) {}

    // Refits the triangles of the leaf slots of one node and sets their boxes. Triangles whose geometry has float
    // vertices and no transform are refitted in two steps over the whole node: first their indices are read and
    // their vertices' lines requested, then the vertices are read and the leaves written; so the cache misses of
    // many triangles overlap instead of forming one dependent chain per triangle.
    void leaves(const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth], uint64_t recordCount,
                SimdBoxNanIgnored boxes[kNodeWidth]) {
        const TriangleSource* s = nullptr;
        uint32_t g = 0;
        for (uint32_t i = 0; i < kNodeWidth && !s; ++i)
            if (inside(refs[i], recordCount)) {
                g = triangleLeaf(src, leafFirst(refs[i]), leafCount(refs[i])).geometryIndex(0);
                s = main_.at(g);
            }
        if (s) {
            s->visit([&](auto reader) { batch(reader, g, src, dst, refs, recordCount, boxes); });
        } else {
            for (uint32_t i = 0; i < kNodeWidth; ++i)
                if (inside(refs[i], recordCount))
                    for (uint32_t l = 0; l < leafCount(refs[i]); ++l) one(lane(src, dst, refs[i], l), boxes[i]);
        }
    }

    // (public for PipelinedTriangleRefit, which shares the leaf rewrite)
    static constexpr uint32_t kBatch = 64;

    // A leaf inside the triangle array (always, for a structure vkas built or loaded; anything else is left alone).
    static bool inside(ChildRef ref, uint64_t recordCount) {
        return isLeaf(ref) && leafFirst(ref) <= recordCount && leafCount(ref) <= recordCount - leafFirst(ref);
    }
    static LaneRef lane(const std::byte* src, std::byte* dst, ChildRef ref, uint32_t lane) {
        return {triangleLeaf(src, leafFirst(ref), leafCount(ref)), triangleLeaf(dst, leafFirst(ref), leafCount(ref)), lane};
    }

    struct Pending {
        const std::byte* vertex[3];
        LaneRef at;
        uint32_t slot;
    };

    template <class Reader>
    static constexpr bool kFloats = Reader::kVertex != TriangleVertexKind::Other && !Reader::kTransform;

    // One triangle, through its own geometry's reader (other_, so that main_'s reader stays valid).
    void one(const LaneRef& at, SimdBoxNanIgnored& box) {
        const TriangleSource* s = other_.at(at.geometry());
        if (!s) {  // names no geometry of the inputs: kept as it is
            at.keep();
            return;
        }
        s->visit([&](auto reader) { run(reader, at, box); });
    }

    template <class Reader>
    void batch(const Reader& reader, uint32_t g, const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth],
               uint64_t recordCount, SimdBoxNanIgnored boxes[kNodeWidth]) {
        Pending pending[kBatch];
        PendingLeaf leaves[kNodeWidth];
        uint32_t n = 0, leafN = 0;
        const uint32_t count = reader.primitiveCount();
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            if (!inside(refs[i], recordCount)) continue;
            if constexpr (kFloats<Reader>) {
                // A whole leaf of this geometry's primitives (nearly every leaf): refitted four lanes at a time.
                const ConstTriangleLeaf leaf = triangleLeaf(src, leafFirst(refs[i]), leafCount(refs[i]));
                if (wholeLeaf(leaf, g, count)) {
                    PendingLeaf& p = leaves[leafN++];
                    p.src = leaf, p.dst = triangleLeaf(dst, leafFirst(refs[i]), leafCount(refs[i])), p.slot = i;
                    for (uint32_t l = 0; l < leaf.n; ++l)
                        for (uint32_t c = 0; c < 3; ++c) {
                            p.vertex[l][c] = reader.vertexPointer(leaf.primitiveIndex()[l], c);
                            __builtin_prefetch(p.vertex[l][c], 0, 3);
                        }
                    continue;
                }
            }
            for (uint32_t l = 0; l < leafCount(refs[i]); ++l) {
                const LaneRef at = lane(src, dst, refs[i], l);
                if (at.geometry() != g) {
                    one(at, boxes[i]);
                } else if constexpr (!kFloats<Reader>) {
                    run(reader, at, boxes[i]);
                } else if (at.primitive() >= count) {  // not a primitive of the inputs: kept as it is
                    at.keep();
                } else {
                    Pending& p = pending[n++];
                    p.at = at, p.slot = i;
                    for (uint32_t c = 0; c < 3; ++c) {
                        p.vertex[c] = reader.vertexPointer(at.primitive(), c);
                        __builtin_prefetch(p.vertex[c], 0, 3);
                    }
                    if (n == kBatch) finish<Reader::kVertex>(pending, n, boxes), n = 0;
                }
            }
        }
        if (n) finish<Reader::kVertex>(pending, n, boxes);
        if constexpr (kFloats<Reader>)
            for (uint32_t k = 0; k < leafN; ++k) finishLeaf<Reader::kVertex>(leaves[k], boxes);
    }

    // The nine rows of a leaf of N lanes from transposed registers (rows[c][a]: coordinate a of vertex c).
    template <uint32_t N>
    static void storeRows(float* out, const __m128 (&rows)[3][4]) {
        if constexpr (N == 4) {
            for (uint32_t c = 0; c < 3; ++c)
                for (uint32_t a = 0; a < 3; ++a) _mm_storeu_ps(out + 4 * (3 * c + a), rows[c][a]);
        } else {
            alignas(16) float r[9][4];
            for (uint32_t c = 0; c < 3; ++c)
                for (uint32_t a = 0; a < 3; ++a) _mm_store_ps(r[3 * c + a], rows[c][a]);
            for (uint32_t k = 0; k < 9; ++k)
                for (uint32_t l = 0; l < N; ++l) out[N * k + l] = r[k][l];
        }
    }

    // A leaf that finishLeaf refits: one to four lanes, all primitives of geometry g below its count.
    static bool wholeLeaf(const ConstTriangleLeaf& leaf, uint32_t g, uint32_t count) {
        if (leaf.n < 1 || leaf.n > 4) return false;
        for (uint32_t l = 0; l < leaf.n; ++l)
            if (leaf.geometryIndex(l) != g || leaf.primitiveIndex()[l] >= count) return false;
        return true;
    }

    struct PendingLeaf {
        const std::byte* vertex[4][3];
        ConstTriangleLeaf src;
        MutableTriangleLeaf dst;
        uint32_t slot;
    };

    // A whole leaf of float vertices without a transform: the lanes' vertices transposed into the leaf's rows
    // (missing lanes repeat lane 0, and are not stored), the build's degenerate test, the box from the vertices.
    // A leaf with a NaN coordinate goes through the per-lane path, whose decode decides activity and quiets NaNs.
    template <TriangleVertexKind V>
    static void finishLeaf(const PendingLeaf& p, SimdBoxNanIgnored boxes[kNodeWidth]) {
        const uint32_t n = p.src.n;
        __m128 v[3][4];  // v[c][l]: vertex c of lane l, (x, y, z, 0)
        for (uint32_t l = 0; l < 4; ++l)
            for (uint32_t c = 0; c < 3; ++c) v[c][l] = loadFloatVertex<V>(p.vertex[l < n ? l : 0][c]);
        __m128 nan = _mm_setzero_ps();
        for (uint32_t c = 0; c < 3; ++c)
            for (uint32_t l = 0; l < 4; ++l) nan = _mm_or_ps(nan, _mm_cmpunord_ps(v[c][l], v[c][l]));
        if (_mm_movemask_ps(nan)) {
            Pending lanes[4];
            for (uint32_t l = 0; l < n; ++l) {
                lanes[l].at = LaneRef{p.src, p.dst, l}, lanes[l].slot = p.slot;
                for (uint32_t c = 0; c < 3; ++c) lanes[l].vertex[c] = p.vertex[l][c];
            }
            finish<V>(lanes, n, boxes);
            return;
        }
        // rows[3 c + a]: coordinate a of vertex c, one lane each (after the transpose, row 3 of each is zero)
        __m128 rows[3][4];
        for (uint32_t c = 0; c < 3; ++c) {
            rows[c][0] = v[c][0], rows[c][1] = v[c][1], rows[c][2] = v[c][2], rows[c][3] = v[c][3];
            _MM_TRANSPOSE4_PS(rows[c][0], rows[c][1], rows[c][2], rows[c][3]);
        }
        // Degenerate: the build's rule (isDegenerateTriangleSse), lane by lane.
        int degenerate = 0;
        for (uint32_t l = 0; l < n; ++l) degenerate |= int(isDegenerateTriangleSse(v[0][l], v[1][l], v[2][l])) << l;
        // The rows, then the lane words (primitive indices are unchanged; geometry and flags re-packed).
        float* out = p.dst.row(0);
        switch (n) {
            case 4: storeRows<4>(out, rows); break;
            case 3: storeRows<3>(out, rows); break;
            case 2: storeRows<2>(out, rows); break;
            default: storeRows<1>(out, rows); break;
        }
        const bool inPlace = static_cast<const void*>(p.src.base) == static_cast<const void*>(p.dst.base);
        for (uint32_t l = 0; l < n; ++l) {
            if (!inPlace) p.dst.primitiveIndex()[l] = p.src.primitiveIndex()[l];
            uint32_t flags = p.src.flags(l) & ~kTriangleDegenerate;
            if (degenerate & (1 << l)) flags |= kTriangleDegenerate;
            p.dst.geometryAndFlags()[l] = packGeometryAndFlags(p.src.geometryIndex(l), flags);
        }
        // The leaf's box: every lane is active (no NaN); missing lanes repeat lane 0. Reduced so that among equal
        // values (zeros of either sign) the first in lane-then-vertex order wins, as in the per-lane path's
        // extends: first(A, B) = min(B, A) returns A on a tie, and it is associative.
        auto firstMin = [](__m128 a, __m128 b) { return _mm_min_ps(b, a); };
        auto firstMax = [](__m128 a, __m128 b) { return _mm_max_ps(b, a); };
        __m128 lo[4], up[4];
        for (uint32_t l = 0; l < 4; ++l) {
            lo[l] = firstMin(firstMin(v[0][l], v[1][l]), v[2][l]);
            up[l] = firstMax(firstMax(v[0][l], v[1][l]), v[2][l]);
        }
        SimdBoxNanIgnored& box = boxes[p.slot];
        box.lower = firstMin(box.lower, firstMin(firstMin(lo[0], lo[1]), firstMin(lo[2], lo[3])));
        box.upper = firstMax(box.upper, firstMax(firstMax(up[0], up[1]), firstMax(up[2], up[3])));
    }

    // The second step of batch: float vertices without a transform, in SSE registers from load to leaf.
    template <TriangleVertexKind V>
    static void finish(const Pending* pending, uint32_t n, SimdBoxNanIgnored boxes[kNodeWidth]) {
        for (uint32_t k = 0; k < n; ++k) {
            const Pending& p = pending[k];
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
            uint32_t flags = p.at.flags() & ~kTriangleDegenerate;
            if (!active || isDegenerateTriangleSse(v0, v1, v2)) flags |= kTriangleDegenerate;
            alignas(16) float v[3][4];
            _mm_store_ps(v[0], v0), _mm_store_ps(v[1], v1), _mm_store_ps(v[2], v2);
            const float w[3][3] = {{v[0][0], v[0][1], v[0][2]}, {v[1][0], v[1][1], v[1][2]}, {v[2][0], v[2][1], v[2][2]}};
            p.at.write(w, flags);
            if (active) {
                SimdBoxNanIgnored& box = boxes[p.slot];
                box.extend(v0), box.extend(v1), box.extend(v2);
            }
        }
    }

    // One triangle through any reader (whose geometry it names).
    template <class Reader>
    static void run(const Reader& reader, const LaneRef& at, SimdBoxNanIgnored& box) {
        if (at.primitive() >= reader.primitiveCount()) {  // not a primitive of the inputs: kept as it is
            at.keep();
            return;
        }
        float v[3][3];
        const bool active = reader.fetch(at.primitive(), v);
        // Degenerate is re-decided: a triangle that has area again is hit again, and vice versa.
        uint32_t flags = at.flags() & ~kTriangleDegenerate;
        if (!active || isDegenerateTriangle(v)) flags |= kTriangleDegenerate;
        at.write(v, flags);
        if (active)
            for (const auto& q : v) box.extend(_mm_setr_ps(q[0], q[1], q[2], 0.0f));
    }

    TriangleInputs main_, other_;
};

// The probe names a triangle by its leaf lane: records() walks the leaves (refit::forEachLeaf), so key() takes the
// triangle's leaf and lane instead of a record index.
struct TriangleProbe {
    TriangleInputs inputs;
    explicit TriangleProbe(const RefitJob& job) : inputs(job) {}
    template <class Fn>
    void forEachKey(const std::byte* block, const Fn& fn) const {
        const std::byte* recs = records(block);
        refit::forEachLeaf(block, [&](ChildRef ref) {
            const ConstTriangleLeaf leaf = triangleLeaf(recs, leafFirst(ref), leafCount(ref));
            for (uint32_t l = 0; l < leaf.n; ++l) fn(refit::RecordKey{leaf.geometryIndex(l), leaf.primitiveIndex()[l]});
        });
    }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        float v[3][3];
        const TriangleSource* t = inputs.at(g);
        active = storable = t && t->fetch(i, v);
    }
};

// The refit of a structure of one triangle geometry with float vertices and no transform (most meshes), in two
// passes, so that the memory latency of the input (a random index and three random vertices a triangle) overlaps
// across many leaves instead of a node's few:
//   1. forward over the nodes, every leaf slot: a leaf goes through a pipeline of kAhead leaves in flight (its
//      index entries requested when it enters, its vertices requested kStage leaves later, the leaf rewritten
//      (TriangleRefitter::finishLeaf) and its box written into its node slot kStage leaves after that); a leaf that
//      is not of whole lanes of the geometry's primitives is refitted at once by TriangleRefitter's general path;
//   2. backward over the nodes (children after parents in preorder), every internal slot gets its child's box.
// The same bytes as refit::refitTree with TriangleRefitter: leaf boxes and node boxes are the same unions.
class PipelinedTriangleRefit {
public:
    template <class Reader>
    static void run(const RefitJob& job, const Reader& reader) {
        format::Header h;
        std::memcpy(&h, job.src, sizeof h);
        refit::copyUnchangedParts(job, h);
        const auto* srcNodes = reinterpret_cast<const Node*>(job.src + h.nodeOffset);
        auto* dstNodes = reinterpret_cast<Node*>(job.dst + h.nodeOffset);
        if (job.src != job.dst) std::memcpy(dstNodes, srcNodes, uint64_t(h.nodeCount) * sizeof(Node));
        const std::byte* srcRecords = job.src + h.recordOffset;
        std::byte* dstRecords = job.dst + h.recordOffset;
        TriangleRefitter general(job);
        const uint32_t count = reader.primitiveCount();

        Entry ring[kAhead];
        uint64_t pushed = 0;
        auto stageVertices = [&](Entry& e) {
            for (uint32_t l = 0; l < e.leaf.src.n; ++l)
                for (uint32_t c = 0; c < 3; ++c) {
                    e.leaf.vertex[l][c] = reader.vertexPointer(e.leaf.src.primitiveIndex()[l], c);
                    __builtin_prefetch(e.leaf.vertex[l][c], 0, 3);
                }
        };
        auto stageFinish = [&](Entry& e) {
            SimdBoxNanIgnored boxes[kNodeWidth];
            e.leaf.slot = 0;
            TriangleRefitter::finishLeaf<Reader::kVertex>(e.leaf, boxes);
            setSlot(*e.node, e.slot, boxes[0]);
        };
        auto slotDone = [&](Node& node, uint32_t slot, ChildRef ref) {
            if (!TriangleRefitter::inside(ref, h.recordCount)) return setSlot(node, slot, SimdBoxNanIgnored{});
            const ConstTriangleLeaf leaf = triangleLeaf(srcRecords, leafFirst(ref), leafCount(ref));
            if (!TriangleRefitter::wholeLeaf(leaf, 0, count)) {
                ChildRef refs[kNodeWidth] = {ref};
                SimdBoxNanIgnored boxes[kNodeWidth];
                general.leaves(srcRecords, dstRecords, refs, h.recordCount, boxes);
                return setSlot(node, slot, boxes[0]);
            }
            Entry& e = ring[pushed % kAhead];
            e.leaf.src = leaf, e.leaf.dst = triangleLeaf(dstRecords, leafFirst(ref), leafCount(ref));
            e.node = &node, e.slot = slot;
            for (uint32_t l = 0; l < leaf.n; ++l)
                if (const std::byte* index = reader.indexPointer(leaf.primitiveIndex()[l])) __builtin_prefetch(index, 0, 3);
            ++pushed;
            if (pushed > kStage) stageVertices(ring[(pushed - 1 - kStage) % kAhead]);
            if (pushed > 2 * kStage) stageFinish(ring[(pushed - 1 - 2 * kStage) % kAhead]);
        };
        for (uint64_t k = 0; k < h.nodeCount; ++k) {
            // The leaves of a node a few ahead: a node's leaves lie between its subtrees' (leaf order is
            // depth-first), so their addresses jump and no hardware prefetcher follows them.
            if (k + kNodesAhead < h.nodeCount)
                for (const ChildRef ref : srcNodes[k + kNodesAhead].child)
                    if (TriangleRefitter::inside(ref, h.recordCount)) {
                        const std::byte* leaf = srcRecords + kTriangleBytes * leafFirst(ref);
                        for (uint64_t at = 0; at < kTriangleBytes * leafCount(ref); at += 64) __builtin_prefetch(leaf + at, 0, 3);
                    }
            for (uint32_t i = 0; i < kNodeWidth; ++i)
                if (isLeaf(srcNodes[k].child[i])) slotDone(dstNodes[k], i, srcNodes[k].child[i]);
        }
        // The root as a leaf: its box is the header's (a one-slot node on the side).
        Node rootSlot;
        const bool rootLeaf = isLeaf(h.root);
        if (rootLeaf) slotDone(rootSlot, 0, h.root);
        // Drain the pipeline in order.
        for (uint64_t j = pushed > kStage ? pushed - kStage : 0; j < pushed; ++j) stageVertices(ring[j % kAhead]);
        for (uint64_t j = pushed > 2 * kStage ? pushed - 2 * kStage : 0; j < pushed; ++j) stageFinish(ring[j % kAhead]);

        for (uint64_t k = h.nodeCount; k-- > 0;)
            for (uint32_t i = 0; i < kNodeWidth; ++i) {
                const ChildRef ref = srcNodes[k].child[i];
                if (!isInternal(ref)) {
                    if (!isLeaf(ref)) setSlot(dstNodes[k], i, SimdBoxNanIgnored{});  // empty (or unknown) slots
                    continue;
                }
                const uint32_t c = nodeIndex(ref);
                setSlot(dstNodes[k], i, c > k && c < h.nodeCount ? refit::nodeBox(dstNodes[c]) : SimdBoxNanIgnored{});
            }
        SimdBoxNanIgnored bounds;
        if (rootLeaf) {
            bounds.lower = _mm_setr_ps(rootSlot.lowerX[0], rootSlot.lowerY[0], rootSlot.lowerZ[0], 0.0f);
            bounds.upper = _mm_setr_ps(rootSlot.upperX[0], rootSlot.upperY[0], rootSlot.upperZ[0], 0.0f);
        } else if (isInternal(h.root) && nodeIndex(h.root) < h.nodeCount) {
            bounds = refit::nodeBox(dstNodes[nodeIndex(h.root)]);
        }
        refit::finishHeader(job, h, bounds);
    }

private:
    static constexpr uint32_t kStage = 8;           // leaves between requesting indices, vertices, and using them
    static constexpr uint32_t kAhead = 2 * kStage + 1;
    static constexpr uint64_t kNodesAhead = 4;      // nodes between requesting their leaves' records and reading them
    struct Entry {
        TriangleRefitter::PendingLeaf leaf;
        Node* node;
        uint32_t slot;
    };
    static void setSlot(Node& n, uint32_t i, const SimdBoxNanIgnored& b) {  // (its reference stays)
        alignas(16) float lo[4], up[4];
        _mm_store_ps(lo, b.lower);
        _mm_store_ps(up, b.upper);
        format::setSlotBox(n, i, lo, up);
    }
};

}  // namespace

void refitTriangles(const RefitJob& job) {
    if (job.info->geometryCount == 1 && job.ranges[0].primitiveCount != 0) {
        const TriangleSource source(buildGeometry(*job.info, 0).geometry.triangles, job.ranges[0]);
        const bool pipelined = source.visit([&](auto reader) {
            using Reader = decltype(reader);
            if constexpr (Reader::kVertex != TriangleVertexKind::Other && !Reader::kTransform) {
                PipelinedTriangleRefit::run(job, reader);
                return true;
            } else {
                return false;
            }
        });
        if (pipelined) return;
    }
    refit::runRefit<TriangleRefitter>(job);
}

ActivityViolation triangleActivity(const RefitJob& job) {
    TriangleProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace vkas
