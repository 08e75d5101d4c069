// [EXT-OMM] Reads a triangle geometry's VkAccelerationStructureTrianglesOpacityMicromapEXT: which micromap triangle
// (or special index) each triangle uses, and the usage counts the application declares. Decides nothing about trees.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

namespace vkas {

using TrianglesOpacityMicromap = VkAccelerationStructureTrianglesOpacityMicromapEXT;

// The structure in the triangles' pNext chain, or nullptr when the geometry has no opacity micromap.
const TrianglesOpacityMicromap* opacityMicromapOf(const VkAccelerationStructureGeometryTrianglesDataKHR& triangles);

// What triangle i of the geometry uses: a special index (VkOpacityMicromapSpecialIndexEXT, -1 .. -4), or
// micromap triangle `triangle` (the fetched index plus baseTriangle, as 64 bits so that the sum cannot wrap).
struct OpacityIndex {
    bool special;
    int32_t specialIndex;
    uint64_t triangle;
};

// "For each triangle in the geometry, the acceleration structure build fetches an index from indexBuffer using
// indexType and indexStride if present. If indexType is VK_INDEX_TYPE_NONE_KHR, then the index used is the index of
// the triangle in the geometry. If that value is the unsigned cast of one of the values from
// VkOpacityMicromapSpecialIndexEXT then that triangle behaves as described for that special value [...]. Otherwise
// that triangle uses the opacity micromap information from micromap at that index plus baseTriangle."
OpacityIndex opacityIndexOf(const TrianglesOpacityMicromap& omm, uint32_t triangle);

// The usage counts of the structure (pUsageCounts or ppUsageCounts; "only one of [them] can be a valid pointer").
const VkMicromapUsageEXT* usageCountAt(const TrianglesOpacityMicromap& omm, uint32_t i);
template <class Fn>
void forEachUsageCount(const TrianglesOpacityMicromap& omm, const Fn& fn) {
    for (uint32_t i = 0; i < omm.usageCountsCount; ++i)
        if (const VkMicromapUsageEXT* u = usageCountAt(omm, i)) fn(*u);
}

}  // namespace vkas
