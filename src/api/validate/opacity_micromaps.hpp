// [EXT-OMM] The valid usage of a triangle geometry's VkAccelerationStructureTrianglesOpacityMicromapEXT and of the
// acceleration-structure build flags and instance flags of VK_EXT_opacity_micromap.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

#include "api/validate/validator.hpp"

namespace vkas {

class Device;

// The structure's own rules (checked wherever a build info is: builds and the size query).
void checkOpacityMicromapStructure(Validator& v, const VkAccelerationStructureTrianglesOpacityMicromapEXT& omm,
                                   const char* where, uint32_t g);

// What a build reads through it: the micromap handle, the index values and the usage counts they must match.
// `primitiveCount` triangles of geometry g.
void checkOpacityMicromapRange(Validator& v, const Device& dev,
                               const VkAccelerationStructureTrianglesOpacityMicromapEXT& omm, uint32_t primitiveCount,
                               const char* where, uint32_t g);

}  // namespace vkas
