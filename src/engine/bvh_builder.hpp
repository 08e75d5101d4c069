// Top-down binned-SAH builder that writes 8-wide nodes directly: each node starts as one range and the child
// with the largest surface area is split (binned SAH over all three axes) until it has 8 children or no child
// is worth splitting. Deterministic: no randomness, ties broken by axis then bin order.
#pragma once

#include <cstdint>
#include <functional>

#include "engine/format.hpp"
#include "engine/math.hpp"

namespace vkas {

// A primitive's bounds and its index into the build's record array. 32 bytes, lives in scratch memory.
struct PrimRef {
    float lower[3];
    uint32_t index;
    float upper[3];
    uint32_t pad;
};
static_assert(sizeof(PrimRef) == 32);

struct BvhBuildSettings {
    uint32_t maxLeafSize;        // ranges of at most this many primitives become leaves
    uint32_t binCount = 32;      // SAH bins per axis (at most 32)
    uint32_t fewBinsBelow = 4096;  // ranges of fewer primitives get 8 bins (faster, about 1% more SAH cost); 0: never
    bool largestAxisOnly = false;  // bin only along the axis of the largest extent (faster, coarser)
    bool morton = false;  // build with the Morton-code builder (engine/morton_builder.hpp) instead of the SAH
};

// The settings a build's flags ask for: PREFER_FAST_BUILD the Morton-code builder (several times faster, a somewhat
// coarser tree); everything else the binned SAH, with 32 bins at every size for PREFER_FAST_TRACE and for top levels
// (an instance costs a whole bottom-level traversal, and instance counts are small).
BvhBuildSettings buildSettingsFor(uint32_t maxLeafSize, uint32_t buildFlags);

struct BvhBuildResult {
    format::ChildRef root = format::kEmptyRef;
    uint32_t nodeCount = 0;
    Aabb bounds;
};

// Runs fn(i) for every i in [0, count), possibly on several threads, and returns when all have run. Supplied by the
// API layer (deferred host operations); the builder's output does not depend on how the calls are scheduled.
using ParallelFor = std::function<void(uint32_t count, const std::function<void(uint32_t)>& fn)>;

// Upper bound on the nodes buildWideBvh writes for n primitives (docs/FORMAT.md derives it).
uint64_t maxWideNodeCount(uint64_t n, uint32_t maxLeafSize);

// Builds over refs[0..n) (reordered in place: leaves refer to ranges of refs) into nodes[0..nodeCount).
// With `parallel`, subtrees below a size threshold are built as independent tasks and then laid out in the
// order the serial build uses, so the nodes and refs are byte-identical to a build without it.
BvhBuildResult buildWideBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                            const ParallelFor* parallel = nullptr);

}  // namespace vkas
