// What vkGetAccelerationStructureBuildSizesKHR reports: the format's largest structure for the inputs, and the
// scratch memory a build of them uses (PrimRef[n], the temporary records[n], then the tree builders' workspace,
// treeWorkspacePerPrimitive bytes a primitive, which depend on the build flags; from the first 64-byte aligned address of the scratch buffer).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/builders/tree_builder.hpp"
#include "engine/format/layout.hpp"

namespace vkas {

struct StructureSizes {
    uint64_t structureSize;
    uint64_t buildScratchSize;
    uint64_t updateScratchSize;
};

// A safe upper bound for any build of `info`'s kind (type, record type, motion, geometry count) of `primitiveCount`
// primitives (or instances).
StructureSizes structureSizes(const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t primitiveCount);

// The tree builder's settings for a build of `info`'s kind of `primitiveCount` primitives: the selector's
// (buildSettingsFor), with the spatial-split budget where format/sizes.hpp's usesSpatialSplits allows cuts. The size
// query and the build both take them from here, so the scratch reserved is the scratch used.
BvhBuildSettings structureBuildSettings(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                        uint64_t primitiveCount);

// Bytes of the temporary record a build gathers per primitive into its scratch (a format::TriangleRecord for
// triangles, whatever their stored form; the stored record for every other kind).
uint64_t gatheredRecordSize(format::StructureType type, bool motion);

constexpr uint64_t kScratchAlignment = 64;

// The first kScratchAlignment-aligned byte of the build's scratch buffer, where the PrimRef array starts.
std::byte* alignedScratch(const VkAccelerationStructureBuildGeometryInfoKHR& info);

}  // namespace vkas
