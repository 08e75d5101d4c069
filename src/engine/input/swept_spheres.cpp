#include "engine/input/swept_spheres.hpp"

#include "engine/util/byte_io.hpp"

#include <cmath>
#include <cstring>

#include "engine/input/vertex_format.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas {

using namespace format;

namespace {

template <class T>
T load(const std::byte* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// The members the two data structures share, in the same order.
template <typename Data>
void copyCommon(const Data& s, SweptSpheresData& out) {
    out.vertexFormat = s.vertexFormat;
    out.vertexData = static_cast<const std::byte*>(s.vertexData.hostAddress);
    out.vertexStride = s.vertexStride;
    out.radiusFormat = s.radiusFormat;
    out.radiusData = static_cast<const std::byte*>(s.radiusData.hostAddress);
    out.radiusStride = s.radiusStride;
    out.indexType = s.indexType;
    out.indexData = static_cast<const std::byte*>(s.indexData.hostAddress);
    out.indexStride = s.indexStride;
}

}  // namespace

bool sweptSpheresData(const VkAccelerationStructureGeometryKHR& geometry, SweptSpheresData& out) {
    if (geometry.geometryType == VK_GEOMETRY_TYPE_SPHERES_NV) {
        auto* s = static_cast<const VkAccelerationStructureGeometrySpheresDataNV*>(
            findInChain(geometry.pNext, VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV));
        if (!s) return false;
        out = SweptSpheresData{};
        out.lss = false;
        copyCommon(*s, out);
        return true;
    }
    if (geometry.geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV) {
        auto* s = static_cast<const VkAccelerationStructureGeometryLinearSweptSpheresDataNV*>(findInChain(
            geometry.pNext, VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV));
        if (!s) return false;
        out = SweptSpheresData{};
        out.lss = true;
        copyCommon(*s, out);
        out.indexingMode = s->indexingMode;
        out.endCapsMode = s->endCapsMode;
        return true;
    }
    return false;
}

bool isRadiusFormat(VkFormat format) { return format == VK_FORMAT_R32_SFLOAT || format == VK_FORMAT_R16_SFLOAT; }

SweptSpheresSource::SweptSpheresSource(const SweptSpheresData& data,
                                       const VkAccelerationStructureBuildRangeInfoKHR& range)
    : data_(data), firstVertex_(range.firstVertex), count_(range.primitiveCount) {
    const bool indexed = data.indexType == VK_INDEX_TYPE_UINT16 || data.indexType == VK_INDEX_TYPE_UINT32;
    if (indexed) {
        // primitiveOffset moves the indices only.
        vertices_ = data.vertexData;
        radii_ = data.radiusData;
        indices_ = offsetAddress(data.indexData, range.primitiveOffset);
    } else {
        // primitiveOffset moves both the position and the radius buffer.
        vertices_ = offsetAddress(data.vertexData, range.primitiveOffset);
        radii_ = offsetAddress(data.radiusData, range.primitiveOffset);
        indices_ = nullptr;
    }
}

uint64_t SweptSpheresSource::indexValue(uint64_t n) const {
    const std::byte* p = indices_ + data_.indexStride * n;
    return data_.indexType == VK_INDEX_TYPE_UINT16 ? load<uint16_t>(p) : load<uint32_t>(p);
}

uint64_t SweptSpheresSource::vertexNumber(uint32_t i, uint32_t j) const {
    if (!data_.lss) return indices_ ? indexValue(i) : i;
    if (data_.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV)
        return (indices_ ? indexValue(i) : i) + j;
    const uint64_t n = 2ull * i + j;  // LIST: pairs of indices, or pairs of vertices like a line list
    return indices_ ? indexValue(n) : n;
}

bool SweptSpheresSource::fetchVertex(uint64_t vertex, float position[3], float& radius) const {
    const uint64_t v = vertex + firstVertex_;
    double p[3];
    decodeVertex(data_.vertexFormat, vertices_ + data_.vertexStride * v, p);
    const std::byte* r = radii_ + data_.radiusStride * v;
    radius = data_.radiusFormat == VK_FORMAT_R16_SFLOAT ? halfToFloat(load<uint16_t>(r)) : load<float>(r);
    bool active = !std::isnan(radius);
    for (int k = 0; k < 3; ++k) {
        if (std::isnan(p[k])) active = false;
        position[k] = float(p[k]);
    }
    return active;
}

uint32_t SweptSpheresSource::endCaps(uint32_t i) const {
    if (data_.endCapsMode != VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV) return 0;  // NONE: no caps
    // CHAINED: with SUCCESSIVE indexing, a primitive whose index follows the previous primitive's index by one
    // continues that chain and keeps only its trailing cap; the first primitive of a chain has both. Every other
    // primitive (LIST indexing, or no indices) is a chain of its own.
    if (data_.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV && i > 0 &&
        vertexNumber(i, 0) == vertexNumber(i - 1, 0) + 1)
        return kLssCap1;
    return kLssCap0 | kLssCap1;
}

}  // namespace vkas
