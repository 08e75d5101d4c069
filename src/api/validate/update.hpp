// Valid usage of VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR: the source structure, and everything the update's
// inputs must keep from its last build (spec digest section 5). vkas remembers what these rules need in the
// structure itself (Header::type, buildFlags, geometryCount; one GeometryDesc per geometry; the records name the
// primitives that were active), so a compacted or cloned source is checked the same way.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// Rules on the source and on what must match its last build: 04630 (NULL source), 04629 (not a live structure),
// 03708 (no memory), 03667 (not built, or built without ALLOW_UPDATE), 03668 (src and dst alias without being the
// same structure), 03758 geometryCount, 03759 flags, 03760 type, 03761 geometryType, 03762 geometry flags, 03763
// vertexFormat, 03764 maxVertex, 03765 indexType, 03766 / 03767 transformData NULL-ness, 03769 primitiveCount.
// Returns the source's block when it is a structure built with ALLOW_UPDATE (nullptr otherwise). `ranges` may be
// NULL (03769 is then left to the range rules).
const std::byte* checkUpdateSource(Validator& v, const Device& dev, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                   const VkAccelerationStructureBuildRangeInfoKHR* ranges,
                                   const AccelerationStructure* dst, const char* where);

// Rules that read the update's input data, checked only when every other rule of the call passed so far (the
// pointers and offsets are then known to be usable): 03768 (index values), 03663 (an active primitive or instance
// made inactive) and 03664 (an inactive one made active). One message each, naming the first offender.
void checkUpdateData(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                     const VkAccelerationStructureBuildRangeInfoKHR* ranges, const std::byte* src, const char* where);

}  // namespace vkas
