#include "engine/util/host_memory.hpp"
#include "engine/builders/sah_builder.hpp"

#include <vulkan/vulkan_core.h>

#include "engine/builders/sah_wide_builder.hpp"

#include <algorithm>
#include <limits>
#include <memory>
#include <vector>

namespace vkas {

using format::ChildRef;
using format::Node;

namespace {

using namespace sah_detail;

// A part of a parallel build: its own nodes in pre-order from local index 0 (placeholders, WideBuilder::deferredRef(k),
// stand for parts[k]), its root reference, and how many nodes it holds with its parts.
struct Subtree {
    ChildRef root = format::kEmptyRef;
    HostVector<Node> nodes;
    HostVector<Subtree> parts;
    uint64_t totalNodes = 0;
};

// Ranges at or below this many primitives become independent tasks: large enough to amortise a task (2,048 made
// 16-thread builds of 4M triangles 15-30% slower), small enough that a million primitives give about a hundred.
constexpr uint32_t kParallelGrain = 8192;

// Builds the tree over r in parallel: the first node (and any child range over half of r) here, each other child
// range as a task that does the same, down to kParallelGrain.
void buildSubtree(PrimRef* refs, PrimRef* spare, const Range& r, const BvhBuildSettings& settings,
                  const ParallelFor& parallel, Subtree& out) {
    if (r.count() <= kParallelGrain) {
        out.nodes.reserve(r.count() / 8 + 4);
        WideBuilder builder(refs, settings, &out.nodes);
        builder.useSpare(spare);  // only for a range a stable partition left there, which goes back first (split)
        out.root = builder.build(r);
        out.totalNodes = out.nodes.size();
        return;
    }
    WideBuilder topBuilder(refs, settings, &out.nodes, &parallel);
    topBuilder.useSpare(spare);
    topBuilder.deferRangesUpTo(std::max(kParallelGrain, r.count() / 2));
    out.root = topBuilder.build(r);
    const HostVector<Range>& ranges = topBuilder.deferred();
    out.parts.resize(ranges.size());
    parallelFor(&parallel, uint32_t(ranges.size()),
             [&](uint32_t k) { buildSubtree(refs, spare, ranges[k], settings, parallel, out.parts[k]); });
    out.totalNodes = out.nodes.size();
    for (const Subtree& part : out.parts) out.totalNodes += part.totalNodes;
}

// Lays out a parallel build's parts as the serial build would: pre-order, a node's index before its children's
// subtrees, children in slot order. A part's own nodes are few (the top of its range); its parts' places follow
// from their node counts, so they are laid out in parallel, each node copied once, straight to the destination.
class Assembler {
public:
    Assembler(Node* out, const ParallelFor& parallel) : out_(out), parallel_(parallel) {}

    // Places `sub` with its first node at index `base`; returns its root reference.
    ChildRef place(const Subtree& sub, uint32_t base) {
        Placement p{sub, base, {}};
        const ChildRef root = placeNode(p, sub.root);
        parallelFor(&parallel_, uint32_t(p.parts.size()), [&](uint32_t k) { place(sub.parts[p.parts[k].first], p.parts[k].second); });
        return root;
    }

private:
    struct Placement {
        const Subtree& sub;
        uint32_t next;                                    // the next free node index
        HostVector<std::pair<uint32_t, uint32_t>> parts;  // (part, base) to place afterwards
    };

