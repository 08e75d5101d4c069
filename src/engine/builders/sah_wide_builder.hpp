// The top-down binned-SAH splitter behind sah_builder.cpp (WideBuilder): the bins, the split of a range (sampled
// binning for large ranges), the in-place and the stable partitions, and the 8-wide node a range becomes. Internal to
// the builders: only sah_builder.cpp includes it (buildSahBvh, buildBinarySahTree and the parallel layout).
#pragma once

#include <immintrin.h>
#include <vulkan/vulkan_core.h>

#include <algorithm>
#include <cstdint>
#include <limits>

#include "engine/builders/binary_tree.hpp"
#include "engine/builders/centroid_bins.hpp"
#include "engine/builders/tree_builder.hpp"
#include "engine/util/host_memory.hpp"
#include "engine/util/parallel_for.hpp"
#include "engine/util/simd_box.hpp"

namespace vkas::sah_detail {

using format::ChildRef;
using format::Node;

constexpr int kBins = 32;

// The bins per axis for a range of `count` primitives: 32 for large ranges; below `fewBinsBelow` primitives
// (BvhBuildSettings) 8, or as many as primitives, at least 4. Most splits are of small ranges, and clearing and
// sweeping the bins costs them more than binning their primitives; 8 bins there cost about 1% of SAH cost.
constexpr uint32_t kFewBins = 8;
inline uint32_t binCountFor(uint32_t count, uint32_t fewBinsBelow) {
    if (count < fewBinsBelow) return std::max<uint32_t>(4, std::min(count, kFewBins));
    return std::max<uint32_t>(4, std::min<uint32_t>(count, kBins));
}

// Ranges of at least this many primitives are partitioned stably through a spare array (WideBuilder::stablePartition).
constexpr uint32_t kStablePartitionMin = 65536;

struct Range {
    uint32_t begin = 0, end = 0;
    uint32_t depth = 0;
    Aabb bounds;
    // Where the range's refs are: the refs array, or the same indices of the spare array, where a stable partition
    // left them (WideBuilder::stablePartition; they return to the refs array before anything but a stable partition
    // touches them).
    bool inSpare = false;
    uint32_t count() const { return end - begin; }
};

class WideBuilder {
public:
    // Writes the nodes straight to `nodes` (a serial build: the destination, which the size query's bound fits).
    WideBuilder(PrimRef* refs, const BvhBuildSettings& s, Node* nodes, const ParallelFor* parallel = nullptr)
        : refs_(refs), settings_(s), nodes_(nodes), parallel_(parallel) {}
    // Appends the nodes to `nodes` (a part of a parallel build: its node count is known only at the end, and a
    // worst-case array would cost more to allocate and clear than building the part).
    WideBuilder(PrimRef* refs, const BvhBuildSettings& s, HostVector<Node>* nodes, const ParallelFor* parallel = nullptr)
        : refs_(refs), settings_(s), nodes_(nullptr), growing_(nodes), parallel_(parallel) {}

    // With a deferral threshold, ranges of at most that many primitives (but more than a leaf) are not built:
    // they are recorded in deferred() and their place is a placeholder reference, deferredRef(k).
    void deferRangesUpTo(uint32_t threshold) { deferThreshold_ = threshold; }
    // Gives large ranges a buffer of as many refs as the build has (see stablePartition).
    void useSpare(PrimRef* spare) { spare_ = spare; }
    const HostVector<Range>& deferred() const { return deferred_; }
    static constexpr uint64_t kDeferredKind = 3;  // a ChildRef kind the format never uses
    static ChildRef deferredRef(uint64_t k) { return (kDeferredKind << format::kKindShift) | k; }
    static bool isDeferred(ChildRef r) { return (r >> format::kKindShift) == kDeferredKind; }

