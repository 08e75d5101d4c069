// The part of an update (refit.hpp) that is the same for every kind of record: the bottom-up sweep over the nodes,
// which asks a kind's refitter for the new records and boxes of each node's leaf slots, and the update-activity
// check, which asks a kind's probe about each primitive. The kinds (assemble/kinds/) instantiate these templates.
#pragma once

#include <immintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "engine/util/host_memory.hpp"
#include "engine/assemble/refit.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/util/math.hpp"
#include "engine/util/simd_box.hpp"

namespace vkas::refit {

using format::ChildRef;
using format::kNodeWidth;
using format::Node;
using format::isInternal;
using format::isLeaf;
using format::leafCount;
using format::leafFirst;
using format::nodeIndex;

// Refitters (`leaves`) turn the source records of the leaf slots of one node into destination records (which may
// alias them) and set each leaf slot's box to the union of its new records' boxes. A record whose primitive is not valid any more (invalid
// usage that validation reports: it became inactive, its box is inverted, its instance names no structure) is
// kept but never hit, and adds nothing to the box. PerRecord adapts the refitters that work one record at a time.
template <class RecordRefitter>
struct PerRecord {
    RecordRefitter refit;
    explicit PerRecord(const RefitJob& job) : refit(job) {}
    void leaves(const std::byte* src, std::byte* dst, const ChildRef refs[kNodeWidth], uint64_t recordCount,
                SimdBoxNanIgnored boxes[kNodeWidth]) {
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            if (!format::isLeaf(refs[i])) continue;
            const uint64_t first = format::leafFirst(refs[i]), end = std::min(first + format::leafCount(refs[i]), recordCount);
            Aabb b;
            for (uint64_t j = first; j < end; ++j)
                refit(src + j * RecordRefitter::kSize, dst + j * RecordRefitter::kSize, b);
            boxes[i].extend(b);
        }
    }
};

