#include "structure_tree.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace vkas_tool {
namespace {

constexpr uint64_t kHeaderSize = 256, kGeometryDescSize = 32, kNodeSize = 256;
constexpr uint32_t kMotionFlag = 0x20;  // VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV

template <class T>
T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

uint32_t kindOf(uint64_t ref) { return uint32_t(ref >> 62); }  // 0 empty, 1 internal node, 2 leaf
uint32_t nodeIndexOf(uint64_t ref) { return uint32_t(ref & 0xFFFFFFFFu); }
uint32_t leafCountOf(uint64_t ref) { return uint32_t((ref >> 40) & 0xFFu); }

double area(const Box& b) {
    if (!(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return 0;
    const double dx = double(b.hi.x) - b.lo.x, dy = double(b.hi.y) - b.lo.y, dz = double(b.hi.z) - b.lo.z;
    return 2 * (dx * dy + dy * dz + dz * dx);
}

Box slotBox(const unsigned char* node, int s) {
    // Structure of arrays: lowerX, upperX, lowerY, upperY, lowerZ, upperZ, 8 floats each.
    return {{load<float>(node + 4 * s), load<float>(node + 64 + 4 * s), load<float>(node + 128 + 4 * s)},
            {load<float>(node + 32 + 4 * s), load<float>(node + 96 + 4 * s), load<float>(node + 160 + 4 * s)}};
}

void grow(Box& a, const Box& b) {
    a.lo = {std::fmin(a.lo.x, b.lo.x), std::fmin(a.lo.y, b.lo.y), std::fmin(a.lo.z, b.lo.z)};
    a.hi = {std::fmax(a.hi.x, b.hi.x), std::fmax(a.hi.y, b.hi.y), std::fmax(a.hi.z, b.hi.z)};
}

Box emptyBox() { return {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }

void readHeader(const unsigned char* block, size_t size, TreeStats& t) {
    if (size < kHeaderSize) throw std::runtime_error("the block is shorter than its 256-byte header");
    if (load<uint32_t>(block) != 0x53414B56u) throw std::runtime_error("the block does not start with \"VKAS\"");
    t.version = load<uint32_t>(block + 4);
    t.type = load<uint32_t>(block + 8);
    t.buildFlags = load<uint32_t>(block + 12);
    t.usedSize = load<uint64_t>(block + 16);
    t.root = load<uint64_t>(block + 24);
    for (int k = 0; k < 6; ++k) t.bounds[k] = load<float>(block + 32 + 4 * k);
    t.geometryCount = load<uint32_t>(block + 56);
    t.primitiveCount = load<uint32_t>(block + 60);
    t.recordCount = load<uint32_t>(block + 64);
    t.nodeCount = load<uint32_t>(block + 68);
    t.geometryOffset = load<uint64_t>(block + 72);
    t.nodeOffset = load<uint64_t>(block + 80);
    t.recordOffset = load<uint64_t>(block + 88);
    t.primitiveType = load<uint32_t>(block + 96);
    t.motion = (t.buildFlags & kMotionFlag) != 0;
    if (t.version != 2) throw std::runtime_error("block format " + std::to_string(t.version) + ", this tool reads 2");
    if (t.usedSize > size) throw std::runtime_error("usedSize is past the end of the block");
    const bool top = t.type == 0;
    const bool triangles = !top && t.primitiveType == 0;
    t.recordStride = top ? (t.motion ? 256 : 128) : triangles ? (t.motion ? 96 : 44) : 48;
    const uint64_t nodesEnd = t.nodeOffset + kNodeSize * uint64_t(t.nodeCount);
    const uint64_t recordsEnd = t.recordOffset + uint64_t(t.recordStride) * t.recordCount;
    if (t.geometryOffset + kGeometryDescSize * uint64_t(t.geometryCount) > t.nodeOffset || nodesEnd > t.recordOffset ||
        recordsEnd > t.usedSize)
        throw std::runtime_error("the header's offsets are out of order or past usedSize");
}

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
    TreeStats t;
    readHeader(block, size, t);

    // Bytes by part: header, geometry table, nodes, records (with the triangles' 4-byte tail), the micromap section,
    // the fragment section (PREFER_FAST_TRACE's spatial splits) and the alignment gaps between them.
    t.headerBytes = kHeaderSize;
    t.geometryBytes = kGeometryDescSize * t.geometryCount;
    t.nodeBytes = kNodeSize * t.nodeCount;
    uint64_t records = uint64_t(t.recordStride) * t.recordCount;
    if (t.recordStride == 44 && t.recordCount > 0) records += 4;  // the zero tail of the last row's 16-byte load
    (t.type == 0 ? t.instanceBytes : t.recordStride == 44 ? t.leafBytes : t.recordBytes) = records;
    t.micromapBytes = size >= 120 ? load<uint64_t>(block + 112) : 0;  // opacityReserved (0 without micromaps)
    // fragmentCount: the spatial splits' fragment section, 32 bytes an entry (0 without)
    t.fragmentBytes = size >= 132 ? 32 * uint64_t(load<uint32_t>(block + 128)) : 0;
    const uint64_t accounted =
        t.headerBytes + t.geometryBytes + t.nodeBytes + records + t.micromapBytes + t.fragmentBytes;
    t.paddingBytes = t.usedSize > accounted ? t.usedSize - accounted : 0;

    const Box rootBox{{t.bounds[0], t.bounds[1], t.bounds[2]}, {t.bounds[3], t.bounds[4], t.bounds[5]}};
    t.rootArea = area(rootBox);
    if (t.root == 0) return t;
    auto addLeaf = [&](uint64_t ref, uint32_t depth, double leafArea) {
        const uint32_t n = leafCountOf(ref);
        if (t.leavesAtDepth.size() <= depth) t.leavesAtDepth.resize(depth + 1);
        if (t.leafSizes.size() <= n) t.leafSizes.resize(n + 1);
        ++t.leavesAtDepth[depth];
        ++t.leafSizes[n];
        ++t.leaves;
        t.references += n;
        t.sahLeaves += leafArea * n;
    };
    if (kindOf(t.root) == 2) {
        addLeaf(t.root, 0, t.rootArea);
        return t;
    }
    std::vector<std::pair<uint32_t, uint32_t>> stack{{nodeIndexOf(t.root), 0}};  // node, depth
    uint64_t visited = 0;
    while (!stack.empty()) {
        const auto [index, depth] = stack.back();
        stack.pop_back();
        if (index >= t.nodeCount || ++visited > t.nodeCount)
            throw std::runtime_error("a child reference names a node outside the node array");
        const unsigned char* node = block + t.nodeOffset + kNodeSize * index;
        if (t.nodesAtDepth.size() <= depth) t.nodesAtDepth.resize(depth + 1);
        ++t.nodesAtDepth[depth];
        ++t.internalNodes;
        Box nodeBox = emptyBox();
        uint32_t children = 0;
        for (int s = 0; s < 8; ++s) {
            const uint64_t ref = load<uint64_t>(node + 192 + 8 * s);
            if (kindOf(ref) == 0) continue;
            ++children;
            const Box b = slotBox(node, s);
            grow(nodeBox, b);
            if (kindOf(ref) == 1) stack.push_back({nodeIndexOf(ref), depth + 1});
            else if (kindOf(ref) == 2) addLeaf(ref, depth + 1, area(b));
        }
        ++t.childrenPerNode[children];
        t.sahNodes += area(nodeBox);
    }
    return t;
}

std::vector<Box> boxesAtLevel(const unsigned char* block, size_t size, uint32_t level) {
    TreeStats t;
    readHeader(block, size, t);
    std::vector<Box> boxes;
    if (t.root == 0 || kindOf(t.root) != 1) return boxes;
    // Breadth first, level by level, so that boxes come in node order within the level.
    std::vector<uint32_t> current{nodeIndexOf(t.root)}, next;
    for (uint32_t depth = 0; !current.empty(); ++depth) {
        next.clear();
        for (uint32_t index : current) {
            if (index >= t.nodeCount) throw std::runtime_error("a child reference names a node outside the node array");
            const unsigned char* node = block + t.nodeOffset + kNodeSize * index;
            for (int s = 0; s < 8; ++s) {
                const uint64_t ref = load<uint64_t>(node + 192 + 8 * s);
                if (kindOf(ref) == 0) continue;
                if (depth == level) boxes.push_back(slotBox(node, s));
                else if (kindOf(ref) == 1) next.push_back(nodeIndexOf(ref));
            }
        }
        if (depth == level) break;
        if (next.size() > t.nodeCount) throw std::runtime_error("the tree has more nodes than nodeCount");
        current.swap(next);
    }
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
