#include "engine/geometry_fetch.hpp"

#include "engine/byte_io.hpp"

#include <cmath>

#include "engine/vertex_format.hpp"

namespace vkas {

TriangleSource::TriangleSource(const VkAccelerationStructureGeometryTrianglesDataKHR& data,
                               const VkAccelerationStructureBuildRangeInfoKHR& range)
    : format_(data.vertexFormat),
      stride_(data.vertexStride),
      indexType_(data.indexType),
      hasTransform_(data.transformData.hostAddress != nullptr),
      indexKind_(indexType_ == VK_INDEX_TYPE_UINT16   ? TriangleIndexKind::U16
                 : indexType_ == VK_INDEX_TYPE_UINT32 ? TriangleIndexKind::U32
                                                      : TriangleIndexKind::None),
      vertexKind_(format_ == VK_FORMAT_R32G32B32_SFLOAT || format_ == VK_FORMAT_R32G32B32A32_SFLOAT
                      ? TriangleVertexKind::Float3
                  : format_ == VK_FORMAT_R32G32_SFLOAT ? TriangleVertexKind::Float2
                                                       : TriangleVertexKind::Other),
      count_(range.primitiveCount) {
    const void* vertexBase = data.vertexData.hostAddress;
    if (indexType_ == VK_INDEX_TYPE_NONE_KHR) {
        // Non-indexed: primitiveOffset and firstVertex both move the first vertex.
        vertices_ = offsetAddress(vertexBase, range.primitiveOffset + stride_ * uint64_t(range.firstVertex));
        indices_ = nullptr;
    } else {
        // Indexed: primitiveOffset moves the indices only; firstVertex is added to every index.
        vertices_ = offsetAddress(vertexBase, stride_ * uint64_t(range.firstVertex));
        indices_ = offsetAddress(data.indexData.hostAddress, range.primitiveOffset);
    }
    if (hasTransform_) {
        float m[3][4];
        std::memcpy(m, static_cast<const std::byte*>(data.transformData.hostAddress) + range.transformOffset,
                    sizeof m);
        transform_ = affineFromFloat(m);
    }
}

uint64_t TriangleSource::vertexIndex(uint32_t i, uint32_t j) const {
    switch (indexKind_) {
        case TriangleIndexKind::U16: return vertexIndexAs<TriangleIndexKind::U16>(i, j);
        case TriangleIndexKind::U32: return vertexIndexAs<TriangleIndexKind::U32>(i, j);
        default: return vertexIndexAs<TriangleIndexKind::None>(i, j);
    }
}

bool TriangleSource::fetch(uint32_t i, float v[3][3]) const {
    return visit([&](auto reader) { return reader.fetch(i, v); });
}

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
