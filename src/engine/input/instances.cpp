#include "engine/input/instances.hpp"

#include <cstring>

#include "engine/util/byte_io.hpp"
#include "engine/util/math.hpp"

namespace vkas {

InstanceSource::InstanceSource(const VkAccelerationStructureGeometryInstancesDataKHR& data,
                               const VkAccelerationStructureBuildRangeInfoKHR& range)
    : data_(offsetAddress(data.data.hostAddress, range.primitiveOffset)),
      arrayOfPointers_(data.arrayOfPointers == VK_TRUE),
      count_(range.primitiveCount) {}

RawInstance InstanceSource::fetch(uint32_t i) const {
    const std::byte* p = data_ + uint64_t(i) * sizeof(VkAccelerationStructureInstanceKHR);
    if (arrayOfPointers_) p = loadUnaligned<const std::byte*>(data_ + uint64_t(i) * sizeof(void*));
    return loadUnaligned<RawInstance>(p);
}

}  // namespace vkas
