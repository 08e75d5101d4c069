// Top-down binned-SAH builder that writes 8-wide nodes directly: each node starts as one range and the child
// with the largest surface area is split (binned SAH over all three axes) until it has 8 children or no child
// is worth splitting. Deterministic: no randomness, ties broken by axis then bin order. Reached through the
// selector (tree_builder.hpp), whose output contract it keeps.
#pragma once

#include <cstdint>

#include "engine/builders/binary_tree.hpp"
#include "engine/builders/tree_builder.hpp"

namespace vkas {

// With `parallel`, subtrees below a size threshold are built as independent tasks and then laid out in the
// order the serial build uses, so the nodes and refs are byte-identical to a build without it.
BvhBuildResult buildSahBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                           std::byte* workspace, const ParallelFor* parallel = nullptr);

// The binary tree of the same splits, down to single primitives, into out[0..2n-1) (root 0, preorder: children
// after their parent); refs reordered in place, `spare` (n PrimRefs) the stable partition's buffer. Returns the node
// count, 2n - 1.
uint32_t buildBinarySahTree(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, BinaryNode* out,
                            PrimRef* spare, const ParallelFor* parallel = nullptr);

}  // namespace vkas