// All eight slots at once: lanes 0-2 of the boxes transposed into the node's arrays.
inline void setSlots(Node& n, const SimdBoxNanIgnored boxes[kNodeWidth]) {
    for (uint32_t half = 0; half < 2; ++half) {
        const SimdBoxNanIgnored* b = boxes + 4 * half;
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
// SimdBoxNanIgnored or from this function). The lanes are combined pairwise, so the sign of a zero coordinate may differ
// from a sequential union's; no box test can tell (docs/FORMAT.md, "Update (refit)").
inline SimdBoxNanIgnored nodeBox(const Node& n) {
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
    SimdBoxNanIgnored b;
    b.lower = _mm_movelh_ps(_mm_unpacklo_ps(lowest(n.lowerX), lowest(n.lowerY)), lowest(n.lowerZ));
    b.upper = _mm_movelh_ps(_mm_unpacklo_ps(highest(n.upperX), highest(n.upperY)), highest(n.upperZ));
    return b;
}

// Into another structure: the parts a refit does not change (header, geometry table, the zeroed gaps, and what
// follows the records: the zero tail of triangle leaves, layout.hpp).
inline void copyUnchangedParts(const RefitJob& job, const format::Header& h) {
    if (job.src == job.dst) return;
    const uint64_t nodeEnd = h.nodeOffset + uint64_t(h.nodeCount) * sizeof(Node);
    std::memcpy(job.dst, job.src, h.nodeOffset);
    std::memcpy(job.dst + nodeEnd, job.src + nodeEnd, h.recordOffset - nodeEnd);
    const uint64_t recordEnd = h.recordOffset + uint64_t(h.recordCount) * recordSize(h.type, h.primitiveType, h.buildFlags);
    if (h.usedSize > recordEnd) std::memcpy(job.dst + recordEnd, job.src + recordEnd, h.usedSize - recordEnd);
}

// The header's bounds from the root's new box, and the header written.
inline void finishHeader(const RefitJob& job, format::Header& h, const SimdBoxNanIgnored& bounds) {
    alignas(16) float lo[4], up[4];
    _mm_store_ps(lo, bounds.lower);
    _mm_store_ps(up, bounds.upper);
    h.bounds[0] = lo[0], h.bounds[1] = lo[1], h.bounds[2] = lo[2];
    h.bounds[3] = up[0], h.bounds[4] = up[1], h.bounds[5] = up[2];
    std::memcpy(job.dst, &h, sizeof h);
}

// The refit proper. Reads every node and record of src once and writes the same byte ranges of dst.
template <class Refitter>
void refitTree(const RefitJob& job, Refitter& refit) {
    format::Header h;
    std::memcpy(&h, job.src, sizeof h);
    copyUnchangedParts(job, h);
    const auto* srcNodes = reinterpret_cast<const Node*>(job.src + h.nodeOffset);
    auto* dstNodes = reinterpret_cast<Node*>(job.dst + h.nodeOffset);
    const std::byte* srcRecords = job.src + h.recordOffset;
    std::byte* dstRecords = job.dst + h.recordOffset;
    // Preorder numbering: every child node has a larger index than its parent, so a reverse sweep finishes the
    // children first.
    for (uint64_t k = h.nodeCount; k-- > 0;) {
        Node n;
        std::memcpy(&n, &srcNodes[k], sizeof n);
        SimdBoxNanIgnored boxes[kNodeWidth];
        refit.leaves(srcRecords, dstRecords, n.child, h.recordCount, boxes);
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            const ChildRef ref = n.child[i];
            if (format::isInternal(ref)) {
                const uint32_t c = format::nodeIndex(ref);
                if (c > k && c < h.nodeCount) boxes[i] = nodeBox(dstNodes[c]);
            }
        }
        setSlots(n, boxes);  // empty slots keep +inf / -inf
        std::memcpy(&dstNodes[k], &n, sizeof n);
    }
    SimdBoxNanIgnored bounds;
    if (format::isLeaf(h.root)) {
        ChildRef refs[kNodeWidth] = {h.root};
        SimdBoxNanIgnored boxes[kNodeWidth];
        refit.leaves(srcRecords, dstRecords, refs, h.recordCount, boxes);
        bounds = boxes[0];
    } else if (format::isInternal(h.root) && format::nodeIndex(h.root) < h.nodeCount) {
        bounds = nodeBox(dstNodes[nodeIndex(h.root)]);
    }
    finishHeader(job, h, bounds);
}

template <class Refitter>
void runRefit(const RefitJob& job) {
    Refitter r(job);
    refitTree(job, r);
}

// The (geometry, primitive) a record names.
struct RecordKey {
    uint32_t geometry, primitive;
};

// Calls fn(ref) for every leaf of the structure at `block`, in the order of their records (leafFirst).
template <class Fn>
void forEachLeaf(const std::byte* block, const Fn& fn) {
    const format::Header* h = format::header(block);
    HostVector<ChildRef> leaves;
    if (isLeaf(h->root)) leaves.push_back(h->root);
    const Node* nodes = format::nodes(block);
    for (uint64_t k = 0; k < h->nodeCount; ++k)
        for (const ChildRef ref : nodes[k].child)
            if (isLeaf(ref)) leaves.push_back(ref);
    std::sort(leaves.begin(), leaves.end(), [](ChildRef a, ChildRef b) { return leafFirst(a) < leafFirst(b); });
    for (const ChildRef ref : leaves) fn(ref);
}

// VUIDs 03663 / 03664 with a kind's probe: probe.key(records, j) names record j's primitive (or, for records that are
// not an array, probe.forEachKey(block, fn) calls fn with every stored primitive's key in record order),
// probe.probe(g, i, active, storable) says whether input primitive i of geometry g is active (not inactive by the
// spec's rules: NaN, reference 0) and storable (what a build would store: active and valid; degenerate ones count,
// as ALLOW_UPDATE builds keep them).
template <class Probe>
ActivityViolation checkActivity(const RefitJob& job, Probe& probe) {
    const format::Header* h = format::header(job.src);
    const auto& info = *job.info;
    HostVector<uint64_t> base(info.geometryCount + 1, 0);
    for (uint32_t g = 0; g < info.geometryCount; ++g) base[g + 1] = base[g] + job.ranges[g].primitiveCount;
    HostVector<uint64_t> stored((base[info.geometryCount] + 63) / 64, 0);
    ActivityViolation found{};
    bool stop = false;
    auto visitKey = [&](const RecordKey& key) {
        if (stop) return;
        if (key.geometry >= info.geometryCount || key.primitive >= job.ranges[key.geometry].primitiveCount) return;
        const uint64_t bit = base[key.geometry] + key.primitive;
        stored[bit / 64] |= 1ull << (bit % 64);
        bool active, storable;
        probe.probe(key.geometry, key.primitive, active, storable);
        if (!active) found = {3663, key.geometry, key.primitive}, stop = true;
    };
    if constexpr (requires { probe.forEachKey(job.src, visitKey); }) {
        probe.forEachKey(job.src, visitKey);
    } else {
        const std::byte* records = job.src + h->recordOffset;
        for (uint64_t j = 0; j < h->recordCount && !stop; ++j) visitKey(probe.key(records, j));
    }
    if (stop) return found;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        for (uint32_t i = 0; i < job.ranges[g].primitiveCount; ++i) {
            const uint64_t bit = base[g] + i;
            if (stored[bit / 64] & (1ull << (bit % 64))) continue;
            bool active, storable;
            probe.probe(g, i, active, storable);
            if (storable) return {3664, g, i};
        }
    }
    return {};
}

// A probe's key for records that start their identification with geometryIndex, primitiveIndex (every bottom-level
// record type): Record is the record type, kStride its array stride.
template <class Record, size_t kStride = sizeof(Record)>
inline RecordKey recordKeyOf(const std::byte* records, uint64_t j) {
    const auto* r = reinterpret_cast<const Record*>(records + j * kStride);
    return {r->geometryIndex, r->primitiveIndex};
}

}  // namespace vkas::refit
