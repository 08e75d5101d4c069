// What vkas reports as VkPhysicalDeviceAccelerationStructurePropertiesKHR, and checks builds against.
#pragma once

#include <cstdint>

namespace vkas::limits {
constexpr uint64_t kMaxGeometryCount = (1ull << 24) - 1;
constexpr uint64_t kMaxInstanceCount = (1ull << 24) - 1;
constexpr uint64_t kMaxPrimitiveCount = (1ull << 29) - 1;
constexpr uint32_t kMaxPerStageDescriptorAccelerationStructures = 1u << 20;
constexpr uint32_t kMaxDescriptorSetAccelerationStructures = 1u << 20;
constexpr uint32_t kMinScratchOffsetAlignment = 1;  // host scratch needs no alignment
constexpr uint64_t kAccelerationStructureOffsetAlignment = 256;
}  // namespace vkas::limits
