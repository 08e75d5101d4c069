// Where each part of a structure lives and how large a structure can get: the section offsets, the bytes of one
// record, and the node-count bound that makes vkGetAccelerationStructureBuildSizesKHR's structure size safe for
// any build (docs/FORMAT.md derives it). The one place these sizes are decided.
#pragma once

#include <cstdint>

#include "engine/format/layout.hpp"

namespace vkas {

struct StructureLayout {
    uint64_t geometryOffset;
    uint64_t nodeOffset;
    uint64_t recordOffset;
    uint64_t end;  // used size
};

// Bytes per record. motion: the structure stores [NV-motion] records (format::MotionInstanceRecord for a top
// level, format::MotionTriangleRecord for a bottom level of triangles); see usesMotionRecords
// (input/build_inputs.hpp). Triangle, AABB, sphere and LSS records have one size (layout.hpp asserts it).
constexpr uint64_t recordSize(format::StructureType type, bool motion = false) {
    if (type == format::StructureType::TopLevel)
        return motion ? sizeof(format::MotionInstanceRecord) : sizeof(format::InstanceRecord);
    return motion ? sizeof(format::MotionTriangleRecord) : sizeof(format::TriangleRecord);
}
// The same, from the header fields of a block: a motion build (VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV,
// 0x20) stores motion records at the top level and for triangles (primitive type 0) only.
constexpr uint64_t recordSize(uint32_t type, uint32_t primitiveType, uint32_t buildFlags) {
    const bool motion = (buildFlags & 0x20u) != 0;
    const bool topLevel = type == uint32_t(format::StructureType::TopLevel);
    return recordSize(topLevel ? format::StructureType::TopLevel : format::StructureType::BottomLevel,
                      motion && (topLevel || primitiveType == 0 /* VK_GEOMETRY_TYPE_TRIANGLES_KHR */));
}

uint32_t maxLeafSize(format::StructureType type);
StructureLayout structureLayout(format::StructureType type, uint32_t geometryCount, uint64_t nodeCount,
                                uint64_t recordCount, bool motion = false);

// Upper bound on the nodes a build of n primitives writes (every builder keeps to it; docs/FORMAT.md derives it).
uint64_t maxWideNodeCount(uint64_t n, uint32_t maxLeafSize);

// The used size of the largest structure any build of `primitiveCount` primitives (or instances) in
// `geometryCount` geometries can make.
uint64_t maxStructureSize(format::StructureType type, uint32_t geometryCount, uint64_t primitiveCount,
                          bool motion = false);

}  // namespace vkas
