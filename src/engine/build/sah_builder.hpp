// Top-down binned-SAH builder that writes 8-wide nodes directly: each node starts as one range and the child
// with the largest surface area is split (binned SAH over all three axes) until it has 8 children or no child
// is worth splitting. Deterministic: no randomness, ties broken by axis then bin order. Reached through the
// selector (tree_builder.hpp), whose output contract it keeps.
#pragma once

#include <cstdint>

#include "engine/build/tree_builder.hpp"

namespace vkas {

// With `parallel`, subtrees below a size threshold are built as independent tasks and then laid out in the
// order the serial build uses, so the nodes and refs are byte-identical to a build without it.
BvhBuildResult buildSahBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                           std::byte* workspace, const ParallelFor* parallel = nullptr);

}  // namespace vkas
