// The optimal collapse of a binary BVH into 8-wide nodes (after Ylitie, Karras and Laine, "Efficient Incoherent Ray
// Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, section 3.1): bottom up, the cheapest way to stand for
// each binary subtree by at most i = 1..8 roots (leaves of at most maxLeafSize primitives or 8-wide nodes), by
// dynamic programming over the binary splits; then the wide nodes are written top down in preorder, and the refs
// reordered so that every leaf is a range of them. The cost is the surface-area cost of 8-wide traversal: a node
// visit, a leaf visit and each primitive tested (CollapseCosts).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/builders/binary_tree.hpp"
#include "engine/builders/tree_builder.hpp"
#include "engine/format/layout.hpp"

namespace vkas {

// Relative costs. A leaf's four lanes are tested together (trace/triangle_leaf_test.hpp), so a leaf costs about the
// same whatever it holds: the textbook model (a primitive costs 1, a leaf nothing) makes many small leaves that trace
// up to 18% slower (callgrind, diffuse rays on torcs-forza); these weights were the best of those tried there.
struct CollapseCosts {
    float node = 1.0f;        // visiting an 8-wide node (its eight box tests)
    float leaf = 2.0f;        // visiting a leaf, whatever it holds
    float primitive = 0.25f;  // each primitive a leaf holds
};

// The DP's table per binary node (scratch: as many as binary nodes).
struct CollapseEntry {
    float cost[8];       // cost[i]: the cheapest stand-in of at most i + 1 roots
    uint8_t choice[8];   // 0: the node itself as one root; k: k roots for the left child, i + 1 - k for the right
    uint8_t asLeaf;      // whether the node itself, as one root, is a leaf (else an 8-wide node)
    uint8_t nodeSplit;   // as an 8-wide node: k of its eight roots from the left child
    uint8_t pad[2];
};
static_assert(sizeof(CollapseEntry) == 44);

struct CollapseResult {
    bool ok = false;  // false: the tree would break the output contract (too many nodes or too deep); nothing written
    BvhBuildResult tree;
};

// Collapses tree[0..binaryCount) (root 0, n primitives) into nodes, keeping buildTree's output contract
// (tree_builder.hpp); refs are reordered through `spare` (n PrimRefs), `table` holds binaryCount entries.
CollapseResult collapseToWide(const BinaryNode* tree, uint32_t binaryCount, PrimRef* refs, uint32_t n,
                              uint32_t maxLeafSize, const CollapseCosts& costs, CollapseEntry* table, PrimRef* spare,
                              format::Node* nodes);

}  // namespace vkas