    ChildRef build(const Range& r) {
        if (r.count() <= settings_.maxLeafSize) {
            returnToRefs(r);
            return format::makeLeafRef(r.begin, r.count());
        }
        if (r.count() <= deferThreshold_) {
            deferred_.push_back(r);
            return deferredRef(deferred_.size() - 1);
        }
        uint32_t index = nodeCount_++;
        if (growing_) growing_->emplace_back();
        Range children[format::kNodeWidth];
        uint32_t n = 1;
        children[0] = r;
        while (n < format::kNodeWidth) {
            int best = -1;
            float bestArea = -1.0f;
            for (uint32_t i = 0; i < n; ++i) {
                if (children[i].count() <= settings_.maxLeafSize) continue;
                float area = children[i].bounds.halfArea();
                if (area > bestArea) {
                    bestArea = area;
                    best = int(i);
                }
            }
            // A child of more than a leaf splits even when its area is NaN (infinite coordinates): every node keeps
            // 8 children or only leaves (the node bound of the build sizes, docs/FORMAT.md), and a node never has
            // its own range as its only child (which would recurse forever).
            for (uint32_t i = 0; i < n && best < 0; ++i)
                if (children[i].count() > settings_.maxLeafSize) best = int(i);
            if (best < 0) break;
            Range left, right;
            split(children[best], left, right);
            children[best] = left;
            children[n++] = right;
        }
        Node node;
        for (uint32_t i = n; i < format::kNodeWidth; ++i) format::setEmptySlot(node, i);
        for (uint32_t i = 0; i < n; ++i) {
            const Aabb& b = children[i].bounds;
            const float lower[3] = {b.lower.x, b.lower.y, b.lower.z}, upper[3] = {b.upper.x, b.upper.y, b.upper.z};
            format::setSlot(node, i, lower, upper, build(children[i]));
        }
        (growing_ ? (*growing_)[index] : nodes_[index]) = node;
        return format::makeInternalRef(index);
    }

    uint32_t nodeCount() const { return nodeCount_; }

    // One binary SAH split of r (more than one primitive) into left and right, as build() splits a node's children,
    // both in the refs array.
    void splitRange(const Range& r, Range& left, Range& right) {
        split(r, left, right);
        returnToRefs(left);
        returnToRefs(right);
    }

