// The one reader of a structure's bytes outside the trace and the checks: what `vkas inspect`, the benchmarks' SAH
// cost and `vkas heatmap`'s statistics ask of a block (docs/FORMAT.md): its header, its bytes by part, and a walk of
// its tree with depth, leaf-size and fill histograms and the SAH cost. Every offset is bounds-checked, so a block
// read wrongly fails with a reason instead of reading past it. Not reached from any command: it allocates with
// std::vector (the tools' memory), not the application's callbacks.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "engine/format/layout.hpp"
#include "engine/util/math.hpp"

namespace vkas::format {

struct TreeInspection {
    Header header{};
    bool motion = false;        // built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV
    bool triangleLeaves = false;  // records are format-2 triangle leaves (bottom level of triangles, no motion)
    uint32_t recordStride = 0;  // bytes per record (sizes.hpp, recordSize)

    // Bytes by part; they add up to usedSize. recordBytes holds the triangle array's zero tail.
    uint64_t headerBytes = 0, geometryBytes = 0, nodeBytes = 0, recordBytes = 0, micromapBytes = 0,
             fragmentBytes = 0, paddingBytes = 0;

    // The tree.
    uint64_t internalNodes = 0, leaves = 0, references = 0;
    std::vector<uint64_t> nodesAtDepth;   // internal nodes per depth (the root node is depth 0)
    std::vector<uint64_t> leavesAtDepth;  // leaves per depth (the number of internal nodes above them)
    std::vector<uint64_t> leafSizes;      // leafSizes[n]: leaves of n records
    std::array<uint64_t, kNodeWidth + 1> childrenPerNode{};  // childrenPerNode[k]: internal nodes with k children
    // SAH: the surface areas of the internal nodes' boxes, of the leaves' boxes times their records, and of the root.
    double sahNodes = 0, sahLeaves = 0, rootArea = 0;
    double sahCost() const { return rootArea > 0 ? (sahNodes + sahLeaves) / rootArea : 0; }
    double nodeFill() const;  // mean children per internal node / 8
};

// Reads the block's header and walks its tree. Returns nullptr, or the reason the bytes are not a format-2
// structure this can read (then `out` is partly filled).
const char* inspectTree(const std::byte* block, size_t size, TreeInspection& out);

// The slot boxes of the internal nodes at depth `level` (level 0: the root node's children), in node order.
// Returns nullptr or the reason, as inspectTree.
const char* boxesAtLevel(const std::byte* block, size_t size, uint32_t level, std::vector<Aabb>& out);

// A box's surface area (0 for an empty or inverted box), in double: the SAH of every reader.
double surfaceArea(const Aabb& b);

}  // namespace vkas::format
