#include "engine/geometry_fetch.hpp"

#include <cmath>

#include "engine/vertex_format.hpp"

namespace vkas {

TriangleSource::TriangleSource(const VkAccelerationStructureGeometryTrianglesDataKHR& data,
                               const VkAccelerationStructureBuildRangeInfoKHR& range)
    : format_(data.vertexFormat),
      stride_(data.vertexStride),
      indexType_(data.indexType),
      hasTransform_(data.transformData.hostAddress != nullptr),
      count_(range.primitiveCount) {
    auto* vertexBase = static_cast<const std::byte*>(data.vertexData.hostAddress);
    if (indexType_ == VK_INDEX_TYPE_NONE_KHR) {
        // Non-indexed: primitiveOffset and firstVertex both move the first vertex.
        vertices_ = vertexBase + range.primitiveOffset + stride_ * range.firstVertex;
        indices_ = nullptr;
    } else {
        // Indexed: primitiveOffset moves the indices only; firstVertex is added to every index.
        vertices_ = vertexBase + stride_ * range.firstVertex;
        indices_ = static_cast<const std::byte*>(data.indexData.hostAddress) + range.primitiveOffset;
    }
    if (hasTransform_) {
        float m[3][4];
        std::memcpy(m, static_cast<const std::byte*>(data.transformData.hostAddress) + range.transformOffset,
                    sizeof m);
        transform_ = affineFromFloat(m);
    }
}

uint64_t TriangleSource::vertexIndex(uint32_t i, uint32_t j) const {
    uint64_t k = 3ull * i + j;
    switch (indexType_) {
        case VK_INDEX_TYPE_UINT16: return loadUnaligned<uint16_t>(indices_ + 2 * k);
        case VK_INDEX_TYPE_UINT32: return loadUnaligned<uint32_t>(indices_ + 4 * k);
        default: return k;
    }
}

bool TriangleSource::fetch(uint32_t i, float v[3][3]) const {
    bool active = true;
    for (uint32_t j = 0; j < 3; ++j) {
        double p[3];
        decodeVertex(format_, vertices_ + stride_ * vertexIndex(i, j), p);
        if (std::isnan(p[0])) active = false;  // inactive: any NaN in a vertex's raw X
        if (hasTransform_) {
            double q[3];
            applyAffine(transform_, p, q);
            for (int c = 0; c < 3; ++c) v[j][c] = float(q[c]);
        } else {
            for (int c = 0; c < 3; ++c) v[j][c] = float(p[c]);
        }
    }
    return active;
}

bool isDegenerateTriangle(const float v[3][3]) {
    // Differences of floats are exact in double (barring extreme exponent ranges), so a zero cross product
    // means the three points are collinear.
    double e1[3], e2[3];
    for (int c = 0; c < 3; ++c) {
        e1[c] = double(v[1][c]) - double(v[0][c]);
        e2[c] = double(v[2][c]) - double(v[0][c]);
    }
    double n0 = e1[1] * e2[2] - e1[2] * e2[1];
    double n1 = e1[2] * e2[0] - e1[0] * e2[2];
    double n2 = e1[0] * e2[1] - e1[1] * e2[0];
    return n0 == 0.0 && n1 == 0.0 && n2 == 0.0;
}

AabbSource::AabbSource(const VkAccelerationStructureGeometryAabbsDataKHR& data,
                       const VkAccelerationStructureBuildRangeInfoKHR& range)
    : data_(static_cast<const std::byte*>(data.data.hostAddress) + range.primitiveOffset),
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
    : data_(static_cast<const std::byte*>(data.data.hostAddress) + range.primitiveOffset),
      arrayOfPointers_(data.arrayOfPointers == VK_TRUE),
      count_(range.primitiveCount) {}

RawInstance InstanceSource::fetch(uint32_t i) const {
    const std::byte* p = data_ + uint64_t(i) * sizeof(VkAccelerationStructureInstanceKHR);
    if (arrayOfPointers_) p = loadUnaligned<const std::byte*>(data_ + uint64_t(i) * sizeof(void*));
    return loadUnaligned<RawInstance>(p);
}

}  // namespace vkas
