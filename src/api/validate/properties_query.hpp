// Rules on the parameters of vkWriteAccelerationStructuresPropertiesKHR after the device: the counts and pointers,
// the query type with its stride and pointer alignment (one pair of VUIDs per type), and each structure (a live
// one of `dev`, bound to memory, constructed, built for what the query type asks).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

void checkWriteAccelerationStructuresProperties(Validator& v, const Device& dev, uint32_t accelerationStructureCount,
                                                const VkAccelerationStructureKHR* pAccelerationStructures,
                                                VkQueryType queryType, size_t dataSize, void* pData, size_t stride);

}  // namespace vkas
