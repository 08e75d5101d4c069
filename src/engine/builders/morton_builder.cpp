#include "engine/util/host_memory.hpp"
#include "engine/builders/morton_builder.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "engine/util/parallel_for.hpp"
#include "engine/util/simd_box.hpp"

namespace vkas {

using format::ChildRef;
using format::Node;

namespace {

// Bits per axis of the Morton code, at most: a cell is 1/16,384 of the largest centroid extent, and 42 code bits
// leave 22 for the index (more primitives take bits from the code: 10 per axis at 2^32).
constexpr uint32_t kMaxAxisBits = 14;
// The sort: one pass over all keys by the code's top 10 bits (1,024 buckets: few enough write streams for the
// caches and TLB), then each bucket, now small enough to stay in cache, by 8-bit digits of the rest.
constexpr uint32_t kTopBits = 10;
constexpr uint32_t kLowDigitBits = 8;
constexpr uint32_t kMaxLowPasses = (3 * kMaxAxisBits - kTopBits + kLowDigitBits - 1) / kLowDigitBits;
constexpr uint32_t kInsertionSortMax = 48;  // buckets up to this size: insertion sort beats counting passes

// bits[v]: the 7 bits of v moved apart to bits 0, 3, 6, ..., 18. Two lookups spread 14 bits.
struct SpreadTable {
    uint64_t bits[128];
    constexpr SpreadTable() : bits{} {
        for (uint32_t v = 0; v < 128; ++v)
            for (uint32_t k = 0; k < 7; ++k) bits[v] |= uint64_t((v >> k) & 1) << (3 * k);
    }
};
constexpr SpreadTable kSpread;
inline uint64_t spreadBits3(uint32_t v) { return kSpread.bits[v & 127] | kSpread.bits[(v >> 7) & 127] << 21; }

// A primitive's bounds from its PrimRef (lane 3, the index, cleared).
inline void load(const PrimRef& p, __m128& lo, __m128& up) {
    lo = xyz(_mm_loadu_ps(p.lower));
    up = xyz(_mm_loadu_ps(p.upper));
}

// Half-sums: the centroid without the overflow of lower + upper near the float range's ends.
inline __m128 centroid(__m128 lo, __m128 up) {
    const __m128 half = _mm_set1_ps(0.5f);
    return _mm_add_ps(_mm_mul_ps(lo, half), _mm_mul_ps(up, half));
}

// All-ones in the lanes whose value is finite (NaN and +-inf compare false).
inline __m128 finiteMask(__m128 v) {
    const __m128 abs = _mm_andnot_ps(_mm_set1_ps(-0.0f), v);
    return _mm_cmplt_ps(abs, _mm_set1_ps(std::numeric_limits<float>::infinity()));
}
inline __m128 select(__m128 mask, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b)); }

// Pass 1: the tree's bounds (with Aabb::extend's rules, as buildWideBvh computes them) and the bounds of the
// finite centroids (an infinite or NaN coordinate would stretch the grid to nothing; such centroids are clamped).
struct InputBounds {
    __m128 lower = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 upper = _mm_set1_ps(-std::numeric_limits<float>::infinity());
    __m128 centroidLower = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 centroidUpper = _mm_set1_ps(-std::numeric_limits<float>::infinity());

    void add(const PrimRef* refs, uint32_t begin, uint32_t end) {
        const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
        const __m128 negInf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
        for (uint32_t i = begin; i < end; ++i) {
            __m128 lo, up;
            load(refs[i], lo, up);
            // Aabb::extend(p) is min(p, acc) per lane: a NaN coordinate leaves the bound as it was.
            lower = _mm_min_ps(up, _mm_min_ps(lo, lower));
            upper = _mm_max_ps(up, _mm_max_ps(lo, upper));
            const __m128 c = centroid(lo, up);
            const __m128 finite = finiteMask(c);
            centroidLower = _mm_min_ps(centroidLower, select(finite, c, inf));
            centroidUpper = _mm_max_ps(centroidUpper, select(finite, c, negInf));
        }
    }
    // The bounds of the primitives after these (a later chunk), with the operands in add's order: the same bytes
    // as one add over both, zeros of either sign included (min and max return their second operand on a tie).
    void merge(const InputBounds& later) {
        lower = _mm_min_ps(later.lower, lower);
        upper = _mm_max_ps(later.upper, upper);
        centroidLower = _mm_min_ps(centroidLower, later.centroidLower);
        centroidUpper = _mm_max_ps(centroidUpper, later.centroidUpper);
    }
};

