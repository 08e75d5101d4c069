// One acceleration-structure build on plain memory, the same path for every kind of structure: the kind's gather
// step (assemble/kinds/) reads the inputs into records and boxes in scratch, the selected builder
// (tree_builder.hpp) makes the tree, and the records, geometry table and header are written in the format.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

struct BuildJob {
    const VkAccelerationStructureBuildGeometryInfoKHR* info;
    const VkAccelerationStructureBuildRangeInfoKHR* ranges;  // info->geometryCount entries
    std::byte* dst;                                           // start of the destination block
    uint64_t dstSize;                                         // bytes available at dst
    BlasResolver resolver;
    const ParallelFor* parallel = nullptr;  // spreads the build over threads (deferred operations); output unchanged
    MicromapResolver micromaps = nullptr;   // [EXT-OMM] the micromaps that triangle geometries name
};

// Returns VK_SUCCESS, or VK_ERROR_UNKNOWN when the destination cannot hold the result (nothing written then).
VkResult buildAccelerationStructure(const BuildJob& job);

}  // namespace vkas
