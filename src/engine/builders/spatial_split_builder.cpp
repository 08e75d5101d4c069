#include "engine/builders/spatial_split_builder.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/builders/binary_tree.hpp"
#include "engine/builders/centroid_bins.hpp"
#include "engine/builders/quality_builder.hpp"
#include "engine/builders/wide_collapse.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"

namespace vkas {

namespace {

constexpr uint32_t kBins = 32;
// Spatial splits are looked for only where the best object split's two boxes overlap by more than this fraction of
// the root's surface area (Stich et al.'s alpha): elsewhere they rarely win and their binning costs the most. Stich
// et al. use 1e-5; 1e-4 builds 15-35% faster for 0.2% more traversal instructions (docs/PERFORMANCE.md).
constexpr double kOverlapFraction = 1e-4;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Box {
    float lo[3] = {kInf, kInf, kInf};
    float hi[3] = {-kInf, -kInf, -kInf};

    // NaN spreads, as in the other builders' boxes (binary_tree.hpp, unionBox).
    void grow(const float* lower, const float* upper) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = (lo[a] < lower[a] || lo[a] != lo[a]) ? lo[a] : lower[a];
            hi[a] = (hi[a] > upper[a] || hi[a] != hi[a]) ? hi[a] : upper[a];
        }
    }
    void grow(const Box& b) { grow(b.lo, b.hi); }
    void grow(const PrimRef& r) { grow(r.lower, r.upper); }
    bool empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
    bool finite() const {
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(lo[a]) || !std::isfinite(hi[a])) return false;
        return true;
    }
    double halfArea() const {
        if (empty()) return 0.0;
        const double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
        return dx * dy + dy * dz + dz * dx;
    }
    static Box of(const PrimRef& r) {
        Box b;
        b.grow(r);
        return b;
    }
    static Box intersection(const Box& a, const Box& b) {
        Box r;
        for (int k = 0; k < 3; ++k) r.lo[k] = std::max(a.lo[k], b.lo[k]), r.hi[k] = std::min(a.hi[k], b.hi[k]);
        return r;
    }
};

// The box of the part of triangle v inside lo <= x_axis <= hi, in double (empty when the slab misses it): the
// vertices inside and the edges' crossings of the two planes are the clipped polygon's corners.
struct DoubleBox {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    bool any = false;
    void add(const double p[3]) {
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
        any = true;
    }
};

DoubleBox clipToSlab(const double v[3][3], int axis, double lo, double hi) {
    DoubleBox box;
    for (int k = 0; k < 3; ++k) {
        const double* p = v[k];
        const double* q = v[(k + 1) % 3];
        if (p[axis] >= lo && p[axis] <= hi) box.add(p);
        for (const double plane : {lo, hi}) {
            if (!std::isfinite(plane)) continue;
            if ((p[axis] < plane && q[axis] > plane) || (p[axis] > plane && q[axis] < plane)) {
                const double t = (plane - p[axis]) / (q[axis] - p[axis]);
                double x[3];
                for (int a = 0; a < 3; ++a) x[a] = p[a] + t * (q[a] - p[a]);
                x[axis] = plane;
                box.add(x);
            }
        }
    }
    return box;
}

// A float box that contains `d` (rounded outward), cut to `within`.
Box outwardWithin(const DoubleBox& d, const Box& within) {
    Box b;
    if (!d.any) return b;
    for (int a = 0; a < 3; ++a) {
        float lo = float(d.lo[a]), hi = float(d.hi[a]);
        if (double(lo) > d.lo[a]) lo = std::nextafter(lo, -kInf);
        if (double(hi) < d.hi[a]) hi = std::nextafter(hi, kInf);
        b.lo[a] = std::max(lo, within.lo[a]);
        b.hi[a] = std::min(hi, within.hi[a]);
    }
    return b;
}

void setRef(PrimRef& r, const Box& b) {
    for (int a = 0; a < 3; ++a) r.lower[a] = b.lo[a], r.upper[a] = b.hi[a];
}

