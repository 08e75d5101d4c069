#include "api/validate/swept_spheres.hpp"

#include <cmath>

#include "engine/input/swept_spheres.hpp"
#include "engine/input/vertex_format.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

// VUID names of the two structures, which carry the same rules under different numbers.
struct Vuids {
    const char* structName;
    const char* vertexStride;     // multiple of the component (packed: format) size
    const char* strides;          // vertexStride and radiusStride <= 2^32-1
    const char* vertexFormat;     // AS vertex buffer format feature
    const char* radiusFormat;     // radius buffer format feature
    const char* radii;            // radii >= 0
    const char* indexType;        // indexData not NULL: UINT16 or UINT32
    const char* indexNoneData;    // host: indexType NONE -> indexData.hostAddress 0
    const char* indexData;        // host: indexType not NONE -> indexData.hostAddress != 0
    const char* vertexData;       // host: vertexData.hostAddress != 0
    const char* radiusData;       // host: radiusData.hostAddress != 0
};

const Vuids kSphereVuids = {
    "VkAccelerationStructureGeometrySpheresDataNV",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexStride-10431",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexStride-10432",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexFormat-10434",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-radiusFormat-10435",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-radiusData-10436",
    "VUID-VkAccelerationStructureGeometrySpheresDataNV-indexData-10437",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11822",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11823",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11824",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11825",
};
const Vuids kLssVuids = {
    "VkAccelerationStructureGeometryLinearSweptSpheresDataNV",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexStride-10421",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexStride-10422",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexFormat-10423",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-radiusFormat-10424",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-radiusData-10426",
    "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexData-10428",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11826",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11827",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11828",
    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11829",
};

bool validIndexType(VkIndexType t) {
    return t == VK_INDEX_TYPE_NONE_KHR || t == VK_INDEX_TYPE_UINT16 || t == VK_INDEX_TYPE_UINT32;
}

}  // namespace

void checkSweptSpheresGeometry(Validator& v, const VkAccelerationStructureGeometryKHR& geometry, const char* where,
                               uint32_t g) {
    const bool lss = geometry.geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
    const Vuids& id = lss ? kLssVuids : kSphereVuids;
    SweptSpheresData d;
    if (!sweptSpheresData(geometry, d)) {
        // The geometry union is unused for these types: without the structure there is no geometry data.
        v.fail("VUID-VkAccelerationStructureGeometryKHR-pNext-pNext",
               "%s geometry %u: geometryType is %s but pNext has no %s.", where, g,
               lss ? "LINEAR_SWEPT_SPHERES_NV" : "SPHERES_NV", id.structName);
        return;
    }
    const VertexFormatInfo* fmt = vertexFormatInfo(d.vertexFormat);
    v.check(fmt != nullptr, id.vertexFormat,
            "%s geometry %u: vertexFormat %d lacks VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR.",
            where, g, int(d.vertexFormat));
    if (fmt) {
        const uint32_t unit = fmt->packed ? fmt->size : fmt->componentSize;
        v.check(d.vertexStride % unit == 0, id.vertexStride,
                "%s geometry %u: vertexStride %llu is not a multiple of %u.", where, g, (ull)d.vertexStride, unit);
    }
    v.check(d.vertexStride <= UINT32_MAX && d.radiusStride <= UINT32_MAX, id.strides,
            "%s geometry %u: vertexStride %llu or radiusStride %llu exceeds 2^32-1.", where, g, (ull)d.vertexStride,
            (ull)d.radiusStride);
    v.check(isRadiusFormat(d.radiusFormat), id.radiusFormat,
            "%s geometry %u: radiusFormat %d lacks VK_FORMAT_FEATURE_2_ACCELERATION_STRUCTURE_RADIUS_BUFFER_BIT_NV "
            "(R32_SFLOAT and R16_SFLOAT have it).",
            where, g, int(d.radiusFormat));
    v.check(validIndexType(d.indexType), id.indexType,
            "%s geometry %u: indexType %d is not VK_INDEX_TYPE_UINT16, UINT32 or NONE_KHR.", where, g,
            int(d.indexType));
    if (lss) {
        v.check(d.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV ||
                    d.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV,
                "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexingMode-parameter",
                "%s geometry %u: indexingMode %u is not a VkRayTracingLssIndexingModeNV.", where, g, d.indexingMode);
        v.check(d.endCapsMode == VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV ||
                    d.endCapsMode == VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV,
                "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-endCapsMode-parameter",
                "%s geometry %u: endCapsMode %u is not a VkRayTracingLssPrimitiveEndCapsModeNV.", where, g,
                d.endCapsMode);
    }
}

void checkSweptSpheresRange(Validator& v, const VkAccelerationStructureGeometryKHR& geometry,
                            const VkAccelerationStructureBuildRangeInfoKHR& range, const char* where, uint32_t g) {
    const bool lss = geometry.geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
    const Vuids& id = lss ? kLssVuids : kSphereVuids;
    SweptSpheresData d;
    if (!sweptSpheresData(geometry, d)) return;  // reported by checkSweptSpheresGeometry
    const bool indexed = d.indexType != VK_INDEX_TYPE_NONE_KHR;
    if (indexed)
        v.check(d.indexData != nullptr, id.indexData,
                "%s geometry %u: indexType is %d but indexData.hostAddress is NULL.", where, g, int(d.indexType));
    else
        v.check(d.indexData == nullptr, id.indexNoneData,
                "%s geometry %u: indexType is VK_INDEX_TYPE_NONE_KHR but indexData.hostAddress is %p.", where, g,
                static_cast<const void*>(d.indexData));
    v.check(d.vertexData != nullptr, id.vertexData, "%s geometry %u: vertexData.hostAddress is NULL.", where, g);
    v.check(d.radiusData != nullptr, id.radiusData, "%s geometry %u: radiusData.hostAddress is NULL.", where, g);
    if (lss && d.indexingMode == VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV)
        v.check(d.indexData != nullptr, "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexingMode-10427",
                "%s geometry %u: indexingMode is SUCCESSIVE but indexData is NULL.", where, g);
    // Read the radii only through a geometry that passed every other rule (this one and the structure's).
    if (v.failureCount() != 0 || range.primitiveCount == 0) return;
    if (!vertexFormatInfo(d.vertexFormat) || !isRadiusFormat(d.radiusFormat) || !validIndexType(d.indexType)) return;
    SweptSpheresSource source(d, range);
    const uint32_t ends = lss ? 2 : 1;
    for (uint32_t i = 0; i < range.primitiveCount; ++i) {
        for (uint32_t j = 0; j < ends; ++j) {
            const uint64_t vertex = source.vertexNumber(i, j);
            float p[3], r;
            source.fetchVertex(vertex, p, r);
            if (!(r < 0.0f)) continue;  // NaN (inactive) and zero are fine
            v.fail(id.radii, "%s geometry %u: primitive %u reads radius %g (vertex %llu + firstVertex %u), below 0.",
                   where, g, i, double(r), (ull)vertex, range.firstVertex);
            return;  // one message per geometry
        }
    }
}

}  // namespace vkas
