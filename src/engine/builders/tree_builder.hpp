// The builder selector: every structure build hands its primitive boxes (PrimRefs) to buildTree, which runs the
// builder its settings name (TreeBuilder, chosen from the build flags by buildSettingsFor) and writes 8-wide nodes.
// Every builder keeps one output contract: refs reordered so that leaves are ranges of them, nodes in preorder, at
// most maxWideNodeCount(n, maxLeafSize) of them (format/sizes.hpp), depth at most format::kMaxTreeDepth, bytes
// independent of threading.
//   - binned SAH (sah_builder.hpp): the default build, bottom and top levels;
//   - Morton codes (morton_builder.hpp): PREFER_FAST_BUILD (which wins where both preferences are set);
//   - the quality builder (quality_builder.hpp: a binary SAH tree collapsed optimally): PREFER_FAST_TRACE, with
//     spatial splits (spatial_split_builder.hpp) where the structure build gives it a split budget and its triangles.
#pragma once

#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/util/math.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

// A primitive's bounds and its index into the build's record array. 32 bytes, lives in scratch memory.
struct PrimRef {
    float lower[3];
    uint32_t index;
    float upper[3];
    uint32_t pad;
};
static_assert(sizeof(PrimRef) == 32);

// The PrimRef of record `index` with box b.
inline void setPrimRef(PrimRef& ref, uint32_t index, const Aabb& b) {
    ref.lower[0] = b.lower.x, ref.lower[1] = b.lower.y, ref.lower[2] = b.lower.z;
    ref.upper[0] = b.upper.x, ref.upper[1] = b.upper.y, ref.upper[2] = b.upper.z;
    ref.index = index;
    ref.pad = 0;
}

// The sample the default build bins in a large range (BvhBuildSettings::binSampleTarget): chosen by the SAH cost and
// build time of the bench meshes (docs/PERFORMANCE.md, "Sampled binning").
constexpr uint32_t kDefaultBinSampleTarget = 1024;

// Which builder a build runs (one selector, as madmann91/bvh's default_builder.h: an enum, not a set of flags).
enum class TreeBuilder {
    Sah,      // binned SAH, straight to 8-wide nodes (sah_builder.hpp)
    Morton,   // Morton codes (morton_builder.hpp): PREFER_FAST_BUILD
    Quality,  // binary SAH collapsed optimally (quality_builder.hpp), spatial splits with a split budget: PREFER_FAST_TRACE
};

struct BvhBuildSettings {
    uint32_t maxLeafSize;        // ranges of at most this many primitives become leaves
    uint32_t binCount = 32;      // SAH bins per axis (at most 32)
    uint32_t fewBinsBelow = 4096;  // ranges of fewer primitives get 8 bins (faster, about 1% more SAH cost); 0: never
    bool largestAxisOnly = false;  // bin only along the axis of the largest extent (faster, coarser)
    // Ranges of at least twice this many primitives bin an evenly strided sample of about this many of them (the
    // split is chosen from the sample; the children's bounds are still every primitive's): the top of a large tree
    // is found at a fraction of the cost. 0: every primitive is binned.
    uint32_t binSampleTarget = 0;
    TreeBuilder builder = TreeBuilder::Sah;
    // With TreeBuilder::Quality: also cut references at planes, up to splitBudget cuts (spatial_split_builder.hpp), over the
    // gathered triangles the refs' indices name. Set by the structure build where format/sizes.hpp's
    // usesSpatialSplits allows it (the selector sees no triangles).
    uint32_t splitBudget = 0;
    const format::TriangleRecord* triangles = nullptr;
};

// The settings a build's flags ask for: PREFER_FAST_BUILD the Morton-code builder (several times faster, a somewhat
// coarser tree); PREFER_FAST_TRACE the quality builder (a better tree, several times slower to build); everything
// else the binned SAH, with 32 bins at every size for PREFER_FAST_TRACE and for top levels (an instance costs a whole
// bottom-level traversal, and instance counts are small), and sampled binning of large ranges for the default
// bottom-level build.
BvhBuildSettings buildSettingsFor(uint32_t maxLeafSize, uint32_t buildFlags);

// A spatial split's fragment region (spatial_split_builder.hpp): lower <= p < upper on every axis.
struct FragmentRegion {
    float lower[3];
    float upper[3];
};

struct BvhBuildResult {
    format::ChildRef root = format::kEmptyRef;
    uint32_t nodeCount = 0;
    Aabb bounds;
    // Where the leaves' references are: null for the refs given to buildTree (n of them, reordered); a spatial-split
    // build returns its own array of refCount references (more than n when it cut some) and their regions.
    const PrimRef* refs = nullptr;
    uint32_t refCount = 0;
    const FragmentRegion* regions = nullptr;
};

// The builders' temporary memory per primitive, which the build takes from its scratch buffer (after the gathered
// records: assemble/size_query.hpp) so that a build allocates nothing and an application that reuses its scratch
// buffer pays no page faults for it: the SAH builder's stable-partition buffer (a PrimRef each), the Morton
// builder's keys (two 8-byte words: the sort's two buffers) and sorted PrimRefs.
constexpr uint64_t kTreeWorkspacePerPrimitive = 48;

// The workspace bytes per primitive of the builder `settings` names: kTreeWorkspacePerPrimitive, or more for the
// quality builder (quality_builder.hpp) and its spatial splits (spatial_split_builder.hpp).
uint64_t treeWorkspacePerPrimitive(const BvhBuildSettings& settings);

// Builds over refs[0..n) (reordered in place) into nodes[0..nodeCount) with the builder `settings` names;
// `workspace` holds n * treeWorkspacePerPrimitive(settings) bytes, 16-byte aligned. With `parallel`, the output is
// byte-identical to a build without it.
BvhBuildResult buildTree(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                         std::byte* workspace, const ParallelFor* parallel = nullptr);

}  // namespace vkas
