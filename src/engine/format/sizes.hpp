// Where each part of a structure lives and how large a structure can get: the section offsets, the bytes of one
// record, and the node-count bound that makes vkGetAccelerationStructureBuildSizesKHR's structure size safe for
// any build (docs/FORMAT.md derives it). The one place these sizes are decided.
#pragma once

#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/motion.hpp"

namespace vkas {

struct StructureLayout {
    uint64_t geometryOffset;
    uint64_t nodeOffset;
    uint64_t recordOffset;
    uint64_t fragmentOffset;  // 0 without fragments (format/fragment_section.hpp)
    uint64_t end;  // used size
};

// Bytes per record. motion: the structure stores [NV-motion] records (format::MotionInstanceRecord for a top
// level, format::MotionTriangleRecord for a bottom level of triangles); see usesMotionRecords
// (input/build_inputs.hpp). Format 2 stores a non-motion triangle in kTriangleBytes of its leaf (layout.hpp,
// TriangleLeaf); AABB, sphere and LSS records have the size of a TriangleRecord (layout.hpp asserts it).
constexpr bool storesTriangleLeaves(format::StructureType type, uint32_t primitiveType, bool motion) {
    return type == format::StructureType::BottomLevel && !motion && primitiveType == 0 /* TRIANGLES */;
}
constexpr uint64_t recordSize(format::StructureType type, uint32_t primitiveType, bool motion) {
    if (type == format::StructureType::TopLevel)
        return motion ? sizeof(format::MotionInstanceRecord) : sizeof(format::InstanceRecord);
    if (motion && primitiveType == 0) return sizeof(format::MotionTriangleRecord);
    return storesTriangleLeaves(type, primitiveType, motion) ? format::kTriangleBytes : sizeof(format::TriangleRecord);
}
// The same, from the header fields of a block of format 2: a motion build (motion::isMotionBuild) stores motion
// records at the top level and for triangles (primitive type 0) only.
constexpr format::StructureType structureTypeOf(uint32_t type) {
    return type == uint32_t(format::StructureType::TopLevel) ? format::StructureType::TopLevel
                                                             : format::StructureType::BottomLevel;
}
constexpr uint64_t recordSize(uint32_t type, uint32_t primitiveType, uint32_t buildFlags) {
    return recordSize(structureTypeOf(type), primitiveType, motion::isMotionBuild(buildFlags));
}
// Bytes after the last record: the zero tail of a triangle array (layout.hpp, kTriangleTailBytes), else none.
constexpr uint64_t recordTailSize(format::StructureType type, uint32_t primitiveType, bool motion, uint64_t recordCount) {
    return recordCount != 0 && storesTriangleLeaves(type, primitiveType, motion) ? format::kTriangleTailBytes : 0;
}
constexpr uint64_t recordTailSize(uint32_t type, uint32_t primitiveType, uint32_t buildFlags, uint64_t recordCount) {
    return recordTailSize(structureTypeOf(type), primitiveType, motion::isMotionBuild(buildFlags), recordCount);
}

uint32_t maxLeafSize(format::StructureType type);
StructureLayout structureLayout(format::StructureType type, uint32_t primitiveType, uint32_t geometryCount,
                                uint64_t nodeCount, uint64_t recordCount, bool motion = false,
                                uint64_t fragmentCount = 0);

// PREFER_FAST_TRACE with spatial splits (builders/spatial_split_builder.hpp): a bottom level of (non-motion) triangles
// built for the fastest trace and never updated (a refit cannot move a split plane) may store a triangle as several
// fragment records. The split budget bounds how many: at most spatialSplitBudget(n) splits, each adding one record
// and at most two fragment entries.
bool usesSpatialSplits(format::StructureType type, uint32_t primitiveType, bool motion, uint32_t buildFlags);
constexpr uint64_t spatialSplitBudget(uint64_t primitiveCount) {
    return primitiveCount >= 64 ? primitiveCount / 4 : 0;
}

// Upper bound on the nodes a build of n primitives writes (every builder keeps to it; docs/FORMAT.md derives it).
uint64_t maxWideNodeCount(uint64_t n, uint32_t maxLeafSize);

// The used size of the largest structure any build of `primitiveCount` primitives (or instances) in
// `geometryCount` geometries can make.
// `buildFlags`: the VkBuildAccelerationStructureFlagsKHR of the build, which decide whether spatial splits may add
// records (usesSpatialSplits).
uint64_t maxStructureSize(format::StructureType type, uint32_t primitiveType, uint32_t geometryCount,
                          uint64_t primitiveCount, bool motion = false, uint32_t buildFlags = 0);

}  // namespace vkas