// Maps a centroid to integer grid cells [0, 2^bits) per axis: q = c * scale - offset, clamped in float (NaN and
// -inf land in cell 0, +inf in the last), so invalid input still gets a valid code. The cells are cubes (one
// scale, from the largest extent): per-axis scales would split a flat scene across its thin axis as often as along
// the others (torcs-forza: SAH cost 11.2 with per-axis scales, 7.2 with cubes; docs/PERFORMANCE.md).
struct Quantizer {
    __m128 scale, offset, lastCell;

    Quantizer(const InputBounds& b, uint32_t bits) {
        alignas(16) float lo[4], up[4], s[4] = {0, 0, 0, 0}, o[4] = {0, 0, 0, 0};
        _mm_store_ps(lo, b.centroidLower);
        _mm_store_ps(up, b.centroidUpper);
        const double cells = double(1u << bits);
        double extent = 0;  // in double: no overflow
        for (int a = 0; a < 3; ++a)
            if (up[a] >= lo[a]) extent = std::max(extent, double(up[a]) - double(lo[a]));
        for (int a = 0; a < 3; ++a) {
            if (!(up[a] >= lo[a]) || !(extent > 0)) continue;  // no finite centroid, or one cell
            s[a] = float(cells / extent);
            o[a] = float(double(lo[a]) * double(s[a]));
        }
        scale = _mm_load_ps(s);
        offset = _mm_load_ps(o);
        lastCell = _mm_set1_ps(float(cells - 1));
    }

    uint64_t code(__m128 lo, __m128 up) const {
        __m128 q = _mm_sub_ps(_mm_mul_ps(centroid(lo, up), scale), offset);
        q = _mm_min_ps(_mm_max_ps(q, _mm_setzero_ps()), lastCell);  // max(NaN, 0) is 0
        alignas(16) int32_t c[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(c), _mm_cvttps_epi32(q));
        return spreadBits3(uint32_t(c[0])) | spreadBits3(uint32_t(c[1])) << 1 | spreadBits3(uint32_t(c[2])) << 2;
    }
};

// The sort key of primitive i: its Morton code above its index. The index makes every key unique, so the sorted
// order (and the tree) is one and the same whatever sorts it, and keeps the primitives of one cell in input order.
struct KeyLayout {
    uint32_t indexBits;  // bits of the largest index, at least 1
    uint32_t axisBits;   // Morton bits per axis
    uint32_t codeBits() const { return 3 * axisBits; }
    uint64_t indexMask() const { return (uint64_t(1) << indexBits) - 1; }
    uint32_t topDigit(uint64_t key) const {
        return uint32_t(key >> (indexBits + codeBits() - kTopBits)) & ((1u << kTopBits) - 1);
    }
    // Digit p (from the lowest) of the code bits below the top digit.
    uint32_t lowDigit(uint64_t key, uint32_t p) const {
        return uint32_t(key >> (indexBits + p * kLowDigitBits)) & ((1u << kLowDigitBits) - 1);
    }
    uint32_t lowPasses() const { return (codeBits() - kTopBits + kLowDigitBits - 1) / kLowDigitBits; }

    explicit KeyLayout(uint32_t n) {
        indexBits = 1;
        while (indexBits < 32 && (uint64_t(1) << indexBits) < n) ++indexBits;
        axisBits = std::min(kMaxAxisBits, (64 - indexBits) / 3);  // >= 10: the top digit fits
    }
};

// Pass 2: the keys of refs[begin, end) and the count of each top digit.
void makeKeys(const PrimRef* refs, uint32_t begin, uint32_t end, const Quantizer& quant, const KeyLayout& layout,
              uint64_t* keys, uint32_t* topCount) {
    for (uint32_t i = begin; i < end; ++i) {
        __m128 lo, up;
        load(refs[i], lo, up);
        const uint64_t key = quant.code(lo, up) << layout.indexBits | i;
        keys[i] = key;
        topCount[layout.topDigit(key)]++;
    }
}

