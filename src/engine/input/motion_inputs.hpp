// [NV-motion] Build inputs of VK_NV_ray_tracing_motion_blur: the motion instance array (160-byte stride, or
// pointers whose low 4 bits hold the instance type) and the time-1 vertices of motion triangles.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/motion.hpp"

namespace vkas::motion {

// Array stride of VkAccelerationStructureMotionInstanceNV (the struct is 152 bytes; arrays use 160).
constexpr uint64_t kMotionInstanceStride = 160;
static_assert(sizeof(VkAccelerationStructureMotionInstanceNV) == 152);

// One VkAccelerationStructureMotionInstanceNV as read from the build input.
struct RawMotionInstance {
    uint32_t type;                // VkAccelerationStructureMotionInstanceTypeNV (anything else: invalid input)
    uint32_t flags;               // array mode: the struct's flags (must be 0); pointer mode: 0
    float staticTransform[3][4];  // kStatic
    float motion[32];             // kMatrix / kSrt, laid out as in format::MotionInstanceRecord
    uint32_t customIndexAndMask;
    uint32_t sbtOffsetAndFlags;
    uint64_t reference;  // 0 = inactive (and for an invalid type)
};

// Motion instance i: the 152-byte struct at data + primitiveOffset + 160 i, or with arrayOfPointers the 8-byte
// pointer at data + primitiveOffset + 8 i whose low 4 bits hold the type and whose other bits address the
// VkAccelerationStructureInstanceKHR, ...MatrixMotionInstanceNV or ...SRTMotionInstanceNV.
class MotionInstanceSource {
public:
    MotionInstanceSource(const VkAccelerationStructureGeometryInstancesDataKHR& data,
                         const VkAccelerationStructureBuildRangeInfoKHR& range);
    uint32_t count() const { return count_; }
    // The pointer (pointer mode) or struct address of instance i, before the type bits are cleared.
    uintptr_t rawAddress(uint32_t i) const;
    // Reads instance i. Returns false when pointer mode gives a NULL address.
    bool fetch(uint32_t i, RawMotionInstance& out) const;

private:
    const std::byte* data_;
    bool arrayOfPointers_;
    uint32_t count_;
};

// The VkAccelerationStructureGeometryMotionTrianglesDataNV in the triangles' pNext chain, or nullptr.
const VkAccelerationStructureGeometryMotionTrianglesDataNV* findMotionTriangles(
    const VkAccelerationStructureGeometryTrianglesDataKHR& triangles);

}  // namespace vkas::motion
