// PREFER_FAST_TRACE with spatial splits (docs/PERFORMANCE.md, "PREFER_FAST_TRACE with spatial splits: the design";
// after Stich, Friedrich and Dietrich, "Spatial Splits in Bounding Volume Hierarchies", HPG 2009): a binary SAH tree
// whose splits may also cut the references that straddle a plane in two, each bounding only its part of the triangle,
// so that long or large triangles stop inflating the boxes around them. It is collapsed into 8-wide nodes as the
// quality builder's tree is (wide_collapse.hpp).
//
// A cut reference becomes a fragment: a record of the same triangle with a region of space (a half-open box) where
// it alone reports the triangle's hits (format/fragment_section.hpp). Regions start unbounded and each cut divides
// one at its plane, so one triangle's fragments always partition space. Each cut adds one reference, at most
// spatialSplitBudget(n) of them (format/sizes.hpp), which is what the sizes query bounds.
//
// Serial and deterministic: the same input gives the same bytes whatever the thread count. A tree the collapse
// cannot write within the output contract falls back to the quality builder over the untouched input.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/builders/tree_builder.hpp"

namespace vkas {

// The builder's workspace per primitive (tree_builder.hpp, treeWorkspacePerPrimitive): for n + n/4 references the
// working and spare PrimRef arrays, two binary nodes and two collapse entries each, and two regions per cut.
uint64_t spatialSplitWorkspacePerPrimitive();

// Builds over refs[0..n) (left as they are) with settings.triangles the gathered triangles the refs' indices name and
// settings.splitBudget the most cuts allowed. The result's refs (in the workspace) and refCount are the final
// references in leaf order; a reference with pad != 0 is a fragment whose region is result.regions[pad - 1].
BvhBuildResult buildSpatialSplitBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                                    std::byte* workspace, const ParallelFor* parallel = nullptr);

}  // namespace vkas
