// Build inputs of an ordinary top level: the VkAccelerationStructureInstanceKHR array or array of pointers.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

namespace vkas {

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
