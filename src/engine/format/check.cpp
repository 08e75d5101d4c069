#include "engine/util/host_memory.hpp"
#include "engine/format/check.hpp"

#include <cstring>

#include "engine/util/alongside.hpp"
#include "engine/format/fragment_section.hpp"
#include "engine/format/opacity_section.hpp"
#include "engine/format/sizes.hpp"
#include "engine/util/byte_io.hpp"
#include <vector>

#include <vulkan/vulkan_core.h>

#include "vkas/vkas_compat.h"

namespace vkas::format {

namespace {

CheckResult corrupt(const char* reason) { return {CheckStatus::Corrupt, reason}; }

bool isBottomLevelType(uint32_t t) {
    return t == VK_GEOMETRY_TYPE_TRIANGLES_KHR || t == VK_GEOMETRY_TYPE_AABBS_KHR ||
           t == uint32_t(VK_GEOMETRY_TYPE_SPHERES_NV) || t == uint32_t(VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV);
}

// Offset of geometryIndex in a bottom-level record; primitiveIndex follows it.
size_t geometryIndexOffset(uint32_t primitiveType) {
    switch (primitiveType) {
        case VK_GEOMETRY_TYPE_AABBS_KHR: return offsetof(AabbRecord, geometryIndex);
        case uint32_t(VK_GEOMETRY_TYPE_SPHERES_NV): return offsetof(SphereRecord, geometryIndex);
        case uint32_t(VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV): return offsetof(LssRecord, geometryIndex);
        default: return offsetof(TriangleRecord, geometryIndex);  // also the base of a motion triangle record
    }
}

// Checks one child reference; pushes internal nodes. Returns nullptr or the reason it is malformed.
struct TreeWalk {
    uint32_t nodeCount;
    uint64_t recordCount;
    HostVector<uint8_t> visited;
    HostVector<std::pair<uint32_t, uint32_t>> stack;  // node index, depth
    uint64_t nodesSeen = 0;
    uint64_t recordsCovered = 0;
    HostVector<ChildRef>* leaves = nullptr;  // format-2 triangles: every leaf, for the lane checks
    HostVector<uint64_t> covered = HostVector<uint64_t>((recordCount + 63) / 64, 0);  // records named by a leaf

