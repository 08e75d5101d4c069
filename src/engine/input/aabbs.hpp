// Build inputs of AABB geometries: where AABB i is, and whether it is active or inverted.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

namespace vkas {

// AABB i is the VkAabbPositionsKHR at data + primitiveOffset + i * stride (any stride, 0 included: spec Q9).
class AabbSource {
public:
    AabbSource(const VkAccelerationStructureGeometryAabbsDataKHR& data,
               const VkAccelerationStructureBuildRangeInfoKHR& range);
    uint32_t primitiveCount() const { return count_; }
    // Reads AABB i as lower = (minX, minY, minZ), upper = (maxX, maxY, maxZ). Returns false when it is inactive
    // (minX is NaN).
    bool fetch(uint32_t i, float lower[3], float upper[3]) const;

private:
    const std::byte* data_;  // data + primitiveOffset
    uint64_t stride_;
    uint32_t count_;
};

// True unless min <= max on every axis (VUIDs 03546-03548; a NaN outside minX also fails). Such a box is invalid
// input; vkas never reports it.
bool isInvertedAabb(const float lower[3], const float upper[3]);

}  // namespace vkas
