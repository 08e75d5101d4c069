// Morton-code (LBVH-style) builder for PREFER_FAST_BUILD: sort the primitives along a Z-order curve of their
// centroids, then cut the sorted order top-down where the codes' highest differing bit changes, writing 8-wide
// nodes directly. No binning and no per-level bounds passes: child bounds come back up from the leaves.
#pragma once

#include <cstdint>

#include "engine/builders/tree_builder.hpp"
#include "engine/format/layout.hpp"

namespace vkas {

// The output contract of buildTree (tree_builder.hpp) (refs reordered so that leaves are ranges of them, preorder nodes, at most
// maxWideNodeCount(n, maxLeafSize) of them, depth at most format::kMaxTreeDepth). With `parallel`, every pass (bounds,
// keys, the sort, the tree writer's parts) runs on its threads, and the bytes are those of the build without it.
BvhBuildResult buildMortonBvh(PrimRef* refs, uint32_t n, uint32_t maxLeafSize, format::Node* nodes,
                              std::byte* workspace, const ParallelFor* parallel = nullptr);

}  // namespace vkas