// Sorts the keys of one top-digit bucket, given in src[0, n), into dst[0, n) (tmp: n more keys). Stable LSD
// passes over the remaining code digits (the index bits below are in order already), skipping digits that are
// the same for every key; small buckets by insertion sort (keys are unique: any sort gives the same order).
void sortBucket(uint64_t* src, uint64_t* dst, uint64_t* tmp, uint32_t n, const KeyLayout& layout) {
    if (n <= kInsertionSortMax) {
        for (uint32_t i = 0; i < n; ++i) {
            const uint64_t key = src[i];
            uint32_t j = i;
            for (; j > 0 && dst[j - 1] > key; --j) dst[j] = dst[j - 1];
            dst[j] = key;
        }
        return;
    }
    constexpr uint32_t kDigits = 1u << kLowDigitBits;
    const uint32_t passes = layout.lowPasses();
    uint32_t count[kMaxLowPasses][kDigits] = {};
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t p = 0; p < passes; ++p) count[p][layout.lowDigit(src[i], p)]++;
    uint64_t* from = src;
    for (uint32_t p = 0; p < passes; ++p) {
        if (count[p][layout.lowDigit(from[0], p)] == n) continue;
        uint64_t* to = from == dst ? tmp : dst;
        uint32_t offset[kDigits];
        uint32_t sum = 0;
        for (uint32_t d = 0; d < kDigits; ++d) offset[d] = sum, sum += count[p][d];
        for (uint32_t i = 0; i < n; ++i) to[offset[layout.lowDigit(from[i], p)]++] = from[i];
        from = to;
    }
    if (from != dst) std::memcpy(dst, from, n * sizeof(uint64_t));
}

// A range [begin, end) of the sorted primitives and the binary splits above it.
struct Range {
    uint32_t begin, end, depth;
    uint32_t count() const { return end - begin; }
};

// Builds the tree top-down over the sorted keys; bounds come back up from the leaves. Leaves copy their sorted
// references into the output array (the contract: leaves are ranges of refs). Nodes are numbered in preorder from
// nodeBase (0, or where a part of a parallel build begins) and written to nodes[number].
class TreeWriter {
public:
    // bucketBegin[d]: the first key whose top digit is d or more (the sort's buckets; d up to 2^kTopBits).
    TreeWriter(const uint64_t* keys, const KeyLayout& layout, const uint32_t* bucketBegin, const PrimRef* sorted,
               PrimRef* out, Node* nodes, uint32_t maxLeafSize)
        : keys_(keys), indexBits_(layout.indexBits), layout_(layout), bucketBegin_(bucketBegin), sorted_(sorted),
          out_(out), nodes_(nodes), maxLeafSize_(maxLeafSize) {}

    ChildRef build(const Range& r, SimdBoxNanSpreads& box) {
        if (r.count() <= maxLeafSize_) return leaf(r, box);
        const uint32_t index = nodeBase_ + nodeCount_++;
        Range children[format::kNodeWidth];
        const uint32_t n = childRanges(r, children);
        Node node;
        for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
            if (i >= n) {
                format::setEmptySlot(node, i);
                continue;
            }
            SimdBoxNanSpreads child;
            const ChildRef ref = build(children[i], child);
            box.extend(child);
            setSlot(node, i, child, ref);
        }
        nodes_[index] = node;
        return format::makeInternalRef(index);
    }

    // The children of a node over r (more than a leaf), in slot order; returns how many. The node's range is its
    // only child at first; the child of most primitives is split until there are 8 children or every child is a
    // leaf. So every node has 8 children or only leaf children (the node-count bound of docs/FORMAT.md), and it
    // always splits its own range at least once (no endless recursion).
    uint32_t childRanges(const Range& r, Range (&children)[format::kNodeWidth]) const {
        uint32_t n = 1;
        children[0] = r;
        while (n < format::kNodeWidth) {
            int best = -1;
            uint32_t bestCount = maxLeafSize_;
            for (uint32_t i = 0; i < n; ++i)
                if (children[i].count() > bestCount) bestCount = children[i].count(), best = int(i);
            if (best < 0) break;
            const Range whole = children[best];
            split(whole, children[best], children[n++]);
        }
        // Slots in range order: the depth-first build then visits the leaves in array order (streaming reads
        // and writes), and a node's subtrees lie in the order of their primitives.
        std::sort(children, children + n, [](const Range& a, const Range& b) { return a.begin < b.begin; });
        return n;
    }

    // Slot i of `node` gets box b and reference ref.
    static void setSlot(Node& node, uint32_t i, const SimdBoxNanSpreads& b, ChildRef ref) {
        alignas(16) float lo[4], up[4];
        _mm_store_ps(lo, b.lower);
        _mm_store_ps(up, b.upper);
        format::setSlot(node, i, lo, up, ref);
    }

    uint32_t maxLeafSize() const { return maxLeafSize_; }

    // A writer over the same sorted keys for one part of a parallel build, whose nodes are numbered from nodeBase.
    TreeWriter forPart(uint32_t nodeBase) const {
        TreeWriter part = *this;
        part.nodeBase_ = nodeBase, part.nodeCount_ = 0;
        return part;
    }

    // The nodes build(r) writes (r: more than a leaf), from the same splits without writing anything.
    uint32_t countNodes(const Range& r) const {
        Range children[format::kNodeWidth];
        const uint32_t n = childRanges(r, children);
        uint32_t total = 1;
        for (uint32_t i = 0; i < n; ++i)
            if (children[i].count() > maxLeafSize_) total += countNodes(children[i]);
        return total;
    }

    ChildRef leaf(const Range& r, SimdBoxNanSpreads& box) {
        for (uint32_t i = r.begin; i < r.end; ++i) {
            __m128 lo, up;
            load(sorted_[i], lo, up);
            box.extend(lo, up);
            out_[i] = sorted_[i];
        }
        return format::makeLeafRef(r.begin, r.count());
    }

    uint32_t nodeCount() const { return nodeCount_; }

