#include "engine/format/sizes.hpp"

#include <vulkan/vulkan_core.h>

#include "engine/format/fragment_section.hpp"

namespace vkas {

namespace {
constexpr uint64_t alignUp(uint64_t v, uint64_t a) { return (v + a - 1) / a * a; }
}  // namespace

uint32_t maxLeafSize(format::StructureType type) {
    return type == format::StructureType::TopLevel ? format::kMaxInstancesPerLeaf : format::kMaxPrimitivesPerLeaf;
}

StructureLayout structureLayout(format::StructureType type, uint32_t primitiveType, uint32_t geometryCount,
                                uint64_t nodeCount, uint64_t recordCount, bool motion, uint64_t fragmentCount) {
    StructureLayout l;
    l.geometryOffset = sizeof(format::Header);
    l.nodeOffset = alignUp(l.geometryOffset + uint64_t(geometryCount) * sizeof(format::GeometryDesc), 64);
    l.recordOffset = alignUp(l.nodeOffset + nodeCount * sizeof(format::Node), 64);
    l.end = l.recordOffset + recordCount * recordSize(type, primitiveType, motion) +
            recordTailSize(type, primitiveType, motion, recordCount);
    l.fragmentOffset = 0;
    if (fragmentCount != 0) {
        l.fragmentOffset = format::fragmentSectionOffset(l.end);
        l.end = l.fragmentOffset + fragmentCount * sizeof(format::FragmentEntry);
    }
    return l;
}

bool usesSpatialSplits(format::StructureType type, uint32_t primitiveType, bool motion, uint32_t buildFlags) {
    return storesTriangleLeaves(type, primitiveType, motion) &&
           (buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) &&
           !(buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR) &&
           !(buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
}

uint64_t maxWideNodeCount(uint64_t n, uint32_t maxLeafSize) {
    if (n <= maxLeafSize) return 0;
    // Nodes with fewer than 8 children have only leaf children and hold > maxLeafSize primitives, so there are
    // at most n / (maxLeafSize + 1) of them; the rest have 8 children: 7 * full + partial <= leaves - 1.
    uint64_t partial = n / (uint64_t(maxLeafSize) + 1);
    return partial + (n - 1) / 7 + 1;
}

uint64_t maxStructureSize(format::StructureType type, uint32_t primitiveType, uint32_t geometryCount,
                          uint64_t primitiveCount, bool motion, uint32_t buildFlags) {
    const uint64_t splits =
        usesSpatialSplits(type, primitiveType, motion, buildFlags) ? spatialSplitBudget(primitiveCount) : 0;
    const uint64_t records = primitiveCount + splits;
    const uint64_t nodes = maxWideNodeCount(records, maxLeafSize(type));
    return structureLayout(type, primitiveType, geometryCount, nodes, records, motion, 2 * splits).end;
}

}  // namespace vkas
