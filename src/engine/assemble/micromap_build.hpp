// Opacity-micromap builds on plain memory (vkBuildMicromapsEXT, vkGetMicromapBuildSizesEXT; docs/FORMAT.md,
// "Micromaps"). A build copies each triangle's states into the micromap block of format/micromap_layout.hpp, in
// triangle order, so the same inputs always give the same bytes.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/micromap_layout.hpp"

namespace vkas {

// Usage count i of a build info: pUsageCounts[i], or *ppUsageCounts[i] when pUsageCounts is NULL.
const VkMicromapUsageEXT& micromapUsage(const VkMicromapBuildInfoEXT& info, uint32_t i);

// The number of micromap triangles the usage counts describe (the sum of their counts).
uint64_t micromapTriangleCount(const VkMicromapBuildInfoEXT& info);

// The block size of a micromap with those usage counts: the header, 8 bytes per triangle and each triangle's states
// (format::opacityTriangleDataBytes). UINT64_MAX when a format or level is not valid; saturates at UINT64_MAX.
uint64_t micromapSizeForUsage(const VkMicromapBuildInfoEXT& info);

// Micromap triangle i of the build's triangleArray (triangleArrayStride apart; any alignment).
format::MicromapTriangle readMicromapTriangle(const VkMicromapBuildInfoEXT& info, uint64_t i);

// Writes the micromap block of `info` at `dst`, which holds `dstSize` bytes. Returns VK_ERROR_UNKNOWN with nothing
// written when a triangle has a format or level vkas does not build, or the triangles need more than dstSize bytes
// (validation reports both first; this keeps a build with validation off inside its destination), and
// VK_ERROR_OUT_OF_DEVICE_MEMORY when the states exceed 4 GiB (the block's triangle offsets are 32-bit).
VkResult buildMicromap(const VkMicromapBuildInfoEXT& info, std::byte* dst, uint64_t dstSize);

}  // namespace vkas
