#include "engine/input/aabbs.hpp"

#include <cmath>

#include "engine/util/byte_io.hpp"
#include "engine/util/math.hpp"

namespace vkas {

AabbSource::AabbSource(const VkAccelerationStructureGeometryAabbsDataKHR& data,
                       const VkAccelerationStructureBuildRangeInfoKHR& range)
    : data_(offsetAddress(data.data.hostAddress, range.primitiveOffset)),
      stride_(data.stride),
      count_(range.primitiveCount) {}

bool AabbSource::fetch(uint32_t i, float lower[3], float upper[3]) const {
    const auto box = loadUnaligned<VkAabbPositionsKHR>(data_ + stride_ * i);
    lower[0] = box.minX, lower[1] = box.minY, lower[2] = box.minZ;
    upper[0] = box.maxX, upper[1] = box.maxY, upper[2] = box.maxZ;
    return !std::isnan(box.minX);
}

bool isInvertedAabb(const float lower[3], const float upper[3]) {
    return !(lower[0] <= upper[0] && lower[1] <= upper[1] && lower[2] <= upper[2]);
}

}  // namespace vkas
