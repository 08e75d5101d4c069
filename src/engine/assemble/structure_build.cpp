#include "engine/assemble/structure_build.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstring>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/opacity_section_build.hpp"
#include "engine/assemble/refit.hpp"
#include "engine/assemble/size_query.hpp"
#include "engine/builders/tree_builder.hpp"
#include "engine/format/fragment_section.hpp"
#include "engine/format/layout.hpp"
#include "vkas/vkas_compat.h"
#include "engine/format/sizes.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

using namespace format;

namespace {

void writeHeader(std::byte* dst, StructureType type, VkGeometryTypeKHR primitiveType,
                 const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t primitiveCount,
                 const BvhBuildResult& tree, uint32_t recordCount, const StructureLayout& layout, uint64_t usedSize,
                 uint64_t opacityOffset, uint64_t opacityReserved, uint32_t fragmentCount) {
    Header h;
    std::memset(&h, 0, sizeof h);
    h.magic = kMagic;
    h.version = kVersion;
    h.type = uint32_t(type);
    h.buildFlags = info.flags;
    h.usedSize = usedSize;
    h.root = tree.root;
    h.bounds[0] = tree.bounds.lower.x, h.bounds[1] = tree.bounds.lower.y, h.bounds[2] = tree.bounds.lower.z;
    h.bounds[3] = tree.bounds.upper.x, h.bounds[4] = tree.bounds.upper.y, h.bounds[5] = tree.bounds.upper.z;
    h.geometryCount = info.geometryCount;
    h.primitiveCount = uint32_t(primitiveCount);
    h.recordCount = recordCount;
    h.nodeCount = tree.nodeCount;
    h.geometryOffset = layout.geometryOffset;
    h.nodeOffset = layout.nodeOffset;
    h.recordOffset = layout.recordOffset;
    h.primitiveType = primitiveType;
    h.opacityOffset = opacityOffset;
    h.opacityReserved = opacityReserved;
    h.fragmentOffset = layout.fragmentOffset;
    h.fragmentCount = fragmentCount;
    std::memcpy(dst, &h, sizeof h);
}

// Zeroes the alignment gaps between sections so that every byte of [0, usedSize) depends only on the inputs.
void clearGaps(std::byte* dst, uint32_t geometryCount, uint64_t nodeCount, const StructureLayout& layout) {
    uint64_t geometryEnd = layout.geometryOffset + uint64_t(geometryCount) * sizeof(GeometryDesc);
    std::memset(dst + geometryEnd, 0, layout.nodeOffset - geometryEnd);
    uint64_t nodeEnd = layout.nodeOffset + nodeCount * sizeof(Node);
    std::memset(dst + nodeEnd, 0, layout.recordOffset - nodeEnd);
}

void writeGeometryDescs(std::byte* dst, const BuildJob& job) {
    const auto& info = *job.info;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        GeometryDesc d;
        std::memset(&d, 0, sizeof d);
        d.geometryType = geom.geometryType;
        d.flags = geom.flags;
        d.primitiveCount = job.ranges[g].primitiveCount;
        if (geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR) {
            d.vertexFormat = geom.geometry.triangles.vertexFormat;
            d.indexType = geom.geometry.triangles.indexType;
            d.maxVertex = geom.geometry.triangles.maxVertex;
            d.hasTransform = geom.geometry.triangles.transformData.hostAddress != nullptr;
            // What an update must compare its index values against (VUID 03768).
            if ((info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) &&
                geom.geometry.triangles.indexType != VK_INDEX_TYPE_NONE_KHR)
                d.indexHash = referencedIndexHash(geom.geometry.triangles, job.ranges[g]);
        }
        std::memcpy(dst + sizeof(Header) + g * sizeof(GeometryDesc), &d, sizeof d);
    }
}


// The primitives (or instances) given to the build, inactive ones included: a top level has one geometry (VUID
// 03790), whose instances count.
uint64_t primitiveTotal(const BuildJob& job) {
    const auto& info = *job.info;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR)
        return info.geometryCount ? job.ranges[0].primitiveCount : 0;
    uint64_t total = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) total += job.ranges[g].primitiveCount;
    return total;
}

// records[i] = temp[refs[i].index] for i in [begin, end), with the record size a constant of each copy loop (a copy
// of a size known at compile time is a few moves, not a call).
template <uint64_t kSize>
void copyRecords(std::byte* records, const std::byte* temp, const PrimRef* refs, uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i) std::memcpy(records + i * kSize, temp + uint64_t(refs[i].index) * kSize, kSize);
}