    const char* visit(ChildRef ref, uint32_t depth) {
        const uint64_t kind = ref >> kKindShift;
        if (kind == 0) return ref == kEmptyRef ? nullptr : "an empty child slot has payload bits";
        if (kind == kKindInternal) {
            if ((ref & ~((kKindInternal << kKindShift) | 0xFFFF'FFFFull)) != 0) return "an internal reference has stray bits";
            const uint32_t index = nodeIndex(ref);
            if (index >= nodeCount) return "a child reference names a node outside the node array";
            if (visited[index]) return "a node is reached twice (a cycle or a shared subtree)";
            if (depth + 1 > kMaxTreeDepth) return "the tree is deeper than the traversal stack allows";
            visited[index] = 1;
            ++nodesSeen;
            stack.emplace_back(index, depth + 1);
            return nullptr;
        }
        if (kind == kKindLeaf) {
            if ((ref >> 48) & 0x3FFFull) return "a leaf reference has stray bits";
            const uint32_t count = leafCount(ref);
            const uint64_t first = leafFirst(ref);
            if (count == 0) return "a leaf holds no record";
            if (first > recordCount || count > recordCount - first) return "a leaf names records outside the record array";
            // Every record in exactly one leaf (what every build writes): overlapping triangle leaves would lay their
            // rows over each other (layout.hpp, TriangleLeaf), and a refit would write a record twice.
            for (uint64_t r = first; r < first + count; ++r) {
                if (covered[r / 64] & (1ull << (r % 64))) return "two leaves name the same record";
                covered[r / 64] |= 1ull << (r % 64);
            }
            recordsCovered += count;
            if (leaves) leaves->push_back(ref);
            return nullptr;
        }
        return "a child reference has an unknown kind";
    }
};

// [EXT-OMM] The opacity-micromap section (opacity_section.hpp): every geometry block inside the section, one
// primitive entry per primitive of its geometry, every entry's states inside its geometry's data. Sets hasBlock[g].
const char* checkOpacitySection(const std::byte* block, const Header& h, HostVector<uint8_t>& hasBlock) {
    hasBlock.assign(h.geometryCount, 0);
    if (h.opacityOffset == 0) return h.opacityReserved == 0 ? nullptr : "opacityReserved without an opacity section";
    if (h.type != uint32_t(StructureType::BottomLevel) || h.primitiveType != VK_GEOMETRY_TYPE_TRIANGLES_KHR)
        return "an opacity section in a structure that is not a bottom level of triangles";
    const uint64_t begin = h.opacityOffset, end = h.usedSize;
    if (begin % 8 != 0 || begin < h.recordOffset || begin > end || h.opacityReserved > end - begin)
        return "the opacity section is out of range";
    if (uint64_t(h.geometryCount) * 8 > h.opacityReserved) return "the opacity directory does not fit its section";
    const uint64_t sectionEnd = begin + h.opacityReserved;
    for (uint32_t g = 0; g < h.geometryCount; ++g) {
        const uint64_t at = load64(block + begin + 8ull * g);
        if (at == 0) continue;
        if (at % 8 != 0 || at < begin + 8ull * h.geometryCount || at > sectionEnd ||
            sectionEnd - at < sizeof(OpacityGeometry))
            return "an opacity geometry block is out of range";
        OpacityGeometry og;
        std::memcpy(&og, block + at, sizeof og);
        const uint32_t primitives = load32(block + h.geometryOffset + uint64_t(g) * sizeof(GeometryDesc) +
                                           offsetof(GeometryDesc, primitiveCount));
        if (og.primitiveCount != primitives) return "an opacity geometry block's primitive count is not its geometry's";
        const uint64_t primsAt = at + sizeof og;
        if (uint64_t(og.primitiveCount) * sizeof(OpacityPrimitive) > sectionEnd - primsAt)
            return "an opacity geometry block's primitives do not fit";
        if (og.dataOffset < primsAt + uint64_t(og.primitiveCount) * sizeof(OpacityPrimitive) ||
            og.dataOffset > sectionEnd || og.dataSize > sectionEnd - og.dataOffset)
            return "an opacity geometry block's data is out of range";
        for (uint32_t i = 0; i < og.primitiveCount; ++i) {
            OpacityPrimitive p;
            std::memcpy(&p, block + primsAt + uint64_t(i) * sizeof p, sizeof p);
            if (!isOpacityFormat(p.format) || p.subdivisionLevel > maxOpacitySubdivisionLevel(p.format))
                return "an opacity primitive has an invalid format or subdivision level";
            const uint64_t bytes = opacityTriangleDataBytes(p.subdivisionLevel, p.format);
            if (p.dataOffset > og.dataSize || bytes > og.dataSize - p.dataOffset)
                return "an opacity primitive's states are outside its geometry's data";
        }
        hasBlock[g] = 1;
    }
    return nullptr;
}

// The fragment section (fragment_section.hpp): where the layout puts it, inside usedSize, entries sorted by record,
// each inside the record array with a non-empty region. Zero offset and count without fragments.
const char* checkFragmentSection(const std::byte* block, const Header& h, bool triangleLeaves, uint64_t recordTail) {
    if (h.reserved1 != 0) return "a reserved header field is not zero";
    if (h.fragmentCount == 0) return h.fragmentOffset != 0 ? "a fragment section offset without fragments" : nullptr;
    if (!triangleLeaves) return "fragments in a structure without triangle leaves";
    if (h.opacityOffset != 0 || h.opacityReserved != 0) return "fragments in a structure with opacity micromaps";
    const uint64_t recordEnd = h.recordOffset + uint64_t(h.recordCount) * kTriangleBytes + recordTail;
    if (h.fragmentOffset != fragmentSectionOffset(recordEnd)) return "the fragment section does not follow the records";
    if (h.fragmentOffset > h.usedSize || uint64_t(h.fragmentCount) * sizeof(FragmentEntry) > h.usedSize - h.fragmentOffset)
        return "the fragment section does not fit in usedSize";
    if (h.fragmentCount > h.recordCount) return "more fragments than records";
    uint64_t previous = 0;
    for (uint32_t i = 0; i < h.fragmentCount; ++i) {
        FragmentEntry e;
        std::memcpy(&e, block + h.fragmentOffset + uint64_t(i) * sizeof e, sizeof e);
        if (e.record >= h.recordCount) return "a fragment names a record outside the record array";
        if (i != 0 && e.record <= previous) return "the fragment section is not sorted by record";
        previous = e.record;
        if (e.reserved != 0) return "a fragment's reserved word is not zero";
        for (int a = 0; a < 3; ++a)
            if (!(e.lower[a] < e.upper[a])) return "a fragment's region is empty";
    }
    return nullptr;
}

}  // namespace

CheckResult checkBlock(const std::byte* block, uint64_t size) {
    if (!block || size < sizeof(Header)) return corrupt("the block is shorter than its header");
    Header h;
    std::memcpy(&h, block, sizeof h);
    if (h.magic != kMagic) return corrupt("the header's magic is not \"VKAS\"");
    // Format 1 blocks are loaded too (format/convert.hpp rewrites them); their records are all arrays.
    if (h.version != kVersion && h.version != kFormat1) return corrupt("the header's format version is not 1 or 2");
    const bool format1 = h.version == kFormat1;
    if (h.usedSize < sizeof(Header) || h.usedSize > size) return corrupt("usedSize is out of range");
    const bool topLevel = h.type == uint32_t(StructureType::TopLevel);
    if (!topLevel && h.type != uint32_t(StructureType::BottomLevel)) return corrupt("the structure type is unknown");
    if (topLevel ? h.primitiveType != VK_GEOMETRY_TYPE_INSTANCES_KHR : !isBottomLevelType(h.primitiveType))
        return corrupt("the primitive type does not fit the structure type");
    // Sections: geometry table, nodes, records, in this order, inside [256, usedSize), aligned as the format says.
    const uint64_t used = h.usedSize;
    if (h.geometryOffset < sizeof(Header) || h.geometryOffset > used || h.geometryOffset % 8 != 0)
        return corrupt("geometryOffset is out of range");
    // In order before the sizes are subtracted (out of order, the differences below would wrap and pass).
    if (h.nodeOffset < h.geometryOffset || h.recordOffset < h.nodeOffset)
        return corrupt("the sections are not in the order geometry table, nodes, records");
    if (h.nodeOffset > used || h.nodeOffset % 64 != 0 ||
        uint64_t(h.geometryCount) * sizeof(GeometryDesc) > h.nodeOffset - h.geometryOffset)
        return corrupt("the geometry table does not fit before the nodes");
    if (h.recordOffset > used || h.recordOffset % 64 != 0 ||
        uint64_t(h.nodeCount) * sizeof(Node) > h.recordOffset - h.nodeOffset)
        return corrupt("the node array does not fit before the records");
    const bool triangleLeaves =
        !format1 && storesTriangleLeaves(structureTypeOf(h.type), h.primitiveType, motion::isMotionBuild(h.buildFlags));
    const uint64_t stride = format1 && !topLevel && !motion::isMotionBuild(h.buildFlags)
                                ? sizeof(TriangleRecord)  // every format-1 bottom-level record
                                : recordSize(h.type, h.primitiveType, h.buildFlags);
    const uint64_t tail = format1 ? 0 : recordTailSize(h.type, h.primitiveType, h.buildFlags, h.recordCount);
    if (uint64_t(h.recordCount) * stride + tail > used - h.recordOffset)
        return corrupt("the records do not fit in usedSize");
    // Format 2 stores geometry indices in 24 bits (layout.hpp, TriangleLeaf); format 1 blocks must fit to load.
    if (!topLevel && h.geometryCount > kGeometryIndexMask + 1) return corrupt("more geometries than 2^24");
    if (const char* why = checkFragmentSection(block, h, triangleLeaves, tail)) return corrupt(why);
    // Every record but a fragment stands for a primitive of its own.
    if (uint64_t(h.recordCount) > uint64_t(h.primitiveCount) + h.fragmentCount)
        return corrupt("more records than primitives");
    // Geometry table.
    for (uint32_t g = 0; g < h.geometryCount; ++g) {
        const uint32_t type = load32(block + h.geometryOffset + uint64_t(g) * sizeof(GeometryDesc));
        if (topLevel ? type != VK_GEOMETRY_TYPE_INSTANCES_KHR : type != h.primitiveType)
            return corrupt("a geometry's type does not match the structure's primitive type");
    }
    if (format1 && (h.opacityOffset != 0 || h.opacityReserved != 0)) return corrupt("a format-1 block with micromaps");
    HostVector<uint8_t> hasMicromaps;  // per geometry
    if (const char* why = checkOpacitySection(block, h, hasMicromaps)) return corrupt(why);
    // A triangle record that asks for its geometry's micromap must have one to read.
    auto micromapMissing = [&](uint32_t flags, uint32_t geometry) {
        return (flags & kTriangleMicromap) && !hasMicromaps[geometry];
    };
    HostVector<ChildRef> leaves;
    // Tree: every node reached exactly once from the root, no deeper than the traversal stack allows, every leaf
    // inside the record array, the leaves covering recordCount records.
    if (h.root == kEmptyRef) {
        if (h.nodeCount != 0 || h.recordCount != 0) return corrupt("an empty root with nodes or records");
    } else {
        TreeWalk walk{h.nodeCount, h.recordCount, HostVector<uint8_t>(h.nodeCount, 0), {}};
        walk.leaves = triangleLeaves ? &leaves : nullptr;
        if (const char* why = walk.visit(h.root, 0)) return corrupt(why);
        while (!walk.stack.empty()) {
            const auto [index, depth] = walk.stack.back();
            walk.stack.pop_back();
            const std::byte* node = block + h.nodeOffset + uint64_t(index) * sizeof(Node);
            for (uint32_t c = 0; c < kNodeWidth; ++c) {
                const ChildRef ref = load64(node + offsetof(Node, child) + 8 * c);
                if (const char* why = walk.visit(ref, depth)) return corrupt(why);
            }
        }
        if (walk.nodesSeen != h.nodeCount) return corrupt("some nodes are not reachable from the root");
        if (walk.recordsCovered != h.recordCount) return corrupt("the leaves do not cover the records exactly");
    }
    // Records: indices in range.
    const std::byte* records = block + h.recordOffset;
    auto primitivesOf = [&](uint32_t geometry) {
        return load32(block + h.geometryOffset + uint64_t(geometry) * sizeof(GeometryDesc) +
                      offsetof(GeometryDesc, primitiveCount));
    };
    if (triangleLeaves) {  // format 2 triangles: lane by lane through the leaves (which lie inside the array)
        uint64_t fragmentsSeen = 0;
        for (const ChildRef ref : leaves) {
            const uint64_t at = leafFirst(ref) * kTriangleBytes;
            const uint32_t n = leafCount(ref);
            for (uint32_t l = 0; l < n; ++l) {
                const uint32_t word = load32(records + at + 4 * (uint64_t(kTriangleRows + 1) * n + l));
                const uint32_t geometry = word & kGeometryIndexMask;
                if (geometry >= h.geometryCount) return corrupt("a record's geometryIndex is out of range");
                if (micromapMissing(word >> kGeometryIndexBits, geometry))
                    return corrupt("a triangle asks for an opacity micromap its geometry does not have");
                if ((word >> kGeometryIndexBits) & kTriangleFragment) {
                    if (!findFragment(block, uint32_t(leafFirst(ref) + l)))
                        return corrupt("a fragment record has no region in the fragment section");
                    ++fragmentsSeen;
                }
                if (load32(records + at + 4 * (uint64_t(kTriangleRows) * n + l)) >= primitivesOf(geometry))
                    return corrupt("a record's primitiveIndex is out of range");
            }
        }
        // The entries are sorted and distinct, so one per flagged record means no entry names an unflagged one.
        if (fragmentsSeen != h.fragmentCount) return corrupt("the fragment section names records that are not fragments");
        return {};
    }
    if (topLevel) {
        const bool motion = stride == sizeof(MotionInstanceRecord);
        for (uint64_t r = 0; r < h.recordCount; ++r) {
            const std::byte* rec = records + r * stride;
            if (load32(rec + serial::kInstanceIdOffset) >= h.primitiveCount)
                return corrupt("an instance record's instanceId is out of range");
            const uint32_t motionType = load32(rec + serial::kInstanceMotionTypeOffset);
            if (motion ? motionType > 2 : motionType != 0) return corrupt("an instance record's motion type is invalid");
        }
    } else {
        const size_t at = geometryIndexOffset(h.primitiveType);
        for (uint64_t r = 0; r < h.recordCount; ++r) {
            const std::byte* rec = records + r * stride;
            const uint32_t geometry = load32(rec + at);
            if (geometry >= h.geometryCount) return corrupt("a record's geometryIndex is out of range");
            if (load32(rec + at + 4) >= primitivesOf(geometry)) return corrupt("a record's primitiveIndex is out of range");
            if (h.primitiveType == VK_GEOMETRY_TYPE_TRIANGLES_KHR && micromapMissing(load32(rec + at + 8), geometry))
                return corrupt("a triangle asks for an opacity micromap its geometry does not have");
            // Only format-2 triangle leaves hold fragments (fragment_section.hpp).
            if (h.primitiveType == VK_GEOMETRY_TYPE_TRIANGLES_KHR && (load32(rec + at + 8) & kTriangleFragment))
                return corrupt("a triangle record outside triangle leaves is flagged as a fragment");
        }
    }
    return {};
}

CheckResult checkSerializedLayout(const std::byte* data, uint64_t size, serial::SerializedView* view) {
    using namespace serial;
    if (!data || size < kHeaderSize) return corrupt("the blob is shorter than the serialized header");
    SerializedView v;
    v.layout = layoutOf(reinterpret_cast<const uint8_t*>(data));
    v.blockVersion = blockVersionOf(reinterpret_cast<const uint8_t*>(data));
    if (v.layout == Layout::None)
        return {CheckStatus::Incompatible, "the driver or compatibility UUID is not one vkas loads"};
    v.data = data;
    v.serializedSize = load64(data + kSerializedSizeOffset);
    v.deserializedSize = load64(data + kDeserializedSizeOffset);
    const uint64_t count = load64(data + kHandleCountOffset);
    if (v.serializedSize < kHeaderSize || v.serializedSize > size) return corrupt("the serialized size is out of range");
    // [OMM-KHR] A bottom level may announce its (here: zero) blocks as 0xFFFFFFFF in the high word.
    const bool blockForm = (count >> 32) == 0xFFFF'FFFFull;
    if (blockForm && (count & 0xFFFF'FFFFull) != 0) return corrupt("the blob has opacity-micromap blocks");
    v.handleCount = blockForm ? 0 : count;
    const uint64_t prefix = opaquePrefixSize(v.layout);
    if (v.handleCount > (v.serializedSize - kHeaderSize) / 8) return corrupt("the handle count is out of range");
    if (v.serializedSize - kHeaderSize - 8 * v.handleCount < prefix)
        return corrupt("the serialized size leaves no room for the integrity hash");
    // The sizes must agree with each other before anything past the header is read: the header's serialized size
    // is the extent the application vouches for, so a changed size field must be caught from the header alone.
    if (v.serializedSize - kHeaderSize - 8 * v.handleCount - prefix != v.deserializedSize)
        return corrupt("the serialized size does not match the deserialized size and handle count");
    if (v.deserializedSize < sizeof(Header)) return corrupt("the deserialized size is shorter than a block header");
    v.handles = data + kHandlesOffset;
    if (v.layout == Layout::V2) v.storedHash = load64(v.handles + 8 * v.handleCount);
    v.block = v.handles + 8 * v.handleCount + prefix;
    if (view) *view = v;
    return {};
}

CheckResult checkLoadedBlock(const serial::SerializedView& view, const std::byte* block) {
    const CheckResult r = checkBlock(block, view.deserializedSize);
    if (!r.ok()) return r;
    Header h;
    std::memcpy(&h, block, sizeof h);
    if (h.usedSize != view.deserializedSize) return corrupt("the deserialized size is not the block's usedSize");
    if (h.version != view.blockVersion) return corrupt("the block's format version is not the compatibility UUID's");
    const bool topLevel = h.type == uint32_t(StructureType::TopLevel);
    const bool blockForm = (load64(view.data + serial::kHandleCountOffset) >> 32) == 0xFFFF'FFFFull;
    if (topLevel ? (blockForm || view.handleCount != h.primitiveCount) : view.handleCount != 0)
        return corrupt("the handle count does not match the structure");
    return {};
}

CheckResult checkSerialized(const std::byte* data, uint64_t size, serial::SerializedView* view) {
    serial::SerializedView v;
    const CheckResult layout = checkSerializedLayout(data, size, &v);
    if (!layout.ok()) return layout;
    // Serialized layout 2: any change of a hashed byte (everything but the handle array) is caught by the hash. It is
    // computed beside the structural checks (on a thread of its own for a large blob); both must pass.
    bool hashMatches = true;
    CheckResult block;
    alongside(
        v.layout == serial::Layout::V2 && v.deserializedSize >= serial::kHashAlongsideBytes,
        [&] { hashMatches = v.layout != serial::Layout::V2 || serial::integrityHash(v) == v.storedHash; },
        [&] { block = checkLoadedBlock(v, v.block); });
    if (!hashMatches) return corrupt("the integrity hash does not match the data (the blob was changed)");
    if (!block.ok()) return block;
    if (view) *view = v;
    return {};
}

}  // namespace vkas::format