// A range of the working array: references [begin, end), and room to add references up to capEnd.
struct Range {
    uint32_t begin, end, capEnd;
    uint32_t count() const { return end - begin; }
    uint32_t room() const { return capEnd - end; }
};

struct ObjectSplit {
    double cost = HUGE_VAL;
    int axis = -1;
    uint32_t bin = 0;  // the left side is bins [0, bin]
    Box left, right;
};

struct SpatialSplit {
    double cost = HUGE_VAL;
    int axis = -1;
    float plane = 0.0f;
    Box left, right;
    uint32_t leftCount = 0, rightCount = 0;
};

__m128 loadLower(const PrimRef& r) { return _mm_loadu_ps(r.lower); }  // lane 3 (the index) is never read
__m128 loadUpper(const PrimRef& r) { return _mm_loadu_ps(r.upper); }
__m128 point(const float* p) { return _mm_setr_ps(p[0], p[1], p[2], 0.0f); }

struct SweepResult {
    double cost = HUGE_VAL;
    uint32_t bin = kBins;  // the left side is bins [0, bin]; kBins: no split
    Box left, right;
    uint32_t leftCount = 0, rightCount = 0;
};

// Up to kBins boxes (SSE, lanes 0-2) with counts, and the SAH sweep over their planes. Bins estimate a split's cost,
// so they need no NaN rule: the builder's own bounds (Box) keep it.
struct SimdBins {
    uint32_t used;  // bins in use
    __m128 lo[kBins], hi[kBins];
    uint32_t count[kBins];
    explicit SimdBins(uint32_t n = kBins) : used(n) {  // only the bins in use are initialised
        for (uint32_t b = 0; b < n; ++b) lo[b] = _mm_set1_ps(kInf), hi[b] = _mm_set1_ps(-kInf), count[b] = 0;
    }
    void grow(uint32_t b, __m128 l, __m128 h) { lo[b] = _mm_min_ps(lo[b], l), hi[b] = _mm_max_ps(hi[b], h); }
    void add(uint32_t b, __m128 l, __m128 h) { grow(b, l, h), ++count[b]; }

    static Box toBox(__m128 l, __m128 h) {
        alignas(16) float a[4], b[4];
        _mm_store_ps(a, l), _mm_store_ps(b, h);
        Box box;
        for (int k = 0; k < 3; ++k) box.lo[k] = a[k], box.hi[k] = b[k];
        return box;
    }
    // The cheapest plane between bins b and b + 1, with leftCounts[b] summed from the left and rightCounts[b] from
    // the right (object splits: the same counts; spatial splits: entries and exits). With `count`, both sides must
    // hold fewer than count references and the references counted on both sides at most `room` more.
    SweepResult sweep(const uint32_t* leftCounts, const uint32_t* rightCounts, uint32_t count = 0,
                      uint32_t room = 0) const {
        Box rightBoxes[kBins];
        uint32_t rightN[kBins];
        __m128 l = _mm_set1_ps(kInf), h = _mm_set1_ps(-kInf);
        uint32_t n = 0;
        for (uint32_t b = used; b-- > 1;) {
            l = _mm_min_ps(l, lo[b]), h = _mm_max_ps(h, hi[b]);
            n += rightCounts[b];
            rightBoxes[b] = toBox(l, h), rightN[b] = n;
        }
        SweepResult best;
        l = _mm_set1_ps(kInf), h = _mm_set1_ps(-kInf);
        n = 0;
        for (uint32_t b = 0; b + 1 < used; ++b) {
            l = _mm_min_ps(l, lo[b]), h = _mm_max_ps(h, hi[b]);
            n += leftCounts[b];
            const uint32_t nr = rightN[b + 1];
            if (n == 0 || nr == 0) continue;
            if (count != 0 && (n >= count || nr >= count || n + nr - count > room)) continue;
            const Box left = toBox(l, h);
            const double cost = left.halfArea() * n + rightBoxes[b + 1].halfArea() * nr;
            if (cost < best.cost) {
                best.cost = cost, best.bin = b, best.left = left, best.right = rightBoxes[b + 1];
                best.leftCount = n, best.rightCount = nr;
            }
        }
        return best;
    }
};

