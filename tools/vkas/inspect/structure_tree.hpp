// Reads a vkas acceleration structure's bytes as docs/FORMAT.md documents them (header, 8-wide nodes with child
// references, leaves and records) for `vkas inspect`: counts, bytes by part, depth / leaf-size / fill histograms,
// the SAH cost, and the boxes of one tree level. The bytes come from a structure vkas built or loaded (and so
// checked); every offset is still bounds-checked here, so that a block the tool misreads fails with a message.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "scene.hpp"

namespace vkas_tool {

struct TreeStats {
    // Header fields (FORMAT.md, "Header").
    uint32_t version = 0, type = 0, buildFlags = 0, primitiveType = 0;
    uint32_t geometryCount = 0, primitiveCount = 0, recordCount = 0, nodeCount = 0;
    uint64_t usedSize = 0, root = 0, geometryOffset = 0, nodeOffset = 0, recordOffset = 0;
    float bounds[6] = {};
    bool motion = false;
    uint32_t recordStride = 0;  // bytes per record: 44 (triangle leaves), 48, 96, 128 or 256

    // Bytes by part; they add up to usedSize.
    uint64_t headerBytes = 0, geometryBytes = 0, nodeBytes = 0, leafBytes = 0, recordBytes = 0, instanceBytes = 0,
             micromapBytes = 0, fragmentBytes = 0, paddingBytes = 0;
    const char* recordPart() const;  // "leaves" (triangles), "records" (AABBs, spheres, LSS, motion) or "instances"

    // The tree.
    uint64_t internalNodes = 0, leaves = 0, references = 0;
    std::vector<uint64_t> nodesAtDepth;   // internal nodes per depth (the root node is depth 0)
    std::vector<uint64_t> leavesAtDepth;  // leaves per depth (the number of internal nodes above them)
    std::vector<uint64_t> leafSizes;      // leafSizes[n]: leaves of n records
    std::array<uint64_t, 9> childrenPerNode{};  // childrenPerNode[k]: internal nodes with k children
    double sahNodes = 0, sahLeaves = 0, rootArea = 0;
    double sahCost() const { return rootArea > 0 ? (sahNodes + sahLeaves) / rootArea : 0; }
    double nodeFill() const;  // mean children per internal node / 8
};

const char* structureTypeName(uint32_t type);
const char* primitiveTypeName(uint32_t primitiveType);

// Throws std::runtime_error when the bytes are not a structure this tool can read.
TreeStats analyseTree(const unsigned char* block, size_t size);

// The slot boxes of the internal nodes at depth `level` (level 0: the root node's children), in node order.
std::vector<Box> boxesAtLevel(const unsigned char* block, size_t size, uint32_t level);
// Writes boxes as an OBJ file (8 vertices and 6 quads each); throws std::runtime_error when it cannot.
void writeBoxesObj(const std::string& path, const std::vector<Box>& boxes, const std::string& comment);

}  // namespace vkas_tool