void copyInTreeOrder(uint64_t recordSize, std::byte* records, const std::byte* temp, const PrimRef* refs,
                     uint64_t begin, uint64_t end) {
    switch (recordSize) {
        case sizeof(AabbRecord): return copyRecords<sizeof(AabbRecord)>(records, temp, refs, begin, end);
        case sizeof(MotionTriangleRecord):
            return copyRecords<sizeof(MotionTriangleRecord)>(records, temp, refs, begin, end);
        case sizeof(InstanceRecord): return copyRecords<sizeof(InstanceRecord)>(records, temp, refs, begin, end);
        case sizeof(MotionInstanceRecord):
            return copyRecords<sizeof(MotionInstanceRecord)>(records, temp, refs, begin, end);
        default:
            for (uint64_t i = begin; i < end; ++i)
                std::memcpy(records + i * recordSize, temp + uint64_t(refs[i].index) * recordSize, recordSize);
    }
}

// Format 2 triangle leaves (layout.hpp, TriangleLeaf): leaf `ref` written from the gathered records its refs name;
// with `fragments`, a ref with a region (pad != 0: a spatial split's fragment) gets the kTriangleFragment flag.
void writeTriangleLeaf(std::byte* records, const std::byte* temp, const PrimRef* refs, ChildRef ref, bool fragments) {
    const uint64_t first = leafFirst(ref);
    const uint32_t n = leafCount(ref);
    const MutableTriangleLeaf leaf = triangleLeaf(records, first, n);
    const auto* gathered = reinterpret_cast<const TriangleRecord*>(temp);
    if (n == 4) {  // the common leaf: three 4x4 transposes of the records' 12 words
        __m128 a[4], b[4], c[4];
        for (uint32_t l = 0; l < 4; ++l) {
            const float* r = gathered[refs[first + l].index].v[0];
            a[l] = _mm_loadu_ps(r), b[l] = _mm_loadu_ps(r + 4), c[l] = _mm_loadu_ps(r + 8);
        }
        _MM_TRANSPOSE4_PS(a[0], a[1], a[2], a[3]);  // v0x v0y v0z v1x
        _MM_TRANSPOSE4_PS(b[0], b[1], b[2], b[3]);  // v1y v1z v2x v2y
        _MM_TRANSPOSE4_PS(c[0], c[1], c[2], c[3]);  // v2z geometryIndex primitiveIndex flags
        float* rows = leaf.row(0);
        for (uint32_t r = 0; r < 4; ++r) _mm_storeu_ps(rows + 4 * r, a[r]), _mm_storeu_ps(rows + 16 + 4 * r, b[r]);
        _mm_storeu_ps(rows + 32, c[0]);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(leaf.primitiveIndex()), _mm_castps_si128(c[2]));
        const __m128i geometry = _mm_and_si128(_mm_castps_si128(c[1]), _mm_set1_epi32(int(kGeometryIndexMask)));
        const __m128i flags = _mm_slli_epi32(_mm_castps_si128(c[3]), int(kGeometryIndexBits));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(leaf.geometryAndFlags()), _mm_or_si128(geometry, flags));
    } else {
        for (uint32_t lane = 0; lane < n; ++lane) leaf.setLane(lane, gathered[refs[first + lane].index]);
    }
    if (fragments)
        for (uint32_t lane = 0; lane < n; ++lane)
            if (refs[first + lane].pad != 0) leaf.geometryAndFlags()[lane] |= kTriangleFragment << kGeometryIndexBits;
}

// The fragment section (format/fragment_section.hpp): the region of every fragment, in record order.
void writeFragments(std::byte* dst, const StructureLayout& layout, const BvhBuildResult& tree) {
    uint32_t count = 0;
    for (uint32_t i = 0; i < tree.refCount; ++i) {
        const PrimRef& ref = tree.refs[i];
        if (ref.pad == 0) continue;
        FragmentEntry e;
        e.record = i;
        e.reserved = 0;
        const FragmentRegion& region = tree.regions[ref.pad - 1];
        std::memcpy(e.lower, region.lower, sizeof e.lower);
        std::memcpy(e.upper, region.upper, sizeof e.upper);
        std::memcpy(dst + layout.fragmentOffset + uint64_t(count++) * sizeof e, &e, sizeof e);
    }
}

uint32_t countFragments(const BvhBuildResult& tree) {
    uint32_t count = 0;
    if (tree.regions)
        for (uint32_t i = 0; i < tree.refCount; ++i) count += tree.refs[i].pad != 0;
    return count;
}

// Every leaf of the tree, found through the node slots that name it (or the root), on several threads for large trees.
void writeTriangleLeaves(const BuildJob& job, const Node* nodes, const BvhBuildResult& tree, std::byte* records,
                         const std::byte* temp, const PrimRef* refs) {
    const bool fragments = tree.regions != nullptr;
    if (isLeaf(tree.root)) writeTriangleLeaf(records, temp, refs, tree.root, fragments);
    constexpr uint32_t kNodeChunk = 4096;
    parallelForChunks(tree.nodeCount > 2 * kNodeChunk ? job.parallel : nullptr, tree.nodeCount, kNodeChunk,
                      [&](uint32_t, uint64_t begin, uint64_t end) {
                          for (uint64_t k = begin; k < end; ++k)
                              for (const ChildRef ref : nodes[k].child)
                                  if (isLeaf(ref)) writeTriangleLeaf(records, temp, refs, ref, fragments);
                      });
}

}  // namespace

