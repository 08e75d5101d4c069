// The valid usage of one vkBuildAccelerationStructuresKHR call (host builds): each info against itself (mode,
// destination, update source, geometries, ranges and their data, destination size and scratch) and the infos
// against each other. The rules shared with the size query are in geometry_info.hpp, the per-geometry range rules in
// build_ranges.hpp, those of UPDATE in update.hpp.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// Every rule of the call after the device: the deferred operation and the arrays, then each info in turn (and 03698:
// no destination twice), then the rules between infos, which have no order, so none may read or write what another
// writes (03403, 03701-03707, 03407). Reports into v; the command fails when v.failed().
void checkBuildAccelerationStructures(Validator& v, const Device& dev, VkDeferredOperationKHR deferredOperation,
                                      uint32_t infoCount, const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
                                      const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos);

}  // namespace vkas