    // Copies a range that a stable partition left in the spare array back to the refs array (in chunks that may run
    // on several threads; a copy: the same bytes either way).
    void returnToRefs(const Range& r) {
        if (!r.inSpare) return;
        const uint32_t chunks = (r.count() + kPartitionChunk - 1) / kPartitionChunk;
        runChunks(chunks, [&](uint32_t c) {
            const uint32_t begin = r.begin + c * kPartitionChunk, end = std::min(r.end, begin + kPartitionChunk);
            std::copy(spare_ + begin, spare_ + end, refs_ + begin);
        });
    }

private:
    // Per axis and bin: the primitives' bounds and their count. SSE boxes: a primitive extends three bins with six
    // instructions. Counts are sums and bounds min/max, so chunks merged in any order give the same bins.
    struct Bins {
        struct Box {  // trivially constructible: only the bins in use are initialised
            __m128 lower, upper;
        };
        int binCount = kBins;
        Box bounds[3][kBins];
        uint32_t count[3][kBins];
        explicit Bins(int n = kBins) : binCount(n) {
            const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < n; ++b) count[a][b] = 0, bounds[a][b] = {inf, _mm_sub_ps(_mm_setzero_ps(), inf)};
        }
        void add(int a, int b, __m128 lo, __m128 up) {
            bounds[a][b].lower = _mm_min_ps(bounds[a][b].lower, lo);
            bounds[a][b].upper = _mm_max_ps(bounds[a][b].upper, up);
            count[a][b]++;
        }
        void merge(const Bins& o) {
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < binCount; ++b) {
                    bounds[a][b].lower = _mm_min_ps(bounds[a][b].lower, o.bounds[a][b].lower);
                    bounds[a][b].upper = _mm_max_ps(bounds[a][b].upper, o.bounds[a][b].upper);
                    count[a][b] += o.count[a][b];
                }
        }
    };
    struct RangeBounds {
        SimdBoxNanSpreads bounds;
        void merge(const RangeBounds& o) { bounds.extend(o.bounds); }
    };

    // A primitive's bounds from its PrimRef (lane 3, the index, cleared).
    static void load(const PrimRef& p, __m128& lo, __m128& up) {
        lo = xyz(_mm_loadu_ps(p.lower));
        up = xyz(_mm_loadu_ps(p.upper));
    }

    // Runs fn over [begin, end) chunks of r into `out`: in one go, or in parallel chunks merged afterwards when the
    // range is large and the builder has a ParallelFor. Only for reductions whose merge is exact (sums, min/max).
    template <typename Acc, typename Fn>
    void forChunks(const Range& r, const Fn& fn, Acc& out, const Acc& empty) {
        constexpr uint32_t kChunk = 16384;
        if (!parallel_ || r.count() < 4 * kChunk) {
            fn(r.begin, r.end, out);
            return;
        }
        const uint32_t chunks = (r.count() + kChunk - 1) / kChunk;
        HostVector<Acc> partial(chunks, empty);
        parallelFor(parallel_, chunks, [&](uint32_t c) {
            fn(r.begin + c * kChunk, std::min(r.end, r.begin + (c + 1) * kChunk), partial[c]);
        });
        for (const Acc& p : partial) out.merge(p);
    }

    void finishRange(Range& r) {
        RangeBounds rb;
        const PrimRef* refs = at(r);
        forChunks(r, [&](uint32_t begin, uint32_t end, RangeBounds& local) {
            for (uint32_t i = begin; i < end; ++i) {
                __m128 lo, up;
                load(refs[i], lo, up);
                local.bounds.extend(lo, up);
            }
        }, rb, RangeBounds{});
        r.bounds = rb.bounds.aabb();
    }

    void halve(const Range& r, Range& left, Range& right) {
        uint32_t mid = r.begin + r.count() / 2;
        left.begin = r.begin, left.end = mid;
        right.begin = mid, right.end = r.end;
        left.depth = right.depth = r.depth + 1;
        left.inSpare = right.inSpare = r.inSpare;
        finishRange(left);
        finishRange(right);
    }

    // The refs of a range, where they are.
    const PrimRef* at(const Range& r) const { return r.inSpare ? spare_ : refs_; }

    void split(const Range& range, Range& left, Range& right) {
        // Only a stable partition reads a range from the spare array: a smaller one goes back first.
        Range r = range;
        if (r.inSpare && r.count() < kStablePartitionMin) returnToRefs(r), r.inSpare = false;
        // The bins divide the range's bounds, doubled (lower + upper, twice a centroid, lies within them): the
        // children's bounds come from the bins, so no pass gathers centroid bounds. Ranges that are one point are
        // halved; ranges whose centroids coincide fall into one bin and are halved below.
        Vec3 cl = r.bounds.lower + r.bounds.lower, cu = r.bounds.upper + r.bounds.upper;
        Vec3 extent = cu - cl;
        if (r.depth >= format::kSahDepthLimit || !(extent.x > 0 || extent.y > 0 || extent.z > 0)) {
            return halve(r, left, right);
        }
        const int binCount = int(std::min<uint32_t>(settings_.binCount, binCountFor(r.count(), settings_.fewBinsBelow)));
        // The axes binned: all three, or only the one of the largest extent.
        int axes[3] = {0, 1, 2}, axisCount = 3;
        if (settings_.largestAxisOnly) {
            axes[0] = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
            axisCount = 1;
        }
        bool binned[3] = {false, false, false};
        for (int k = 0; k < axisCount; ++k) binned[axes[k]] = true;
        const float lower[3] = {r.bounds.lower.x, r.bounds.lower.y, r.bounds.lower.z};
        const float upper[3] = {r.bounds.upper.x, r.bounds.upper.y, r.bounds.upper.z};
        const CentroidBins binning(lower, upper, binCount, binned);  // (centroid_bins.hpp)
        const float* scale = binning.axisScale;
        auto binsOf = [&](__m128 lo, __m128 up) { return binning.of(lo, up); };
        Bins bins(binCount);
        // A large range bins every stride-th primitive from its first (binSampleTarget); the sample's indices
        // depend on the range alone, never on the chunks, so threads see the same sample.
        const uint32_t stride = sampleStride(r.count());
        const PrimRef* refs = at(r);
        forChunks(r, [&](uint32_t begin, uint32_t end, Bins& local) {
            uint32_t i = begin;
            if (stride > 1) i = r.begin + (begin - r.begin + stride - 1) / stride * stride;
            if (end > i && (end - i) / stride >= 256) {
                // Neighbouring primitives tend to fall into the same bins: a second set of bins for every other
                // primitive halves the chains of dependent updates. Merged exactly (min/max, sums).
                Bins odd(binCount);
                for (; i + stride < end; i += 2 * stride) {
                    __m128 lo0, up0, lo1, up1;
                    load(refs[i], lo0, up0);
                    load(refs[i + stride], lo1, up1);
                    alignas(16) int b0[4], b1[4];
                    _mm_store_si128(reinterpret_cast<__m128i*>(b0), binsOf(lo0, up0));
                    _mm_store_si128(reinterpret_cast<__m128i*>(b1), binsOf(lo1, up1));
                    for (int k = 0; k < axisCount; ++k) {
                        local.add(axes[k], b0[axes[k]], lo0, up0);
                        odd.add(axes[k], b1[axes[k]], lo1, up1);
                    }
                }
                local.merge(odd);
            }
            for (; i < end; i += stride) {
                __m128 lo, up;
                load(refs[i], lo, up);
                alignas(16) int b[4];
                _mm_store_si128(reinterpret_cast<__m128i*>(b), binsOf(lo, up));
                for (int k = 0; k < axisCount; ++k) local.add(axes[k], b[axes[k]], lo, up);
            }
        }, bins, Bins(binCount));
        float bestCost = std::numeric_limits<float>::infinity();
        int bestAxis = -1, bestBin = -1;
        for (int k = 0; k < axisCount; ++k) {
            const int a = axes[k];
            if (scale[a] == 0.0f) continue;
            float rightArea[kBins];
            uint32_t rightCount[kBins];
            SimdBoxNanSpreads acc;
            uint32_t cnt = 0;
            for (int b = binCount - 1; b > 0; --b) {
                acc.extend(bins.bounds[a][b].lower, bins.bounds[a][b].upper);
                cnt += bins.count[a][b];
                rightArea[b] = acc.halfArea();
                rightCount[b] = cnt;
            }
            acc = SimdBoxNanSpreads{};
            cnt = 0;
            for (int b = 0; b < binCount - 1; ++b) {  // split between bin b and b + 1
                acc.extend(bins.bounds[a][b].lower, bins.bounds[a][b].upper);
                cnt += bins.count[a][b];
                if (cnt == 0 || rightCount[b + 1] == 0) continue;
                float cost = acc.halfArea() * float(cnt) + rightArea[b + 1] * float(rightCount[b + 1]);
                if (cost < bestCost) {
                    bestCost = cost;
                    bestAxis = a;
                    bestBin = b;
                }
            }
        }
        if (bestAxis < 0) return halve(r, left, right);
        // The children's bounds: the bins on either side of the split, exactly the primitives' (min / max of the
        // same values).
        SimdBoxNanSpreads leftBox, rightBox;
        for (int b = 0; b < binCount; ++b)
            (b <= bestBin ? leftBox : rightBox).extend(bins.bounds[bestAxis][b].lower, bins.bounds[bestAxis][b].upper);

        // Partition (primitives in bins <= bestBin go left).
        // bin <= bestBin, decided on the split axis alone: the bin is trunc(clamp(f, 0, last)) with NaN in bin 0, and
        // bestBin + 1 <= last, so it is !(f >= bestBin + 1) with f the bins' position (CentroidBins::position).
        const __m128 splitLimit = _mm_set1_ps(float(bestBin + 1));
        const int axisBit = 1 << bestAxis;
        auto goesLeft = [=](__m128 lo, __m128 up) {
            return (_mm_movemask_ps(_mm_cmpge_ps(binning.position(lo, up), splitLimit)) & axisBit) == 0;
        };
        // Large ranges: stably through the spare array, in chunks that may run on several threads, each side's
        // bounds gathered on the way (merged in chunk order: the same bytes with threads or without).
        auto add = [](RangeBounds& side, __m128 lo, __m128 up) { side.bounds.extend(lo, up); };
        if (spare_ && r.count() >= kStablePartitionMin) return stablePartition(r, goesLeft, add, left, right);
        // In place. The bounds come from the bins, unless the bins saw only a sample.
        if (stride > 1) return partitionInPlace<true>(r, goesLeft, left, right);
        partitionInPlace<false>(r, goesLeft, left, right);
        left.bounds = leftBox.aabb();
        right.bounds = rightBox.aabb();
    }

    // The stride of the sample a range bins: 1 (every primitive) below twice the settings' sample target.
    uint32_t sampleStride(uint32_t count) const {
        const uint32_t target = settings_.binSampleTarget;
        return target != 0 && count >= 2 * target ? count / target : 1;
    }

    // The in-place partition of split, without branches on the side (which is close to random near the leaves):
    // every primitive is swapped with the first one not known to go left, which moves it there if it goes left and
    // leaves the order of [begin, l) left, [l, i) right otherwise. With kGatherBounds (a range whose bins saw only a
    // sample), each side's bounds are gathered on the way, each primitive extending its own side's box exactly as
    // RangeBounds::extend would; otherwise the caller takes them from the bins.
    template <bool kGatherBounds, typename GoesLeft>
    void partitionInPlace(const Range& r, const GoesLeft& goesLeft, Range& left, Range& right) {
        SimdBoxNanSpreads lb, rb;
        auto select = [](__m128 mask, __m128 ifSet, __m128 ifClear) {  // SSE2: no blendv in the baseline ISA
            return _mm_or_ps(_mm_and_ps(mask, ifSet), _mm_andnot_ps(mask, ifClear));
        };
        uint32_t l = r.begin;
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const __m128 p0 = _mm_loadu_ps(refs_[i].lower), p1 = _mm_loadu_ps(refs_[i].upper);
            const __m128 lo = xyz(p0), up = xyz(p1);
            const uint32_t toLeft = goesLeft(lo, up);
            if constexpr (kGatherBounds) {
                const __m128 side = _mm_castsi128_ps(_mm_set1_epi32(-int32_t(toLeft)));  // all ones: left
                lb.lower = select(side, _mm_min_ps(lb.lower, lo), lb.lower);
                lb.upper = select(side, _mm_max_ps(lb.upper, up), lb.upper);
                rb.lower = select(side, rb.lower, _mm_min_ps(rb.lower, lo));
                rb.upper = select(side, rb.upper, _mm_max_ps(rb.upper, up));
            }
            const __m128 q0 = _mm_loadu_ps(refs_[l].lower), q1 = _mm_loadu_ps(refs_[l].upper);
            _mm_storeu_ps(refs_[i].lower, q0), _mm_storeu_ps(refs_[i].upper, q1);
            _mm_storeu_ps(refs_[l].lower, p0), _mm_storeu_ps(refs_[l].upper, p1);
            l += toLeft;
        }
        left.begin = r.begin, left.end = l;
        right.begin = l, right.end = r.end;
        left.depth = right.depth = r.depth + 1;
        if constexpr (kGatherBounds) left.bounds = lb.aabb(), right.bounds = rb.aabb();
    }

    static constexpr uint32_t kPartitionChunk = 16384;

    template <typename Fn>
    void runChunks(uint32_t chunks, const Fn& fn) {
        parallelFor(parallel_, chunks, fn);
    }

    // A large range is partitioned stably (each side keeps its order) from the array it is in into the other one (the
    // refs array and the spare array take turns, so no pass copies a side back), in fixed chunks that threads can
    // share: the order depends on the chunks, never on the threads, and the top of the tree, where every range is
    // large, is not serial. Index i of either array is only used by the range that holds i: disjoint ranges never
    // collide.
    template <typename GoesLeft, typename Add>
    void stablePartition(const Range& r, const GoesLeft& goesLeft, const Add& add, Range& left, Range& right) {
        const PrimRef* from = at(r);
        PrimRef* to = r.inSpare ? refs_ : spare_;
        const uint32_t chunks = (r.count() + kPartitionChunk - 1) / kPartitionChunk;
        struct Side {
            uint32_t leftCount = 0, leftAt = 0, rightAt = 0;
            RangeBounds lb, rb;
        };
        HostVector<Side> sides(chunks);
        auto chunkBegin = [&](uint32_t c) { return r.begin + c * kPartitionChunk; };
        auto chunkEnd = [&](uint32_t c) { return std::min(r.end, r.begin + (c + 1) * kPartitionChunk); };
        runChunks(chunks, [&](uint32_t c) {
            Side& side = sides[c];
            for (uint32_t i = chunkBegin(c); i < chunkEnd(c); ++i) {
                __m128 lo, up;
                load(from[i], lo, up);
                if (goesLeft(lo, up)) {
                    add(side.lb, lo, up);
                    ++side.leftCount;
                } else {
                    add(side.rb, lo, up);
                }
            }
        });
        uint32_t leftTotal = 0;
        for (Side& side : sides) side.leftAt = r.begin + leftTotal, leftTotal += side.leftCount;
        uint32_t rightAt = r.begin + leftTotal;
        for (uint32_t c = 0; c < chunks; ++c) {
            sides[c].rightAt = rightAt;
            rightAt += (chunkEnd(c) - chunkBegin(c)) - sides[c].leftCount;
        }
        runChunks(chunks, [&](uint32_t c) {
            uint32_t l = sides[c].leftAt, rr = sides[c].rightAt;
            for (uint32_t i = chunkBegin(c); i < chunkEnd(c); ++i) {
                __m128 lo, up;
                load(from[i], lo, up);
                to[goesLeft(lo, up) ? l++ : rr++] = from[i];
            }
        });
        RangeBounds lb, rb;
        for (const Side& side : sides) lb.merge(side.lb), rb.merge(side.rb);
        left.begin = r.begin, left.end = r.begin + leftTotal;
        right.begin = left.end, right.end = r.end;
        left.depth = right.depth = r.depth + 1;
        left.inSpare = right.inSpare = !r.inSpare;
        left.bounds = lb.bounds.aabb();
        right.bounds = rb.bounds.aabb();
    }

    PrimRef* refs_;
    PrimRef* spare_ = nullptr;  // as many as refs_: the buffer of stablePartition
    BvhBuildSettings settings_;
    Node* nodes_;
    HostVector<Node>* growing_ = nullptr;
    const ParallelFor* parallel_;  // for binning and bounds of large ranges
    uint32_t nodeCount_ = 0;
    uint32_t deferThreshold_ = 0;
    HostVector<Range> deferred_;
};

}  // namespace vkas::sah_detail