VkResult buildAccelerationStructure(const BuildJob& job) {
    const auto& info = *job.info;
    const StructureType type = structureTypeOf(info.type);
    const uint64_t total = primitiveTotal(job);
    const bool motion = usesMotionRecords(info);  // [NV-motion] MotionInstanceRecords / MotionTriangleRecords
    const VkGeometryTypeKHR primitiveType = recordPrimitiveType(info);
    const uint64_t opacityBound = opacitySectionBound(info, [&](uint32_t g) { return job.ranges[g].primitiveCount; });
    if (maxStructureSize(type, primitiveType, info.geometryCount, total, motion, info.flags) + opacityBound >
        job.dstSize)
        return VK_ERROR_UNKNOWN;

    const PrimitiveKind& kind = primitiveKind(type == StructureType::TopLevel, primitiveType, motion);
    // Scratch: PrimRef[total], the gathered records in input order, the tree builders' workspace
    // (assemble/size_query.hpp).
    PrimRef* refs = nullptr;
    std::byte* temp = nullptr;
    std::byte* workspace = nullptr;
    if (total != 0) {
        refs = reinterpret_cast<PrimRef*>(alignedScratch(info));
        temp = reinterpret_cast<std::byte*>(refs + total);
        workspace = temp + total * gatheredRecordSize(type, motion);
    }
    const uint32_t n = total != 0 ? kind.gather(job, refs, temp) : 0;

    const StructureLayout pre = structureLayout(type, primitiveType, info.geometryCount, 0, 0, motion);
    auto* nodes = reinterpret_cast<Node*>(job.dst + pre.nodeOffset);
    BvhBuildSettings settings = structureBuildSettings(info, n);
    // PREFER_FAST_TRACE may cut triangles at planes (builders/spatial_split_builder.hpp), not with micromaps, whose
    // section follows the records.
    if (opacityBound != 0) settings.splitBudget = 0;
    if (settings.splitBudget != 0) settings.triangles = reinterpret_cast<const TriangleRecord*>(temp);
    BvhBuildResult tree = buildTree(refs, n, settings, nodes, workspace, job.parallel);
    if (!tree.refs) tree.refs = refs, tree.refCount = n;
    const uint32_t recordCount = tree.refCount;
    const uint32_t fragmentCount = countFragments(tree);
    const StructureLayout layout =
        structureLayout(type, primitiveType, info.geometryCount, tree.nodeCount, recordCount, motion, fragmentCount);
    // The records in tree order: leaf ranges of refs name their temp slots.
    std::byte* records = job.dst + layout.recordOffset;
    if (storesTriangleLeaves(type, primitiveType, motion)) {
        writeTriangleLeaves(job, nodes, tree, records, temp, tree.refs);
        const uint64_t recordEnd = fragmentCount != 0 ? layout.fragmentOffset : layout.end;
        std::memset(records + kTriangleBytes * recordCount, 0,
                    recordEnd - layout.recordOffset - kTriangleBytes * recordCount);  // tail
        if (fragmentCount != 0) writeFragments(job.dst, layout, tree);
    } else {
        const uint64_t size = recordSize(type, primitiveType, motion);
        constexpr uint32_t kCopyChunk = 65536;
        parallelForChunks(n > 2 * kCopyChunk ? job.parallel : nullptr, n, kCopyChunk,
                          [&](uint32_t, uint64_t begin, uint64_t end) {
                              copyInTreeOrder(size, records, temp, refs, begin, end);
                          });
    }
    // [EXT-OMM] The opacity micromaps after the records. A build that lets updates change micromaps keeps the room
    // its usage counts bound, so that an update can rewrite the section in place.
    uint64_t usedSize = layout.end, opacityOffset = 0, opacityReserved = 0;
    if (opacityBound != 0) {
        opacityOffset = alignOpacity(layout.end);
        std::memset(job.dst + layout.end, 0, opacityOffset - layout.end);
        const uint64_t written = writeOpacitySection(info, job.ranges, job.micromaps, job.dst, opacityOffset,
                                                     job.dstSize - opacityOffset);
        if (written == UINT64_MAX) return VK_ERROR_UNKNOWN;
        opacityReserved = written;
        if (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT)
            opacityReserved = std::max(written, alignOpacity(opacityBound));
        std::memset(job.dst + opacityOffset + written, 0, opacityReserved - written);
        usedSize = opacityOffset + opacityReserved;
    }
    writeGeometryDescs(job.dst, job);
    clearGaps(job.dst, info.geometryCount, tree.nodeCount, layout);
    writeHeader(job.dst, type, primitiveType, info, total, tree, recordCount, layout, usedSize, opacityOffset,
                opacityReserved, fragmentCount);
    return VK_SUCCESS;
}

}  // namespace vkas
