// One acceleration-structure build on plain memory: fetch the geometry, build the tree in scratch, write the
// format into the destination block.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

namespace vkas {

// Turns an instance's accelerationStructureReference into the block of the bottom-level structure it names,
// or nullptr when it names none. Supplied by the API layer, which owns the handles.
using BlasResolver = const std::byte* (*)(uint64_t reference);

struct BuildJob {
    const VkAccelerationStructureBuildGeometryInfoKHR* info;
    const VkAccelerationStructureBuildRangeInfoKHR* ranges;  // info->geometryCount entries
    std::byte* dst;                                           // start of the destination block
    uint64_t dstSize;                                         // bytes available at dst
    BlasResolver resolver;
};

const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                        uint32_t i);

// [NV-motion] Whether a build stores motion records: built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV and a
// top level, or a bottom level of triangles (motion AABBs keep their ordinary records: only the application's
// intersection code knows how a box moves).
bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info);

// Returns VK_SUCCESS, or VK_ERROR_UNKNOWN when the destination cannot hold the result (nothing written then).
VkResult buildAccelerationStructure(const BuildJob& job);

}  // namespace vkas
