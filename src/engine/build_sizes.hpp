// Where each part of a structure lives, and the sizes vkGetAccelerationStructureBuildSizesKHR reports.
#pragma once

#include <cstdint>

#include "engine/format.hpp"

namespace vkas {

struct StructureLayout {
    uint64_t geometryOffset;
    uint64_t nodeOffset;
    uint64_t recordOffset;
    uint64_t end;  // used size
};

// motion: the structure stores [NV-motion] records (format::MotionInstanceRecord for a top level,
// format::MotionTriangleRecord for a bottom level of triangles); see usesMotionRecords in as_build.hpp.
uint64_t recordSize(format::StructureType type, bool motion = false);
uint32_t maxLeafSize(format::StructureType type);
StructureLayout structureLayout(format::StructureType type, uint32_t geometryCount, uint64_t nodeCount,
                                uint64_t recordCount, bool motion = false);

struct StructureSizes {
    uint64_t structureSize;
    uint64_t buildScratchSize;
    uint64_t updateScratchSize;
};

// A safe upper bound for any build of `primitiveCount` primitives (or instances) in `geometryCount` geometries.
StructureSizes structureSizes(format::StructureType type, uint32_t geometryCount, uint64_t primitiveCount,
                              bool motion = false);

// Scratch layout of a build: PrimRef[n] then temporary records[n], from the first 64-byte aligned address.
constexpr uint64_t kScratchAlignment = 64;

}  // namespace vkas
