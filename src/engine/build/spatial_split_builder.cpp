#include "engine/build/spatial_split_builder.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/build/binary_tree.hpp"
#include "engine/build/quality_builder.hpp"
#include "engine/build/wide_collapse.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"

namespace vkas {

namespace {

constexpr uint32_t kBins = 32;
// Spatial splits are looked for only where the best object split's two boxes overlap by more than this fraction of
// the root's surface area (Stich et al.'s alpha): elsewhere they rarely win and their binning costs the most.
constexpr double kOverlapFraction = 1e-5;
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
    float origin = 0.0f, scale = 0.0f;
    Box left, right;
};

struct SpatialSplit {
    double cost = HUGE_VAL;
    int axis = -1;
    float plane = 0.0f;
    Box left, right;
    uint32_t leftCount = 0, rightCount = 0;
};

float centroid(const PrimRef& r, int axis) { return 0.5f * r.lower[axis] + 0.5f * r.upper[axis]; }

uint32_t centroidBin(float c, float origin, float scale) {
    const float f = (c - origin) * scale;
    if (!(f >= 1.0f)) return 0;  // NaN too
    if (f >= float(kBins - 1)) return kBins - 1;
    return uint32_t(f);
}

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
        Box bounds, centroids;
        for (uint32_t i = r.begin; i < r.end; ++i) {
            bounds.grow(work_[i]);
            float c[3];
            for (int a = 0; a < 3; ++a) c[a] = centroid(work_[i], a);
            centroids.grow(c, c);
        }
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
            const ObjectSplit object = findObjectSplit(r, centroids);
            bool done = false;
            if (r.room() != 0 && bounds.finite() && object.axis >= 0 &&
                Box::intersection(object.left, object.right).halfArea() > overlapLimit_) {
                const SpatialSplit spatial = findSpatialSplit(r, bounds);
                if (spatial.axis >= 0 && spatial.cost < object.cost) done = spatialPartition(r, spatial, left, right);
            }
            if (!done) {
                if (object.axis >= 0)
                    objectPartition(r, object, left, right);
                else
                    halve(r, left, right);
            }
        }
        const uint32_t l = build(left, depth + 1, index);
        const uint32_t rr = build(right, depth + 1, index);
        BinaryNode& self = tree_[index];  // (tree_ does not move; a reference for clarity)
        self.child[0] = l;
        self.child[1] = rr;
        self.primCount = tree_[l].primCount + tree_[rr].primCount;
        return index;
    }

    uint32_t nodeCount() const { return nodeCount_; }
    uint32_t regionCount() const { return regionCount_; }

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

    // Binned SAH over the centroids, kBins bins on each axis; ties go to the lower axis, then the lower bin.
    ObjectSplit findObjectSplit(const Range& r, const Box& centroids) const {
        ObjectSplit best;
        for (int a = 0; a < 3; ++a) {
            const float extent = centroids.hi[a] - centroids.lo[a];
            if (!(extent > 0.0f) || !std::isfinite(extent)) continue;
            const float scale = float(kBins) * (1.0f - 1e-6f) / extent;
            Box boxes[kBins];
            uint32_t counts[kBins] = {};
            for (uint32_t i = r.begin; i < r.end; ++i) {
                const uint32_t b = centroidBin(centroid(work_[i], a), centroids.lo[a], scale);
                boxes[b].grow(work_[i]);
                ++counts[b];
            }
            Box rightBoxes[kBins];
            uint32_t rightCounts[kBins];
            Box acc;
            uint32_t n = 0;
            for (uint32_t b = kBins; b-- > 1;) {
                acc.grow(boxes[b]);
                n += counts[b];
                rightBoxes[b] = acc, rightCounts[b] = n;
            }
            acc = Box{};
            n = 0;
            for (uint32_t b = 0; b + 1 < kBins; ++b) {
                acc.grow(boxes[b]);
                n += counts[b];
                if (n == 0 || rightCounts[b + 1] == 0) continue;
                const double cost = acc.halfArea() * n + rightBoxes[b + 1].halfArea() * rightCounts[b + 1];
                if (cost < best.cost) {
                    best.cost = cost, best.axis = a, best.bin = b, best.origin = centroids.lo[a], best.scale = scale;
                    best.left = acc, best.right = rightBoxes[b + 1];
                }
            }
        }
        return best;
    }

    void triangleOf(const PrimRef& ref, double v[3][3]) const {
        const format::TriangleRecord& t = triangles_[ref.index];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) v[k][a] = t.v[k][a];
    }

    // The plane between spatial bins k - 1 and k (k in 1..kBins-1) of `bounds` on `axis`.
    static float binPlane(const Box& bounds, int axis, uint32_t k) {
        return bounds.lo[axis] + (bounds.hi[axis] - bounds.lo[axis]) * (float(k) / float(kBins));
    }
    // The spatial bin of coordinate x: the planes decide, so that binning and partition agree.
    static uint32_t spatialBin(const Box& bounds, int axis, float x) {
        const float extent = bounds.hi[axis] - bounds.lo[axis];
        const float f = (x - bounds.lo[axis]) * (float(kBins) / extent);
        uint32_t b = !(f >= 1.0f) ? 0 : f >= float(kBins - 1) ? kBins - 1 : uint32_t(f);
        while (b > 0 && x < binPlane(bounds, axis, b)) --b;
        while (b + 1 < kBins && x >= binPlane(bounds, axis, b + 1)) ++b;
        return b;
    }

    // Binned spatial splits (Stich et al., section 3.2): each reference is clipped into every bin it spans; it
    // enters the bin of its lower side and exits the bin of its upper side.
    SpatialSplit findSpatialSplit(const Range& r, const Box& bounds) const {
        SpatialSplit best;
        for (int a = 0; a < 3; ++a) {
            if (!(bounds.hi[a] > bounds.lo[a])) continue;
            Box boxes[kBins];
            uint32_t enter[kBins] = {}, exit[kBins] = {};
            for (uint32_t i = r.begin; i < r.end; ++i) {
                const PrimRef& ref = work_[i];
                const uint32_t b0 = spatialBin(bounds, a, ref.lower[a]), b1 = spatialBin(bounds, a, ref.upper[a]);
                ++enter[b0], ++exit[b1];
                if (b0 == b1) {
                    boxes[b0].grow(ref);
                    continue;
                }
                double v[3][3];
                triangleOf(ref, v);
                const Box refBox = Box::of(ref);
                for (uint32_t b = b0; b <= b1; ++b) {
                    const double lo = b == b0 ? -HUGE_VAL : binPlane(bounds, a, b);
                    const double hi = b == b1 ? HUGE_VAL : binPlane(bounds, a, b + 1);
                    boxes[b].grow(outwardWithin(clipToSlab(v, a, lo, hi), refBox));
                }
            }
            Box rightBoxes[kBins];
            uint32_t rightCounts[kBins];
            Box acc;
            uint32_t n = 0;
            for (uint32_t b = kBins; b-- > 1;) {
                acc.grow(boxes[b]);
                n += exit[b];
                rightBoxes[b] = acc, rightCounts[b] = n;
            }
            acc = Box{};
            n = 0;
            for (uint32_t b = 0; b + 1 < kBins; ++b) {
                acc.grow(boxes[b]);
                n += enter[b];
                const uint32_t nr = rightCounts[b + 1];
                // Both sides must make progress, and the references cut must fit the range's room.
                if (n == 0 || nr == 0 || n >= r.count() || nr >= r.count() || n + nr - r.count() > r.room()) continue;
                const double cost = acc.halfArea() * n + rightBoxes[b + 1].halfArea() * nr;
                if (cost < best.cost) {
                    best.cost = cost, best.axis = a, best.plane = binPlane(bounds, a, b + 1);
                    best.left = acc, best.right = rightBoxes[b + 1];
                    best.leftCount = n, best.rightCount = nr;
                }
            }
        }
        return best;
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

    void objectPartition(const Range& r, const ObjectSplit& s, Range& left, Range& right) {
        uint32_t nl = 0, nr = 0;
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const PrimRef& ref = work_[i];
            if (centroidBin(centroid(ref, s.axis), s.origin, s.scale) <= s.bin)
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
