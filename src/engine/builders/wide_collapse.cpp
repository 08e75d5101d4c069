#include "engine/builders/wide_collapse.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "engine/format/sizes.hpp"

namespace vkas {

using format::ChildRef;
using format::Node;

namespace {

constexpr uint32_t kWidth = format::kNodeWidth;

// The DP of one binary node, its children's entries done. Every comparison keeps the first candidate on a tie or a
// NaN (infinite boxes), so the choice is deterministic and always a valid stand-in: a leaf only when the primitives
// fit one, an 8-wide node only of at least two roots.
void solve(const BinaryNode& b, const CollapseEntry* table, uint32_t maxLeafSize, const CollapseCosts& c,
           CollapseEntry& e) {
    const float area = b.halfArea();
    std::memset(&e, 0, sizeof e);
    if (b.isLeaf()) {
        const float leaf = area * (c.leaf + c.primitive);
        e.asLeaf = 1;
        for (uint32_t i = 0; i < kWidth; ++i) e.cost[i] = leaf;
        return;
    }
    const CollapseEntry& l = table[b.child[0]];
    const CollapseEntry& r = table[b.child[1]];
    // split[j]: the cheapest j roots, k from the left and j - k from the right (children's costs are "at most").
    float split[kWidth + 1];
    uint8_t splitK[kWidth + 1];
    for (uint32_t j = 2; j <= kWidth; ++j) {
        split[j] = l.cost[0] + r.cost[j - 2];
        splitK[j] = 1;
        for (uint32_t k = 2; k < j; ++k) {
            const float cost = l.cost[k - 1] + r.cost[j - k - 1];
            if (cost < split[j]) split[j] = cost, splitK[j] = uint8_t(k);
        }
    }
    const float asNode = area * c.node + split[kWidth];
    e.nodeSplit = splitK[kWidth];
    e.cost[0] = asNode;
    if (b.primCount <= maxLeafSize) {
        const float asLeaf = area * (c.leaf + c.primitive * float(b.primCount));
        if (!(asNode < asLeaf)) e.cost[0] = asLeaf, e.asLeaf = 1;
    }
    for (uint32_t i = 1; i < kWidth; ++i) {
        e.cost[i] = e.cost[0];
        if (split[i + 1] < e.cost[i]) e.cost[i] = split[i + 1], e.choice[i] = splitK[i + 1];
    }
}

class Collapser {
public:
    Collapser(const BinaryNode* tree, const CollapseEntry* table, PrimRef* refs, PrimRef* spare, Node* nodes)
        : tree_(tree), table_(table), refs_(refs), spare_(spare), nodes_(nodes) {}

    // The roots that stand for binary node b with at most `slots` of them, appended to roots[0..count).
    void gather(uint32_t b, uint32_t slots, uint32_t* roots, uint32_t& count) const {
        const uint8_t k = table_[b].choice[slots - 1];
        if (k == 0) {
            roots[count++] = b;
            return;
        }
        gather(tree_[b].child[0], k, roots, count);
        gather(tree_[b].child[1], slots - k, roots, count);
    }
    // The 8-wide node's roots of binary node b.
    uint32_t nodeRoots(uint32_t b, uint32_t* roots) const {
        uint32_t count = 0;
        const uint8_t k = table_[b].nodeSplit;
        gather(tree_[b].child[0], k, roots, count);
        gather(tree_[b].child[1], kWidth - k, roots, count);
        return count;
    }

    // The wide nodes below (and of) binary node b as a wide node, and the deepest wide level, without writing.
    void count(uint32_t b, uint32_t depth, uint64_t& nodes, uint32_t& maxDepth) const {
        ++nodes;
        maxDepth = std::max(maxDepth, depth);
        uint32_t roots[kWidth];
        const uint32_t n = nodeRoots(b, roots);
        for (uint32_t i = 0; i < n; ++i)
            if (!table_[roots[i]].asLeaf) count(roots[i], depth + 1, nodes, maxDepth);
    }

    // Writes binary node b as a wide node (preorder: its index before its children's), its leaves' refs to spare.
    ChildRef emit(uint32_t b) {
        const uint32_t index = nodeCount_++;
        uint32_t roots[kWidth];
        const uint32_t n = nodeRoots(b, roots);
        Node node;
        for (uint32_t i = n; i < kWidth; ++i) format::setEmptySlot(node, i);
        for (uint32_t i = 0; i < n; ++i) {
            const BinaryNode& r = tree_[roots[i]];
            format::setSlot(node, i, r.lower, r.upper, table_[roots[i]].asLeaf ? emitLeaf(roots[i]) : emit(roots[i]));
        }
        nodes_[index] = node;
        return format::makeInternalRef(index);
    }

    ChildRef emitLeaf(uint32_t b) {
        const uint64_t first = written_;
        appendPrimitives(b);
        return format::makeLeafRef(first, uint32_t(written_ - first));
    }

    uint32_t nodeCount() const { return nodeCount_; }
    uint64_t written() const { return written_; }

private:
    void appendPrimitives(uint32_t b) {  // a leaf's subtree: at most maxLeafSize primitives, a few levels
        const BinaryNode& node = tree_[b];
        if (node.isLeaf()) {
            spare_[written_++] = refs_[node.child[0]];
            return;
        }
        appendPrimitives(node.child[0]);
        appendPrimitives(node.child[1]);
    }

    const BinaryNode* tree_;
    const CollapseEntry* table_;
    PrimRef* refs_;
    PrimRef* spare_;
    Node* nodes_;
    uint32_t nodeCount_ = 0;
    uint64_t written_ = 0;
};

}  // namespace

CollapseResult collapseToWide(const BinaryNode* tree, uint32_t binaryCount, PrimRef* refs, uint32_t n,
                              uint32_t maxLeafSize, const CollapseCosts& costs, CollapseEntry* table, PrimRef* spare,
                              format::Node* nodes) {
    CollapseResult result;
    if (n == 0 || binaryCount == 0) return result;
    // Children before parents: a preorder (kept in the spare array, which holds 32n bytes; 2n - 1 indices fit) read
    // backwards.
    auto* order = reinterpret_cast<uint32_t*>(spare);
    uint32_t top = 0, filled = 0;
    order[filled++] = 0;
    while (top < filled) {
        const BinaryNode& b = tree[order[top++]];
        if (!b.isLeaf()) order[filled++] = b.child[0], order[filled++] = b.child[1];
    }
    for (uint32_t i = filled; i-- > 0;) solve(tree[order[i]], table, maxLeafSize, costs, table[order[i]]);

    Collapser collapser(tree, table, refs, spare, nodes);
    const Aabb rootBox{{tree[0].lower[0], tree[0].lower[1], tree[0].lower[2]},
                       {tree[0].upper[0], tree[0].upper[1], tree[0].upper[2]}};
    if (n <= maxLeafSize) {
        // One leaf, as the other builders make it: the refs keep their order.
        result.ok = true;
        result.tree.root = format::makeLeafRef(0, n);
        result.tree.bounds = rootBox;
        return result;
    }
    uint64_t wideNodes = 0;
    uint32_t depth = 0;
    collapser.count(0, 1, wideNodes, depth);
    if (wideNodes > maxWideNodeCount(n, maxLeafSize) || depth > format::kMaxTreeDepth) return result;
    result.tree.root = collapser.emit(0);
    result.tree.nodeCount = collapser.nodeCount();
    result.tree.bounds = rootBox;
    std::copy(spare, spare + n, refs);
    result.ok = true;
    return result;
}

}  // namespace vkas