private:

    // Splits where the highest bit that differs between the range's first and last code turns to 1 (the codes
    // are sorted, so a binary search finds it). Identical codes, and every range below binary split depth
    // kSahDepthLimit, are halved: depth stays within format::kMaxTreeDepth.
    void split(const Range& r, Range& left, Range& right) const {
        uint32_t mid = r.begin + r.count() / 2;
        const uint64_t first = keys_[r.begin] >> indexBits_, last = keys_[r.end - 1] >> indexBits_;
        if (r.depth < format::kSahDepthLimit && first != last) {
            const int bit = 63 - __builtin_clzll(first ^ last);
            const uint64_t threshold = (last >> bit << bit) << indexBits_;  // common prefix, then the 1 bit
            if (uint32_t(bit) >= layout_.codeBits() - kTopBits) {
                // A bit of the top digit: every bit of the threshold below it is 0, so the first key at or above
                // the threshold is where the sort's bucket of the threshold's top digit begins (the binary search's
                // answer, without its cache misses over a large range).
                left = {r.begin, bucketBegin_[layout_.topDigit(threshold)], r.depth + 1};
                right = {left.end, r.end, r.depth + 1};
                return;
            }
            // Branch-free lower bound: the comparisons are unpredictable, a conditional move is not.
            const uint64_t* base = keys_ + r.begin;
            for (uint32_t len = r.count(); len > 1;) {
                const uint32_t half = len / 2;
                base = base[half] < threshold ? base + half : base;
                len -= half;
            }
            mid = uint32_t(base - keys_) + (*base < threshold);
        }
        left = {r.begin, mid, r.depth + 1};
        right = {mid, r.end, r.depth + 1};
    }

    const uint64_t* keys_;
    uint32_t indexBits_;
    KeyLayout layout_;
    const uint32_t* bucketBegin_;
    const PrimRef* sorted_;
    PrimRef* out_;
    Node* nodes_;
    uint32_t maxLeafSize_;
    uint32_t nodeBase_ = 0;
    uint32_t nodeCount_ = 0;
};

// A tree built on several threads: the top, down to ranges of at most partMax primitives, is planned here (the
// splits depend on the keys alone); each such range (a part) counts its nodes, which gives every part its place in
// preorder; each part is built by its own TreeWriter straight into its place; then the top's nodes are written.
// Node indices, slot boxes and unions come out as the serial TreeWriter makes them: a part's subtree is built by the
// same code, its nodes are contiguous in preorder, and every box is extended in the same order.
class ParallelTree {
public:
    ParallelTree(TreeWriter& top, const ParallelFor& parallel) : top_(top), parallel_(parallel) {}

