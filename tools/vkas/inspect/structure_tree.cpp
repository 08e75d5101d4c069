#include "structure_tree.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "engine/format/inspect.hpp"  // the one reader of the format: header, bytes by part, tree walk, SAH

namespace vkas_tool {
namespace {

const std::byte* bytes(const unsigned char* block) { return reinterpret_cast<const std::byte*>(block); }

Box toBox(const vkas::Aabb& b) { return {{b.lower.x, b.lower.y, b.lower.z}, {b.upper.x, b.upper.y, b.upper.z}}; }

}  // namespace

const char* structureTypeName(uint32_t type) {
    return type == 0 ? "top level" : type == 1 ? "bottom level" : "unknown";
}

const char* primitiveTypeName(uint32_t p) {
    switch (p) {
    case 0: return "triangles";
    case 1: return "AABBs";
    case 2: return "instances";
    case 1000429004: return "spheres";
    case 1000429005: return "linear swept spheres";
    }
    return "unknown";
}

const char* TreeStats::recordPart() const {
    if (type == 0) return "instances";
    return primitiveType == 0 && !motion ? "leaves" : "records";
}

double TreeStats::nodeFill() const {
    uint64_t children = 0;
    for (size_t k = 0; k < childrenPerNode.size(); ++k) children += k * childrenPerNode[k];
    return internalNodes ? double(children) / (8.0 * double(internalNodes)) : 0;
}

TreeStats analyseTree(const unsigned char* block, size_t size) {
    vkas::format::TreeInspection in;
    if (const char* why = vkas::format::inspectTree(bytes(block), size, in)) throw std::runtime_error(why);
    const vkas::format::Header& h = in.header;
    TreeStats t;
    t.version = h.version, t.type = h.type, t.buildFlags = h.buildFlags, t.primitiveType = h.primitiveType;
    t.geometryCount = h.geometryCount, t.primitiveCount = h.primitiveCount, t.recordCount = h.recordCount;
    t.nodeCount = h.nodeCount;
    t.usedSize = h.usedSize, t.root = h.root, t.geometryOffset = h.geometryOffset, t.nodeOffset = h.nodeOffset;
    t.recordOffset = h.recordOffset;
    for (int k = 0; k < 6; ++k) t.bounds[k] = h.bounds[k];
    t.motion = in.motion;
    t.recordStride = in.recordStride;
    t.headerBytes = in.headerBytes, t.geometryBytes = in.geometryBytes, t.nodeBytes = in.nodeBytes;
    (t.type == 0 ? t.instanceBytes : in.triangleLeaves ? t.leafBytes : t.recordBytes) = in.recordBytes;
    t.micromapBytes = in.micromapBytes, t.fragmentBytes = in.fragmentBytes, t.paddingBytes = in.paddingBytes;
    t.internalNodes = in.internalNodes, t.leaves = in.leaves, t.references = in.references;
    t.nodesAtDepth = in.nodesAtDepth, t.leavesAtDepth = in.leavesAtDepth, t.leafSizes = in.leafSizes;
    for (size_t k = 0; k < t.childrenPerNode.size(); ++k) t.childrenPerNode[k] = in.childrenPerNode[k];
    t.sahNodes = in.sahNodes, t.sahLeaves = in.sahLeaves, t.rootArea = in.rootArea;
    return t;
}

std::vector<Box> boxesAtLevel(const unsigned char* block, size_t size, uint32_t level) {
    std::vector<vkas::Aabb> found;
    if (const char* why = vkas::format::boxesAtLevel(bytes(block), size, level, found)) throw std::runtime_error(why);
    std::vector<Box> boxes;
    boxes.reserve(found.size());
    for (const auto& b : found) boxes.push_back(toBox(b));
    return boxes;
}

void writeBoxesObj(const std::string& path, const std::vector<Box>& boxes, const std::string& comment) {
    FILE* f = std::fopen(path.c_str(), "w");
    if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    std::fprintf(f, "# %s\n# %zu boxes, 8 vertices and 6 faces each\n", comment.c_str(), boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
        const Box& b = boxes[i];
        std::fprintf(f, "o box%zu\n", i);
        for (int c = 0; c < 8; ++c)
            std::fprintf(f, "v %.9g %.9g %.9g\n", (c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                         (c & 4) ? b.hi.z : b.lo.z);
        const unsigned base = unsigned(8 * i + 1);
        static const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
        for (const auto& q : faces)
            std::fprintf(f, "f %u %u %u %u\n", base + q[0], base + q[1], base + q[2], base + q[3]);
    }
    const bool ok = std::ferror(f) == 0;
    if (std::fclose(f) != 0 || !ok) throw std::runtime_error("cannot write " + path);
}

}  // namespace vkas_tool