// The spatial bins of one axis of a range's bounds: kBins equal slabs; a coordinate's bin is decided by the planes
// themselves, so that binning and partition agree.
struct SpatialAxis {
    float origin, scale;
    float plane[kBins];  // plane[k], k = 1..kBins-1: between bins k - 1 and k
    SpatialAxis(const Box& bounds, int axis) : origin(bounds.lo[axis]) {
        const float extent = bounds.hi[axis] - bounds.lo[axis];
        scale = float(kBins) / extent;
        plane[0] = origin;
        for (uint32_t k = 1; k < kBins; ++k) plane[k] = origin + extent * (float(k) / float(kBins));
    }
    uint32_t bin(float x) const {
        const float f = (x - origin) * scale;
        uint32_t b = !(f >= 1.0f) ? 0 : f >= float(kBins - 1) ? kBins - 1 : uint32_t(f);
        while (b > 0 && x < plane[b]) --b;
        while (b + 1 < kBins && x >= plane[b + 1]) ++b;
        return b;
    }
};

class SplitBuilder {
public:
    SplitBuilder(PrimRef* work, PrimRef* spare, BinaryNode* tree, FragmentRegion* regions, uint32_t regionCapacity,
                 const format::TriangleRecord* triangles, double rootHalfArea)
        : work_(work), spare_(spare), tree_(tree), regions_(regions), regionCapacity_(regionCapacity),
          triangles_(triangles), overlapLimit_(kOverlapFraction * rootHalfArea) {}

    // The subtree of `r` from binary node nodeCount_ on (preorder); returns its node index.
    uint32_t build(const Range& r, uint32_t depth, uint32_t parent) {
        const uint32_t index = nodeCount_++;
        BinaryNode& node = tree_[index];
        node.parent = parent;
        const Box bounds = boundsOf(r);
        setBox(node, bounds);
        if (r.count() == 1) {
            node.child[0] = r.begin;
            node.child[1] = BinaryNode::kNone;
            node.primCount = 1;
            return index;
        }
        Range left{}, right{};
        if (depth >= format::kSahDepthLimit) {
            halve(r, left, right);
        } else {
            // As many object bins as references below kBins (at least 4), as in the SAH builder: the sweep over
            // unused bins would cost more than the binning.
            const uint32_t binCount = std::max(4u, std::min(kBins, r.count()));
            const bool all[3] = {true, true, true};
            const CentroidBins binning(bounds.lo, bounds.hi, int(binCount), all);
            const ObjectSplit object = findObjectSplit(r, binning, binCount);
            bool done = false;
            if (r.room() != 0 && bounds.finite() && object.axis >= 0 &&
                Box::intersection(object.left, object.right).halfArea() > overlapLimit_) {
                const SpatialSplit spatial = findSpatialSplit(r, bounds);
                if (spatial.axis >= 0 && spatial.cost < object.cost) done = spatialPartition(r, spatial, left, right);
            }
            if (!done) {
                if (object.axis >= 0)
                    objectPartition(r, binning, object, left, right);
                else
                    halve(r, left, right);
            }
        }
        const uint32_t l = build(left, depth + 1, index);
        const uint32_t rr = build(right, depth + 1, index);
        node.child[0] = l;
        node.child[1] = rr;
        node.primCount = tree_[l].primCount + tree_[rr].primCount;
        return index;
    }

    uint32_t nodeCount() const { return nodeCount_; }

private:
    static void setBox(BinaryNode& n, const Box& b) {
        for (int a = 0; a < 3; ++a) n.lower[a] = b.lo[a], n.upper[a] = b.hi[a];
    }

