#include "engine/format/inspect.hpp"

#include <cstring>
#include <utility>

#include "engine/format/fragment_section.hpp"
#include "engine/format/motion.hpp"
#include "engine/format/sizes.hpp"

namespace vkas::format {
namespace {

Node nodeAt(const std::byte* block, const Header& h, uint32_t index) {
    Node n;
    std::memcpy(&n, block + h.nodeOffset + sizeof(Node) * uint64_t(index), sizeof n);
    return n;
}

Aabb slotBox(const Node& n, uint32_t s) {
    Aabb b;
    b.lower = {n.lowerX[s], n.lowerY[s], n.lowerZ[s]};
    b.upper = {n.upperX[s], n.upperY[s], n.upperZ[s]};
    return b;
}

// The header, checked far enough that every offset the walk reads lies inside the block.
const char* readHeader(const std::byte* block, size_t size, TreeInspection& t) {
    if (size < sizeof(Header)) return "the block is shorter than its 256-byte header";
    std::memcpy(&t.header, block, sizeof(Header));
    const Header& h = t.header;
    if (h.magic != kMagic) return "the block does not start with \"VKAS\"";
    if (h.version != kVersion) return "the block is not of format 2";
    if (h.usedSize > size) return "usedSize is past the end of the block";
    t.motion = motion::isMotionBuild(h.buildFlags);
    t.triangleLeaves = storesTriangleLeaves(structureTypeOf(h.type), h.primitiveType, t.motion);
    t.recordStride = uint32_t(recordSize(h.type, h.primitiveType, h.buildFlags));
    const uint64_t nodesEnd = h.nodeOffset + sizeof(Node) * uint64_t(h.nodeCount);
    const uint64_t recordsEnd = h.recordOffset + uint64_t(t.recordStride) * h.recordCount;
    if (h.geometryOffset < sizeof(Header) || h.geometryOffset > h.nodeOffset ||
        h.geometryOffset + sizeof(GeometryDesc) * uint64_t(h.geometryCount) > h.nodeOffset ||
        nodesEnd > h.recordOffset || recordsEnd > h.usedSize)
        return "the header's offsets are out of order or past usedSize";
    return nullptr;
}

}  // namespace

double surfaceArea(const Aabb& b) {
    if (!(b.lower.x <= b.upper.x && b.lower.y <= b.upper.y && b.lower.z <= b.upper.z)) return 0;
    const double dx = double(b.upper.x) - b.lower.x, dy = double(b.upper.y) - b.lower.y,
                 dz = double(b.upper.z) - b.lower.z;
    return 2 * (dx * dy + dy * dz + dz * dx);
}

double TreeInspection::nodeFill() const {
    uint64_t children = 0;
    for (size_t k = 0; k < childrenPerNode.size(); ++k) children += k * childrenPerNode[k];
    return internalNodes ? double(children) / (double(kNodeWidth) * double(internalNodes)) : 0;
}

const char* inspectTree(const std::byte* block, size_t size, TreeInspection& t) {
    if (const char* why = readHeader(block, size, t)) return why;
    const Header& h = t.header;

    // Bytes by part: header, geometry table, nodes, records (with the triangle array's zero tail), the opacity
    // micromap section, the fragment section (PREFER_FAST_TRACE's spatial splits) and the alignment gaps.
    t.headerBytes = sizeof(Header);
    t.geometryBytes = sizeof(GeometryDesc) * uint64_t(h.geometryCount);
    t.nodeBytes = sizeof(Node) * uint64_t(h.nodeCount);
    t.recordBytes = uint64_t(t.recordStride) * h.recordCount + recordTailSize(h.type, h.primitiveType, h.buildFlags,
                                                                               h.recordCount);
    t.micromapBytes = h.opacityReserved;
    t.fragmentBytes = sizeof(FragmentEntry) * uint64_t(h.fragmentCount);
    const uint64_t accounted =
        t.headerBytes + t.geometryBytes + t.nodeBytes + t.recordBytes + t.micromapBytes + t.fragmentBytes;
    t.paddingBytes = h.usedSize > accounted ? h.usedSize - accounted : 0;

    Aabb root;
    root.lower = {h.bounds[0], h.bounds[1], h.bounds[2]};
    root.upper = {h.bounds[3], h.bounds[4], h.bounds[5]};
    t.rootArea = surfaceArea(root);
    if (h.root == kEmptyRef) return nullptr;
    auto addLeaf = [&](ChildRef ref, uint32_t depth, double leafArea) {
        const uint32_t n = leafCount(ref);
        if (t.leavesAtDepth.size() <= depth) t.leavesAtDepth.resize(depth + 1);
        if (t.leafSizes.size() <= n) t.leafSizes.resize(n + 1);
        ++t.leavesAtDepth[depth];
        ++t.leafSizes[n];
        ++t.leaves;
        t.references += n;
        t.sahLeaves += leafArea * n;
    };
    if (isLeaf(h.root)) {
        addLeaf(h.root, 0, t.rootArea);
        return nullptr;
    }
    std::vector<std::pair<uint32_t, uint32_t>> stack{{nodeIndex(h.root), 0}};  // node, depth
    uint64_t visited = 0;
    while (!stack.empty()) {
        const auto [index, depth] = stack.back();
        stack.pop_back();
        if (index >= h.nodeCount || ++visited > h.nodeCount)
            return "a child reference names a node outside the node array";
        const Node node = nodeAt(block, h, index);
        if (t.nodesAtDepth.size() <= depth) t.nodesAtDepth.resize(depth + 1);
        ++t.nodesAtDepth[depth];
        ++t.internalNodes;
        Aabb nodeBox;
        uint32_t children = 0;
        for (uint32_t s = 0; s < kNodeWidth; ++s) {
            const ChildRef ref = node.child[s];
            if (!isInternal(ref) && !isLeaf(ref)) continue;
            ++children;
            const Aabb b = slotBox(node, s);
            nodeBox.extend(b);
            if (isInternal(ref)) stack.push_back({nodeIndex(ref), depth + 1});
            else addLeaf(ref, depth + 1, surfaceArea(b));
        }
        ++t.childrenPerNode[children];
        t.sahNodes += surfaceArea(nodeBox);
    }
    return nullptr;
}

const char* boxesAtLevel(const std::byte* block, size_t size, uint32_t level, std::vector<Aabb>& boxes) {
    TreeInspection t;
    if (const char* why = readHeader(block, size, t)) return why;
    const Header& h = t.header;
    if (!isInternal(h.root)) return nullptr;
    // Breadth first, level by level, so that boxes come in node order within the level.
    std::vector<uint32_t> current{nodeIndex(h.root)}, next;
    for (uint32_t depth = 0; !current.empty(); ++depth) {
        next.clear();
        for (uint32_t index : current) {
            if (index >= h.nodeCount) return "a child reference names a node outside the node array";
            const Node node = nodeAt(block, h, index);
            for (uint32_t s = 0; s < kNodeWidth; ++s) {
                const ChildRef ref = node.child[s];
                if (!isInternal(ref) && !isLeaf(ref)) continue;
                if (depth == level) boxes.push_back(slotBox(node, s));
                else if (isInternal(ref)) next.push_back(nodeIndex(ref));
            }
        }
        if (depth == level) break;
        if (next.size() > h.nodeCount) return "the tree has more nodes than nodeCount";
        current.swap(next);
    }
    return nullptr;
}

}  // namespace vkas::format
