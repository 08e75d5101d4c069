// One acceleration-structure build on plain memory: fetch the geometry, build the tree in scratch, write the
// format into the destination block.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/bvh_builder.hpp"

#include "engine/format.hpp"
#include "engine/geometry_fetch.hpp"
#include "engine/math.hpp"
#include "engine/motion.hpp"

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
    const ParallelFor* parallel = nullptr;  // spreads the build over threads (deferred operations); output unchanged
};

const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                        uint32_t i);

// [NV-motion] Whether a build stores motion records: built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV and a
// top level, or a bottom level of triangles (motion AABBs keep their ordinary records: only the application's
// intersection code knows how a box moves).
bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info);

// Returns VK_SUCCESS, or VK_ERROR_UNKNOWN when the destination cannot hold the result (nothing written then).
VkResult buildAccelerationStructure(const BuildJob& job);

// The record of active instance `instanceId` and its world-space box (the bottom level `blas`'s bounds
// transformed, rounded outwards), exactly as a top-level build stores them; shared with the refit (refit.hpp).
void makeInstanceRecord(const RawInstance& inst, uint32_t instanceId, const std::byte* blas,
                        format::InstanceRecord& rec, Aabb& box);
// [NV-motion] The same for a motion top level: the box holds the instance over the time range [0, 1].
void makeMotionInstanceRecord(const motion::RawMotionInstance& inst, uint32_t instanceId, const std::byte* blas,
                              format::MotionInstanceRecord& rec, Aabb& box);

}  // namespace vkas
