#include "engine/sphere_fetch.hpp"

#include "engine/byte_io.hpp"

#include <cmath>
#include <cstring>

#include "engine/vertex_format.hpp"

namespace vkas {

using namespace format;

namespace {

template <class T>
T load(const std::byte* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}



void setRef(PrimRef& ref, uint32_t index, const double lo[3], const double hi[3]) {
    for (int k = 0; k < 3; ++k) ref.lower[k] = roundDown(lo[k]), ref.upper[k] = roundUp(hi[k]);
    ref.index = index;
    ref.pad = 0;
}

uint32_t recordFlags(VkGeometryFlagsKHR flags) {
    uint32_t f = 0;
    if (flags & VK_GEOMETRY_OPAQUE_BIT_KHR) f |= kSweptOpaque;
    if (flags & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR) f |= kSweptNoDuplicateAnyHit;
    return f;
}

}  // namespace

void extendBall(double lo[3], double hi[3], const float c[3], float r) {
    for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], double(c[k]) - double(r));
        hi[k] = std::max(hi[k], double(c[k]) + double(r));
    }
}

const void* findInChain(const void* pNext, VkStructureType sType) {
    for (auto* s = static_cast<const VkBaseInStructure*>(pNext); s; s = s->pNext)
        if (s->sType == sType) return s;
    return nullptr;
}

namespace {

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

uint32_t gatherSpheres(const BuildJob& job, PrimRef* refs, SphereRecord* temp) {
    const auto& info = *job.info;
    const bool keepDegenerate = (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) != 0;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        SweptSpheresData data;
        if (geom.geometryType != VK_GEOMETRY_TYPE_SPHERES_NV || !sweptSpheresData(geom, data)) continue;
        SweptSpheresSource source(data, job.ranges[g]);
        const uint32_t flags = recordFlags(geom.flags);
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            SphereRecord rec;
            std::memset(&rec, 0, sizeof rec);
            if (!source.fetchVertex(source.vertexNumber(i, 0), rec.center, rec.radius)) continue;  // inactive
            if (!(rec.radius >= 0.0f)) continue;  // negative radius: invalid input, never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags;
            if (rec.radius == 0.0f) {  // degenerate: never hit; kept for an update that gives it a radius
                if (!keepDegenerate) continue;
                rec.flags |= kSweptDegenerate;
            }
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            extendBall(lo, hi, rec.center, rec.radius);
            temp[n] = rec;
            setRef(refs[n], n, lo, hi);
            ++n;
        }
    }
    return n;
}

uint32_t gatherLss(const BuildJob& job, PrimRef* refs, LssRecord* temp) {
    const auto& info = *job.info;
    const bool keepDegenerate = (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) != 0;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        SweptSpheresData data;
        if (geom.geometryType != VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV || !sweptSpheresData(geom, data)) continue;
        SweptSpheresSource source(data, job.ranges[g]);
        const uint32_t flags = recordFlags(geom.flags);
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            LssRecord rec;
            std::memset(&rec, 0, sizeof rec);
            const bool a = source.fetchVertex(source.vertexNumber(i, 0), rec.p0, rec.r0);
            const bool b = source.fetchVertex(source.vertexNumber(i, 1), rec.p1, rec.r1);
            if (!a || !b) continue;                                  // inactive
            if (!(rec.r0 >= 0.0f && rec.r1 >= 0.0f)) continue;       // invalid input: never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags | source.endCaps(i);
            if (rec.r0 == 0.0f && rec.r1 == 0.0f) {  // degenerate: never hit; kept for an update
                if (!keepDegenerate) continue;
                rec.flags |= kSweptDegenerate;
            }
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            extendBall(lo, hi, rec.p0, rec.r0);
            extendBall(lo, hi, rec.p1, rec.r1);
            temp[n] = rec;
            setRef(refs[n], n, lo, hi);
            ++n;
        }
    }
    return n;
}

}  // namespace vkas