    BvhBuildResult build(const Range& all, uint32_t partMax, Node* nodes) {
        partMax_ = partMax;
        plan(all);
        partNodes_.resize(parts_.size());
        partBoxes_.resize(parts_.size());
        partBase_.resize(parts_.size());
        parallelFor(&parallel_, uint32_t(parts_.size()), [&](uint32_t p) { partNodes_[p] = top_.countNodes(parts_[p]); });
        placeParts(0);
        parallelFor(&parallel_, uint32_t(parts_.size()), [&](uint32_t p) {
            TreeWriter writer = top_.forPart(partBase_[p]);
            writer.build(parts_[p], partBoxes_[p]);
        });
        nodes_ = nodes;
        next_ = 0;
        BvhBuildResult result;
        SimdBoxNanSpreads box;
        result.root = writeTop(0, box);
        result.nodeCount = total_;
        return result;
    }

private:
    static constexpr uint32_t kLeaf = UINT32_MAX, kPart = UINT32_MAX - 1;
    // A node of the top: its children's ranges and, per child, the top node that continues it, kLeaf, or kPart
    // (parts_[part[i]]).
    struct TopNode {
        Range children[format::kNodeWidth];
        uint32_t n;
        uint32_t next[format::kNodeWidth];
        uint32_t part[format::kNodeWidth];
    };

    // Plans the node over r (more than partMax primitives); returns its index in tops_.
    uint32_t plan(const Range& r) {
        const uint32_t self = uint32_t(tops_.size());
        tops_.emplace_back();
        TopNode t;
        t.n = top_.childRanges(r, t.children);
        for (uint32_t i = 0; i < t.n; ++i) {
            const Range& c = t.children[i];
            t.next[i] = kLeaf, t.part[i] = 0;
            if (c.count() <= top_.maxLeafSize()) continue;
            if (c.count() <= partMax_) {
                t.next[i] = kPart, t.part[i] = uint32_t(parts_.size());
                parts_.push_back(c);
            } else {
                t.next[i] = plan(c);
            }
        }
        tops_[self] = t;
        return self;
    }

    // The preorder numbers: top node t takes the next one, then its children's subtrees follow in slot order.
    void placeParts(uint32_t t) {
        const TopNode& top = tops_[t];
        ++total_;
        for (uint32_t i = 0; i < top.n; ++i) {
            if (top.next[i] == kPart) {
                partBase_[top.part[i]] = total_;
                total_ += partNodes_[top.part[i]];
            } else if (top.next[i] != kLeaf) {
                placeParts(top.next[i]);
            }
        }
    }

    // Writes top node t (at the number placeParts gave it) and the top nodes below it; returns its reference.
    ChildRef writeTop(uint32_t t, SimdBoxNanSpreads& box) {
        const TopNode& top = tops_[t];
        const uint32_t index = next_++;
        Node node;
        for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
            if (i >= top.n) {
                format::setEmptySlot(node, i);
                continue;
            }
            SimdBoxNanSpreads child;
            ChildRef ref;
            if (top.next[i] == kLeaf) {
                ref = top_.leaf(top.children[i], child);
            } else if (top.next[i] == kPart) {
                const uint32_t p = top.part[i];
                ref = format::makeInternalRef(partBase_[p]);  // more than a leaf: its root is a node
                child = partBoxes_[p];
                next_ += partNodes_[p];
            } else {
                ref = writeTop(top.next[i], child);
            }
            box.extend(child);
            TreeWriter::setSlot(node, i, child, ref);
        }
        nodes_[index] = node;
        return format::makeInternalRef(index);
    }

    TreeWriter& top_;
    const ParallelFor& parallel_;
    uint32_t partMax_ = 0;
    HostVector<TopNode> tops_;
    HostVector<Range> parts_;
    HostVector<uint32_t> partNodes_;  // how many nodes each part writes
    HostVector<SimdBoxNanSpreads> partBoxes_;
    HostVector<uint32_t> partBase_;   // the number of each part's first node
    Node* nodes_ = nullptr;
    uint32_t total_ = 0, next_ = 0;
};

// Work over all primitives goes in chunks of this many (the same chunks with threads or without).
constexpr uint32_t kChunk = 65536;
// A parallel tree's parts hold at most max(kPartMin, n / kPartsAtLeast) primitives: about a hundred parts or more,
// each worth a task.
constexpr uint32_t kPartMin = 8192, kPartsAtLeast = 128;

}  // namespace