    // Past the SAH depth limit (or with nothing to bin): two halves in array order, no more room to add references.
    void halve(const Range& r, Range& left, Range& right) const {
        const uint32_t mid = r.begin + r.count() / 2;
        left = {r.begin, mid, mid};
        right = {mid, r.end, r.capEnd};
    }

    // The range's bounds: SSE, with NaN spreading as Box::grow does (a NaN coordinate makes the bound NaN).
    Box boundsOf(const Range& r) const {
        __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf), nanLo = _mm_setzero_ps(), nanHi = _mm_setzero_ps();
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const __m128 l = loadLower(work_[i]), h = loadUpper(work_[i]);
            lo = _mm_min_ps(lo, l), hi = _mm_max_ps(hi, h);
            nanLo = _mm_or_ps(nanLo, _mm_cmpunord_ps(l, l)), nanHi = _mm_or_ps(nanHi, _mm_cmpunord_ps(h, h));
        }
        const __m128 nan = _mm_set1_ps(std::numeric_limits<float>::quiet_NaN());
        lo = _mm_or_ps(_mm_andnot_ps(nanLo, lo), _mm_and_ps(nanLo, nan));
        hi = _mm_or_ps(_mm_andnot_ps(nanHi, hi), _mm_and_ps(nanHi, nan));
        return SimdBins::toBox(lo, hi);
    }

    // Binned SAH over the centroids (centroid_bins.hpp), binCount bins on each axis, all three binned in one pass;
    // ties go to the lower axis, then the lower bin.
    ObjectSplit findObjectSplit(const Range& r, const CentroidBins& binning, uint32_t binCount) const {
        ObjectSplit best;
        const float* scale = binning.axisScale;
        if (scale[0] == 0.0f && scale[1] == 0.0f && scale[2] == 0.0f) return best;
        SimdBins bins[3] = {SimdBins(binCount), SimdBins(binCount), SimdBins(binCount)};
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const PrimRef& ref = work_[i];
            const __m128 lo = loadLower(ref), hi = loadUpper(ref);
            alignas(16) int32_t b[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(b), binning.of(lo, hi));
            bins[0].add(uint32_t(b[0]), lo, hi), bins[1].add(uint32_t(b[1]), lo, hi), bins[2].add(uint32_t(b[2]), lo, hi);
        }
        for (int a = 0; a < 3; ++a) {
            if (scale[a] == 0.0f) continue;
            SweepResult sweep = bins[a].sweep(bins[a].count, bins[a].count);
            if (sweep.bin < kBins && sweep.cost < best.cost) {
                best.cost = sweep.cost, best.axis = a, best.bin = sweep.bin;
                best.left = sweep.left, best.right = sweep.right;
            }
        }
        return best;
    }

    // Adds the parts of ref's triangle in spatial bins b0..b1 (b0 < b1) of `axis` to bins, cut to the ref's box
    // [lo, hi]. An estimate for the SAH (float, not rounded outward): the partition computes the parts it keeps
    // exactly. A bin's part is bounded by the triangle's vertices inside the bin and its cross-sections at the bin's
    // planes, each a segment between two edges' crossings, computed once per plane.
    void binParts(const PrimRef& ref, __m128 lo, __m128 hi, int axis, const SpatialAxis& grid, uint32_t b0,
                  uint32_t b1, SimdBins& bins) const {
        const format::TriangleRecord& t = triangles_[ref.index];
        const float* v[3] = {t.v[0], t.v[1], t.v[2]};
        if (v[1][axis] < v[0][axis]) std::swap(v[0], v[1]);
        if (v[2][axis] < v[1][axis]) std::swap(v[1], v[2]);
        if (v[1][axis] < v[0][axis]) std::swap(v[0], v[1]);
        const __m128 p[3] = {point(v[0]), point(v[1]), point(v[2])};
        auto clamp = [&](__m128 q) { return _mm_min_ps(_mm_max_ps(q, lo), hi); };
        for (int k = 0; k < 3; ++k) {
            const __m128 q = clamp(p[k]);
            bins.grow(std::min(std::max(grid.bin(v[k][axis]), b0), b1), q, q);
        }
        auto along = [&](int from, int to, float plane) {
            const float d = v[to][axis] - v[from][axis];
            const float f = d > 0.0f ? (plane - v[from][axis]) / d : 0.0f;
            return clamp(_mm_add_ps(p[from], _mm_mul_ps(_mm_set1_ps(f), _mm_sub_ps(p[to], p[from]))));
        };
        for (uint32_t b = b0 + 1; b <= b1; ++b) {
            const float plane = grid.plane[b];
            const __m128 longEdge = along(0, 2, plane);
            const __m128 shortEdge = plane < v[1][axis] ? along(0, 1, plane) : along(1, 2, plane);
            const __m128 segLo = _mm_min_ps(longEdge, shortEdge), segHi = _mm_max_ps(longEdge, shortEdge);
            bins.grow(b - 1, segLo, segHi);
            bins.grow(b, segLo, segHi);
        }
    }

    // Binned spatial splits (Stich et al., section 3.2) along the axis of the largest extent only: half the build
    // time of all three axes for 0.6-0.9% more traversal instructions (docs/PERFORMANCE.md, "Spatial splits
    // built"). Each reference is clipped into every bin it spans; it enters the bin of its lower side and exits the
    // bin of its upper side.
    SpatialSplit findSpatialSplit(const Range& r, const Box& bounds) const {
        SpatialSplit best;
        int a = 0;
        for (int k = 1; k < 3; ++k)
            if (bounds.hi[k] - bounds.lo[k] > bounds.hi[a] - bounds.lo[a]) a = k;
        if (!(bounds.hi[a] > bounds.lo[a])) return best;
        const SpatialAxis grid(bounds, a);
        SimdBins bins;
        uint32_t enter[kBins] = {}, exit[kBins] = {};
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const PrimRef& ref = work_[i];
            const __m128 lo = loadLower(ref), hi = loadUpper(ref);
            const uint32_t b0 = grid.bin(ref.lower[a]), b1 = grid.bin(ref.upper[a]);
            ++enter[b0], ++exit[b1];
            if (b0 == b1)
                bins.grow(b0, lo, hi);
            else
                binParts(ref, lo, hi, a, grid, b0, b1, bins);
        }
        // Both sides must make progress, and the references cut must fit the range's room.
        const SweepResult sweep = bins.sweep(enter, exit, r.count(), r.room());
        if (sweep.bin < kBins) {
            best.cost = sweep.cost, best.axis = a, best.plane = grid.plane[sweep.bin + 1];
            best.left = sweep.left, best.right = sweep.right;
            best.leftCount = sweep.leftCount, best.rightCount = sweep.rightCount;
        }
        return best;
    }

    void triangleOf(const PrimRef& ref, double v[3][3]) const {
        const format::TriangleRecord& t = triangles_[ref.index];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) v[k][a] = t.v[k][a];
    }

    // Places the left side's references at the range's start and the right side's after the left's share of the
    // room left over (proportional to the sides' counts), from spare[begin, begin + nl) and, reversed,
    // spare[capEnd - nr, capEnd).
    void place(const Range& r, uint32_t nl, uint32_t nr, Range& left, Range& right) {
        const uint32_t room = r.capEnd - r.begin - nl - nr;
        const uint32_t leftRoom = uint32_t(uint64_t(room) * nl / (uint64_t(nl) + nr));
        std::memcpy(work_ + r.begin, spare_ + r.begin, sizeof(PrimRef) * nl);
        const uint32_t rightBegin = r.begin + nl + leftRoom;
        for (uint32_t k = 0; k < nr; ++k) work_[rightBegin + k] = spare_[r.capEnd - 1 - k];
        left = {r.begin, r.begin + nl, rightBegin};
        right = {rightBegin, rightBegin + nr, r.capEnd};
    }

    void objectPartition(const Range& r, const CentroidBins& binning, const ObjectSplit& s, Range& left,
                         Range& right) {
        uint32_t nl = 0, nr = 0;
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const PrimRef& ref = work_[i];
            alignas(16) int32_t b[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(b), binning.of(loadLower(ref), loadUpper(ref)));
            if (uint32_t(b[s.axis]) <= s.bin)
                spare_[r.begin + nl++] = ref;
            else
                spare_[r.capEnd - 1 - nr++] = ref;
        }
        place(r, nl, nr, left, right);
    }

    // Cuts or moves every reference of r at the plane; false (nothing changed) when a side would be empty or the
    // cuts would not fit, and the caller splits by objects instead.
    bool spatialPartition(const Range& r, const SpatialSplit& s, Range& left, Range& right) {
        const int a = s.axis;
        const float plane = s.plane;
        const uint32_t regionsBefore = regionCount_;
        const double splitCost = s.left.halfArea() * s.leftCount + s.right.halfArea() * s.rightCount;
        uint32_t nl = 0, nr = 0;
        auto toLeft = [&](const PrimRef& ref) { spare_[r.begin + nl++] = ref; };
        auto toRight = [&](const PrimRef& ref) { spare_[r.capEnd - 1 - nr++] = ref; };
        for (uint32_t i = r.begin; i < r.end; ++i) {
            if (r.begin + nl + nr + 1 > r.capEnd) return abandon(regionsBefore);
            const PrimRef& ref = work_[i];
            if (ref.upper[a] <= plane) {
                toLeft(ref);
                continue;
            }
            if (ref.lower[a] >= plane) {
                toRight(ref);
                continue;
            }
            // A fragment whose region lies on one side moves there whole: cutting it would leave an empty region.
            const FragmentRegion* q = ref.pad != 0 ? &regions_[ref.pad - 1] : nullptr;
            if (q && plane <= q->lower[a]) {
                toRight(ref);
                continue;
            }
            if (q && plane >= q->upper[a]) {
                toLeft(ref);
                continue;
            }
            // The two parts, padded by a little more than the hit point's rounding so that the fragment holding a
            // hit point always has it inside its box (format/fragment_section.hpp).
            double v[3][3];
            triangleOf(ref, v);
            double magnitude = 0.0;
            for (const auto& p : v)
                for (const double x : p) magnitude = std::max(magnitude, std::fabs(x));
            const double pad = std::ldexp(magnitude, -17);
            const Box refBox = Box::of(ref);
            const Box lb = outwardWithin(clipToSlab(v, a, -HUGE_VAL, double(plane) + pad), refBox);
            const Box rb = outwardWithin(clipToSlab(v, a, double(plane) - pad, HUGE_VAL), refBox);
            if (lb.empty()) {
                toRight(ref);
                continue;
            }
            if (rb.empty()) {
                toLeft(ref);
                continue;
            }
            // Unsplitting (Stich et al., section 3.3): keep the reference whole on one side when that costs less.
            Box leftWith = s.left, rightWith = s.right;
            leftWith.grow(refBox), rightWith.grow(refBox);
            const double wholeLeft = leftWith.halfArea() * s.leftCount + s.right.halfArea() * (s.rightCount - 1.0);
            const double wholeRight = s.left.halfArea() * (s.leftCount - 1.0) + rightWith.halfArea() * s.rightCount;
            const bool regionsFull = regionCount_ + 2 > regionCapacity_;
            if (regionsFull || wholeLeft < splitCost || wholeRight < splitCost) {
                if (wholeLeft <= wholeRight)
                    toLeft(ref);
                else
                    toRight(ref);
                continue;
            }
            if (r.begin + nl + nr + 2 > r.capEnd) return abandon(regionsBefore);
            FragmentRegion whole;
            for (int k = 0; k < 3; ++k) whole.lower[k] = -kInf, whole.upper[k] = kInf;
            if (q) whole = *q;
            FragmentRegion lr = whole, rr = whole;
            lr.upper[a] = std::min(whole.upper[a], plane);
            rr.lower[a] = std::max(whole.lower[a], plane);
            regions_[regionCount_] = lr;
            regions_[regionCount_ + 1] = rr;
            PrimRef lref = ref, rref = ref;
            setRef(lref, lb), setRef(rref, rb);
            lref.pad = regionCount_ + 1;
            rref.pad = regionCount_ + 2;
            regionCount_ += 2;
            toLeft(lref);
            toRight(rref);
        }
        if (nl == 0 || nr == 0) return abandon(regionsBefore);
        place(r, nl, nr, left, right);
        return true;
    }

    bool abandon(uint32_t regionsBefore) {
        regionCount_ = regionsBefore;
        return false;
    }

    PrimRef* work_;
    PrimRef* spare_;
    BinaryNode* tree_;
    FragmentRegion* regions_;
    uint32_t regionCapacity_;
    const format::TriangleRecord* triangles_;
    double overlapLimit_;
    uint32_t nodeCount_ = 0;
    uint32_t regionCount_ = 0;
};

