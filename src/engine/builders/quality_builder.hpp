// The PREFER_FAST_TRACE builder: a better tree for more build time. The binned SAH's splits make a binary tree down
// to single primitives (sah_builder.hpp), and the binary tree is collapsed into 8-wide nodes by dynamic programming,
// which picks the leaves and each node's eight children for the least surface-area cost (wide_collapse.hpp), where
// the default build fills each node greedily, splitting its largest child. Reached through the
// selector (tree_builder.hpp), whose output contract it keeps; a tree that would break it (too deep, too many nodes:
// possible only for pathological input) is replaced by the default SAH build.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/builders/tree_builder.hpp"

namespace vkas {

// The builder's workspace per primitive: the spare PrimRef array, two binary nodes and their collapse entries.
uint64_t qualityWorkspacePerPrimitive();

BvhBuildResult buildQualityBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                               std::byte* workspace, const ParallelFor* parallel = nullptr);

}  // namespace vkas