BvhBuildResult buildMortonBvh(PrimRef* refs, uint32_t n, uint32_t maxLeafSize, Node* nodes,
                              std::byte* workspace, const ParallelFor* parallel) {
    BvhBuildResult result;
    if (n == 0) return result;
    // Every pass runs over fixed chunks, on several threads when there are: keys are unique, so the sorted order
    // is the same however it is reached, and the bounds merge in chunk order.
    const uint32_t chunks = chunkCount(n, kChunk);
    HostVector<InputBounds> chunkBounds(chunks);
    parallelForChunks(parallel, n, kChunk, [&](uint32_t c, uint64_t begin, uint64_t end) {
        chunkBounds[c].add(refs, uint32_t(begin), uint32_t(end));
    });
    InputBounds input = chunkBounds[0];
    for (uint32_t c = 1; c < chunks; ++c) input.merge(chunkBounds[c]);
    result.bounds = SimdBoxNanSpreads{input.lower, input.upper}.aabb();
    if (n <= maxLeafSize) {
        result.root = format::makeLeafRef(0, n);
        return result;
    }

    const KeyLayout layout(n);
    const Quantizer quant(input, layout.axisBits);
    // The workspace: the keys and the sort's second buffer (16 bytes a primitive), then the sorted PrimRefs.
    uint64_t* keys = reinterpret_cast<uint64_t*>(workspace);
    uint64_t* other = keys + n;
    constexpr uint32_t kBuckets = 1u << kTopBits;
    HostVector<uint32_t> chunkCounts(uint64_t(chunks) * kBuckets, 0);  // per chunk, the count of each top digit
    parallelForChunks(parallel, n, kChunk, [&](uint32_t c, uint64_t begin, uint64_t end) {
        makeKeys(refs, uint32_t(begin), uint32_t(end), quant, layout, keys, &chunkCounts[uint64_t(c) * kBuckets]);
    });

    // Scatter by the top digit into `other` (stable: each chunk writes after the chunks before it in every
    // bucket), then sort each bucket back into `keys`; the bucket's span of `other` is its second buffer once its
    // keys are counted.
    HostVector<uint32_t> bucketBegin(kBuckets + 1, 0);
    for (uint32_t d = 0; d < kBuckets; ++d) {
        uint32_t at = bucketBegin[d];
        for (uint32_t c = 0; c < chunks; ++c) {
            const uint32_t count = chunkCounts[uint64_t(c) * kBuckets + d];
            chunkCounts[uint64_t(c) * kBuckets + d] = at;  // now where chunk c's keys of digit d go
            at += count;
        }
        bucketBegin[d + 1] = at;
    }
    parallelForChunks(parallel, n, kChunk, [&](uint32_t c, uint64_t begin, uint64_t end) {
        uint32_t* offset = &chunkCounts[uint64_t(c) * kBuckets];
        for (uint64_t i = begin; i < end; ++i) other[offset[layout.topDigit(keys[i])]++] = keys[i];
    });
    // The buckets in groups of about n / 256 keys (at least 4,096), a task each.
    HostVector<uint32_t> groupBegin(1, 0);
    const uint32_t groupTarget = std::max<uint32_t>(4096, n / 256);
    for (uint32_t d = 0; d < kBuckets; ++d)
        if (bucketBegin[d + 1] - bucketBegin[groupBegin.back()] >= groupTarget) groupBegin.push_back(d + 1);
    if (groupBegin.back() != kBuckets) groupBegin.push_back(kBuckets);
    parallelFor(parallel, uint32_t(groupBegin.size() - 1), [&](uint32_t g) {
        for (uint32_t d = groupBegin[g]; d < groupBegin[g + 1]; ++d) {
            const uint32_t b = bucketBegin[d], count = bucketBegin[d + 1] - b;
            if (count) sortBucket(other + b, keys + b, other + b, count, layout);
        }
    });
    // The references in sorted order; the leaves copy them back into refs.
    PrimRef* sorted = reinterpret_cast<PrimRef*>(workspace + 16 * uint64_t(n));
    const uint64_t indexMask = layout.indexMask();
    parallelForChunks(parallel, n, kChunk, [&](uint32_t, uint64_t begin, uint64_t end) {
        for (uint64_t i = begin; i < end; ++i) sorted[i] = refs[keys[i] & indexMask];
    });

    TreeWriter writer(keys, layout, bucketBegin.data(), sorted, refs, nodes, maxLeafSize);
    const uint32_t partMax = std::max(kPartMin, n / kPartsAtLeast);
    if (parallel && n > 2 * partMax) {
        const BvhBuildResult tree = ParallelTree(writer, *parallel).build(Range{0, n, 0}, partMax, nodes);
        result.root = tree.root;
        result.nodeCount = tree.nodeCount;
        return result;
    }
    SimdBoxNanSpreads rootBox;
    result.root = writer.build(Range{0, n, 0}, rootBox);
    result.nodeCount = writer.nodeCount();
    return result;
}

}  // namespace vkas