    ChildRef placeNode(Placement& p, ChildRef ref) {
        if (WideBuilder::isDeferred(ref)) {
            const uint32_t k = uint32_t(ref & 0xFFFF'FFFFu);
            const Subtree& part = p.sub.parts[k];
            const uint32_t base = p.next;
            p.next += uint32_t(part.totalNodes);
            p.parts.emplace_back(k, base);
            // A part's root is its first node in pre-order (or a leaf, placed as it is).
            return format::isInternal(part.root) ? format::makeInternalRef(base) : part.root;
        }
        if (!format::isInternal(ref)) return ref;
        const uint32_t index = p.next++;
        Node node = p.sub.nodes[format::nodeIndex(ref)];
        for (uint32_t i = 0; i < format::kNodeWidth; ++i)
            if (node.child[i] != format::kEmptyRef) node.child[i] = placeNode(p, node.child[i]);
        out_[index] = node;
        return format::makeInternalRef(index);
    }

    Node* out_;
    const ParallelFor& parallel_;
};

// The range of all n refs with their bounds, in chunks on several threads for a parallel build (min/max: the same in
// any order).
Range rootRange(const PrimRef* refs, uint32_t n, const ParallelFor* parallel) {
    Range all;
    all.begin = 0, all.end = n;
    constexpr uint32_t kBoundsChunk = 65536;
    const uint32_t chunks = (n + kBoundsChunk - 1) / kBoundsChunk;
    HostVector<SimdBoxNanSpreads> bounds(chunks);
    auto boundChunk = [&](uint32_t c) {
        SimdBoxNanSpreads b;
        for (uint32_t i = c * kBoundsChunk, end = std::min(n, (c + 1) * kBoundsChunk); i < end; ++i)
            b.extend(xyz(_mm_loadu_ps(refs[i].lower)), xyz(_mm_loadu_ps(refs[i].upper)));
        bounds[c] = b;
    };
    parallelFor(parallel, chunks, boundChunk);
    SimdBoxNanSpreads b;
    for (uint32_t c = 0; c < chunks; ++c) b.extend(bounds[c].lower, bounds[c].upper);
    all.bounds = b.aabb();
    return all;
}

}  // namespace

uint32_t buildBinarySahTree(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, BinaryNode* out,
                            PrimRef* spare, const ParallelFor* parallel) {
    if (n == 0) return 0;
    WideBuilder splitter(refs, settings, static_cast<Node*>(nullptr), parallel);
    if (n >= kStablePartitionMin) splitter.useSpare(spare);
    // Depth first, the left child first: node indices in preorder, so every child's index is above its parent's.
    struct Pending {
        Range range;
        uint32_t index;
    };
    HostVector<Pending> stack;
    stack.push_back({rootRange(refs, n, parallel), 0});
    out[0].parent = BinaryNode::kNone;
    uint32_t count = 1;
    while (!stack.empty()) {
        const Pending p = stack.back();
        stack.pop_back();
        BinaryNode& node = out[p.index];
        node.setBox(p.range.bounds);
        node.primCount = p.range.count();
        if (p.range.count() == 1) {
            node.child[0] = p.range.begin;
            node.child[1] = BinaryNode::kNone;
            continue;
        }
        Range left, right;
        splitter.splitRange(p.range, left, right);
        const uint32_t l = count++, r = count++;
        node.child[0] = l, node.child[1] = r;
        out[l].parent = out[r].parent = p.index;
        stack.push_back({right, r});
        stack.push_back({left, l});
    }
    return count;
}

BvhBuildResult buildSahBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, Node* nodes,
                           std::byte* workspace, const ParallelFor* parallel) {
    BvhBuildResult result;
    if (n == 0) return result;
    Range all = rootRange(refs, n, parallel);
    result.bounds = all.bounds;
    // Builds with large ranges partition those through a spare array (the workspace), with threads or without: the
    // same tree.
    PrimRef* spare = n >= kStablePartitionMin ? reinterpret_cast<PrimRef*>(workspace) : nullptr;
    if (!parallel || n <= 2 * kParallelGrain) {
        WideBuilder builder(refs, settings, nodes);
        builder.useSpare(spare);
        result.root = builder.build(all);
        result.nodeCount = builder.nodeCount();
        return result;
    }
    Subtree tree;
    buildSubtree(refs, spare, all, settings, *parallel, tree);
    Assembler assembler(nodes, *parallel);
    result.root = assembler.place(tree, 0);
    result.nodeCount = uint32_t(tree.totalNodes);
    return result;
}

}  // namespace vkas
