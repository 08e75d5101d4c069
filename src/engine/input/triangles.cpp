#include "engine/input/triangles.hpp"

#include "engine/util/byte_io.hpp"

#include <cmath>

#include "engine/input/vertex_format.hpp"

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

}  // namespace vkas
