#include "engine/build_sizes.hpp"

#include "engine/bvh_builder.hpp"

namespace vkas {

namespace {
constexpr uint64_t alignUp(uint64_t v, uint64_t a) { return (v + a - 1) / a * a; }
}  // namespace

uint64_t recordSize(format::StructureType type, bool motion) {
    if (motion)
        return type == format::StructureType::TopLevel ? sizeof(format::MotionInstanceRecord)
                                                       : sizeof(format::MotionTriangleRecord);
    // Triangle and AABB records have the same size (format.hpp asserts it).
    return type == format::StructureType::TopLevel ? sizeof(format::InstanceRecord) : sizeof(format::TriangleRecord);
}

uint32_t maxLeafSize(format::StructureType type) {
    return type == format::StructureType::TopLevel ? format::kMaxInstancesPerLeaf : format::kMaxPrimitivesPerLeaf;
}

StructureLayout structureLayout(format::StructureType type, uint32_t geometryCount, uint64_t nodeCount,
                                uint64_t recordCount, bool motion) {
    StructureLayout l;
    l.geometryOffset = sizeof(format::Header);
    l.nodeOffset = alignUp(l.geometryOffset + uint64_t(geometryCount) * sizeof(format::GeometryDesc), 64);
    l.recordOffset = alignUp(l.nodeOffset + nodeCount * sizeof(format::Node), 64);
    l.end = l.recordOffset + recordCount * recordSize(type, motion);
    return l;
}

StructureSizes structureSizes(format::StructureType type, uint32_t geometryCount, uint64_t primitiveCount,
                              bool motion) {
    StructureSizes s;
    uint64_t nodes = maxWideNodeCount(primitiveCount, maxLeafSize(type));
    s.structureSize = structureLayout(type, geometryCount, nodes, primitiveCount, motion).end;
    s.buildScratchSize =
        primitiveCount == 0 ? 0 : kScratchAlignment + primitiveCount * (sizeof(PrimRef) + recordSize(type, motion));
    s.updateScratchSize = 0;  // a refit works in the structure itself (engine/refit.hpp)
    return s;
}

}  // namespace vkas