// Workspace: work[cap] | spare[cap] | BinaryNode[2 cap] | CollapseEntry[2 cap] | FragmentRegion[2 budget], for
// cap = n + budget references.
struct Workspace {
    PrimRef* work;
    PrimRef* spare;
    BinaryNode* tree;
    CollapseEntry* table;
    FragmentRegion* regions;
};
Workspace carve(std::byte* workspace, uint64_t cap) {
    Workspace w;
    w.work = reinterpret_cast<PrimRef*>(workspace);
    w.spare = w.work + cap;
    w.tree = reinterpret_cast<BinaryNode*>(w.spare + cap);
    w.table = reinterpret_cast<CollapseEntry*>(w.tree + 2 * cap);
    w.regions = reinterpret_cast<FragmentRegion*>(w.table + 2 * cap);
    return w;
}

}  // namespace

// n + n/4 references (format/sizes.hpp, spatialSplitBudget) of 2 PrimRefs, 2 BinaryNodes and 2 CollapseEntries
// (5/4 * 232 = 290 bytes) and n/2 regions (12 bytes): 302 bytes, rounded up.
uint64_t spatialSplitWorkspacePerPrimitive() { return 304; }

BvhBuildResult buildSpatialSplitBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                                    std::byte* workspace, const ParallelFor* parallel) {
    BvhBuildSettings quality = settings;
    quality.splitBudget = 0;
    quality.triangles = nullptr;
    const uint32_t budget = std::min<uint64_t>(settings.splitBudget, spatialSplitBudget(n));
    if (n == 0 || budget == 0 || !settings.triangles) return buildQualityBvh(refs, n, quality, nodes, workspace, parallel);
    const uint32_t cap = n + budget;
    const Workspace w = carve(workspace, cap);
    std::memcpy(w.work, refs, sizeof(PrimRef) * n);
    for (uint32_t i = 0; i < n; ++i) w.work[i].pad = 0;
    Box root;
    for (uint32_t i = 0; i < n; ++i) root.grow(refs[i]);
    SplitBuilder builder(w.work, w.spare, w.tree, w.regions, 2 * budget, settings.triangles, root.halfArea());
    builder.build(Range{0, n, cap}, 0, BinaryNode::kNone);
    const uint32_t refCount = w.tree[0].primCount;
    const CollapseResult wide = collapseToWide(w.tree, builder.nodeCount(), w.work, refCount, settings.maxLeafSize,
                                               CollapseCosts{}, w.table, w.spare, nodes);
    if (!wide.ok) return buildQualityBvh(refs, n, quality, nodes, workspace, parallel);
    BvhBuildResult result = wide.tree;
    result.refs = w.work;
    result.refCount = refCount;
    result.regions = w.regions;
    return result;
}

}  // namespace vkas
