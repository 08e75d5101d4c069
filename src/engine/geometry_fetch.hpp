// Reads build inputs exactly as VkAccelerationStructureBuildRangeInfoKHR defines: which bytes hold triangle i's
// vertices, its transform, AABB i, and which instance is number i. Host pointers have no alignment requirement.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/math.hpp"

namespace vkas {

class TriangleSource {
public:
    TriangleSource(const VkAccelerationStructureGeometryTrianglesDataKHR& data,
                   const VkAccelerationStructureBuildRangeInfoKHR& range);

    uint32_t primitiveCount() const { return count_; }
    // Object-space positions of triangle i (after decode and geometry transform). Returns false when the
    // triangle is inactive (the X of a vertex is NaN in the input data).
    bool fetch(uint32_t i, float v[3][3]) const;
    // The vertex index (before firstVertex is added) that corner j of triangle i reads.
    uint64_t vertexIndex(uint32_t i, uint32_t j) const;

private:
    VkFormat format_;
    const std::byte* vertices_;  // first vertex the geometry may address (firstVertex already applied)
    uint64_t stride_;
    VkIndexType indexType_;
    const std::byte* indices_;  // indexData + primitiveOffset
    bool hasTransform_;
    Affine3x4d transform_;
    uint32_t count_;
};

// True when a triangle collapses to a line or a point: it never produces an intersection.
bool isDegenerateTriangle(const float v[3][3]);

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

// VkAccelerationStructureInstanceKHR as raw words: the packed 24/8-bit fields are decoded with shifts.
struct RawInstance {
    float transform[3][4];
    uint32_t customIndexAndMask;  // bits 0-23 instanceCustomIndex, 24-31 mask
    uint32_t sbtOffsetAndFlags;   // bits 0-23 instanceShaderBindingTableRecordOffset, 24-31 flags
    uint64_t reference;           // accelerationStructureReference: a VkAccelerationStructureKHR handle, 0 = inactive
};
static_assert(sizeof(RawInstance) == sizeof(VkAccelerationStructureInstanceKHR));

class InstanceSource {
public:
    InstanceSource(const VkAccelerationStructureGeometryInstancesDataKHR& data,
                   const VkAccelerationStructureBuildRangeInfoKHR& range);
    uint32_t count() const { return count_; }
    RawInstance fetch(uint32_t i) const;

private:
    const std::byte* data_;
    bool arrayOfPointers_;
    uint32_t count_;
};

}  // namespace vkas
