#include "engine/format/convert.hpp"

#include <cstring>

#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"
#include "engine/util/byte_io.hpp"

namespace vkas::format {

namespace {

Header loadHeader(const std::byte* block) {
    Header h;
    std::memcpy(&h, block, sizeof h);
    return h;
}

// Whether a format-1 block has triangle records that format 2 stores as leaves.
bool changesShape(const Header& h) {
    return h.version == kFormat1 && storesTriangleLeaves(structureTypeOf(h.type), h.primitiveType, motion::isMotionBuild(h.buildFlags));
}

// Format-1 leaf `ref` (48-byte records at src) written as a format-2 triangle leaf at dst.
void convertLeaf(const std::byte* src, std::byte* dst, ChildRef ref) {
    const uint64_t first = leafFirst(ref);
    const MutableTriangleLeaf leaf = triangleLeaf(dst, first, leafCount(ref));
    for (uint32_t lane = 0; lane < leaf.n; ++lane) {
        TriangleRecord t;
        std::memcpy(&t, src + (first + lane) * sizeof(TriangleRecord), sizeof t);
        // Format 1 flags use bits 0-2 (checkBlock bounds geometryIndex by the geometry count, at most 2^24).
        t.flags &= 0xFFu;
        leaf.setLane(lane, t);
    }
}

}  // namespace

uint64_t convertedSize(const std::byte* block) {
    const Header h = loadHeader(block);
    if (!changesShape(h)) return h.usedSize;
    return h.recordOffset + uint64_t(h.recordCount) * kTriangleBytes + (h.recordCount ? kTriangleTailBytes : 0);
}

void convertToCurrentFormat(const std::byte* src, std::byte* dst) {
    Header h = loadHeader(src);
    if (!changesShape(h)) {
        std::memcpy(dst, src, h.usedSize);
        h.version = kVersion;
        std::memcpy(dst, &h, sizeof h);
        return;
    }
    // Header, geometry table, nodes and the gaps as they are; then the leaves, found through the node slots that name
    // them (checkBlock saw every leaf inside the record array).
    std::memcpy(dst, src, h.recordOffset);
    const std::byte* records = src + h.recordOffset;
    std::byte* leaves = dst + h.recordOffset;
    std::memset(leaves, 0, convertedSize(src) - h.recordOffset);  // records no leaf names (none when built), the tail
    if (isLeaf(h.root)) convertLeaf(records, leaves, h.root);
    for (uint64_t k = 0; k < h.nodeCount; ++k)
        for (uint32_t c = 0; c < kNodeWidth; ++c) {
            const ChildRef ref = load64(src + h.nodeOffset + k * sizeof(Node) + offsetof(Node, child) + 8 * c);
            if (isLeaf(ref)) convertLeaf(records, leaves, ref);
        }
    h.version = kVersion;
    h.usedSize = convertedSize(src);
    std::memcpy(dst, &h, sizeof h);
}

}  // namespace vkas::format
