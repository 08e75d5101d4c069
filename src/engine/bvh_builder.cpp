#include "engine/bvh_builder.hpp"

#include <algorithm>
#include <limits>

namespace vkas {

using format::ChildRef;
using format::Node;

uint64_t maxWideNodeCount(uint64_t n, uint32_t maxLeafSize) {
    if (n <= maxLeafSize) return 0;
    // Nodes with fewer than 8 children have only leaf children and hold > maxLeafSize primitives, so there are
    // at most n / (maxLeafSize + 1) of them; the rest have 8 children: 7 * full + partial <= leaves - 1.
    uint64_t partial = n / (uint64_t(maxLeafSize) + 1);
    return partial + (n - 1) / 7 + 1;
}

namespace {

constexpr int kBins = 32;

struct Range {
    uint32_t begin = 0, end = 0;
    uint32_t depth = 0;
    Aabb bounds;
    Aabb centroids;  // bounds of (lower + upper), i.e. twice the centroids
    uint32_t count() const { return end - begin; }
};

inline Vec3 refLower(const PrimRef& r) { return {r.lower[0], r.lower[1], r.lower[2]}; }
inline Vec3 refUpper(const PrimRef& r) { return {r.upper[0], r.upper[1], r.upper[2]}; }
inline Vec3 refCentroid2(const PrimRef& r) {
    return {r.lower[0] + r.upper[0], r.lower[1] + r.upper[1], r.lower[2] + r.upper[2]};
}

class WideBuilder {
public:
    WideBuilder(PrimRef* refs, const BvhBuildSettings& s, Node* nodes) : refs_(refs), settings_(s), nodes_(nodes) {}

    ChildRef build(const Range& r) {
        if (r.count() <= settings_.maxLeafSize) return format::makeLeafRef(r.begin, r.count());
        uint32_t index = nodeCount_++;
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
            if (best < 0) break;
            Range left, right;
            split(children[best], left, right);
            children[best] = left;
            children[n++] = right;
        }
        Node node;
        for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
            node.lowerX[i] = node.lowerY[i] = node.lowerZ[i] = std::numeric_limits<float>::infinity();
            node.upperX[i] = node.upperY[i] = node.upperZ[i] = -std::numeric_limits<float>::infinity();
            node.child[i] = format::kEmptyRef;
        }
        for (uint32_t i = 0; i < n; ++i) {
            const Aabb& b = children[i].bounds;
            node.lowerX[i] = b.lower.x, node.lowerY[i] = b.lower.y, node.lowerZ[i] = b.lower.z;
            node.upperX[i] = b.upper.x, node.upperY[i] = b.upper.y, node.upperZ[i] = b.upper.z;
            node.child[i] = build(children[i]);
        }
        nodes_[index] = node;
        return format::makeInternalRef(index);
    }

    uint32_t nodeCount() const { return nodeCount_; }

private:
    void finishRange(Range& r) {
        r.bounds = Aabb{};
        r.centroids = Aabb{};
        for (uint32_t i = r.begin; i < r.end; ++i) {
            r.bounds.extend(refLower(refs_[i]));
            r.bounds.extend(refUpper(refs_[i]));
            r.centroids.extend(refCentroid2(refs_[i]));
        }
    }

    void halve(const Range& r, Range& left, Range& right) {
        uint32_t mid = r.begin + r.count() / 2;
        left.begin = r.begin, left.end = mid;
        right.begin = mid, right.end = r.end;
        left.depth = right.depth = r.depth + 1;
        finishRange(left);
        finishRange(right);
    }

    void split(const Range& r, Range& left, Range& right) {
        Vec3 cl = r.centroids.lower, cu = r.centroids.upper;
        Vec3 extent = cu - cl;
        if (r.depth >= format::kSahDepthLimit || !(extent.x > 0 || extent.y > 0 || extent.z > 0)) {
            return halve(r, left, right);
        }
        float scale[3];
        for (int a = 0; a < 3; ++a) scale[a] = extent[a] > 0 ? (kBins * 0.99999f) / extent[a] : 0.0f;

        Aabb binBounds[3][kBins];
        uint32_t binCount[3][kBins] = {};
        auto binOf = [&](const PrimRef& p, int a) {
            float f = (p.lower[a] + p.upper[a] - cl[a]) * scale[a];
            // Written so that NaN or infinite coordinates (invalid input) still land in a valid bin.
            return f >= 1.0f ? (f < float(kBins) ? int(f) : kBins - 1) : 0;
        };
        for (uint32_t i = r.begin; i < r.end; ++i) {
            const PrimRef& p = refs_[i];
            for (int a = 0; a < 3; ++a) {
                int b = binOf(p, a);
                binCount[a][b]++;
                binBounds[a][b].extend(refLower(p));
                binBounds[a][b].extend(refUpper(p));
            }
        }
        float bestCost = std::numeric_limits<float>::infinity();
        int bestAxis = -1, bestBin = -1;
        for (int a = 0; a < 3; ++a) {
            if (scale[a] == 0.0f) continue;
            float rightArea[kBins];
            uint32_t rightCount[kBins];
            Aabb acc;
            uint32_t cnt = 0;
            for (int b = kBins - 1; b > 0; --b) {
                acc.extend(binBounds[a][b]);
                cnt += binCount[a][b];
                rightArea[b] = acc.halfArea();
                rightCount[b] = cnt;
            }
            acc = Aabb{};
            cnt = 0;
            for (int b = 0; b < kBins - 1; ++b) {  // split between bin b and b + 1
                acc.extend(binBounds[a][b]);
                cnt += binCount[a][b];
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

        // Partition in place: primitives in bins <= bestBin go left.
        uint32_t i = r.begin, j = r.end;
        while (i < j) {
            if (binOf(refs_[i], bestAxis) <= bestBin) {
                ++i;
            } else {
                --j;
                std::swap(refs_[i], refs_[j]);
            }
        }
        left.begin = r.begin, left.end = i;
        right.begin = i, right.end = r.end;
        left.depth = right.depth = r.depth + 1;
        finishRange(left);
        finishRange(right);
    }

    PrimRef* refs_;
    BvhBuildSettings settings_;
    Node* nodes_;
    uint32_t nodeCount_ = 0;
};

}  // namespace

BvhBuildResult buildWideBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, Node* nodes) {
    BvhBuildResult result;
    if (n == 0) return result;
    Range all;
    all.begin = 0, all.end = n;
    for (uint32_t i = 0; i < n; ++i) {
        all.bounds.extend(refLower(refs[i]));
        all.bounds.extend(refUpper(refs[i]));
        all.centroids.extend(refCentroid2(refs[i]));
    }
    WideBuilder builder(refs, settings, nodes);
    result.root = builder.build(all);
    result.nodeCount = builder.nodeCount();
    result.bounds = all.bounds;
    return result;
}

}  // namespace vkas
