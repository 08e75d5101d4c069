#include "api/validate/geometry_info.hpp"

#include <cstdint>
#include <cstdio>

#include "api/build_geometry_info.hpp"
#include "api/limits.hpp"
#include "api/validate/opacity_micromaps.hpp"
#include "api/validate/parameters.hpp"
#include "api/validate/swept_spheres.hpp"
#include "engine/format/motion.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/motion_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"
#include "engine/input/vertex_format.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

constexpr VkBuildAccelerationStructureFlagsKHR kKnownBuildFlags =
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR |
    VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR |
    VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV |
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR |
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT |
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DISABLE_OPACITY_MICROMAPS_EXT |
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT;
constexpr VkIndexType kIndexTypeUint8 = VkIndexType(1000265000);  // VK_INDEX_TYPE_UINT8 (Vulkan 1.4)

// A VkFormat value of Vulkan 1.3 core (formats of extensions vkas does not enable are not valid values).
bool isFormatValue(VkFormat f) {
    const int64_t v = f;
    return (v >= 0 && v <= VK_FORMAT_ASTC_12x12_SRGB_BLOCK) ||
           (v >= VK_FORMAT_G8B8G8R8_422_UNORM && v <= VK_FORMAT_G16_B16_R16_3PLANE_444_UNORM) ||
           (v >= VK_FORMAT_G8_B8R8_2PLANE_444_UNORM && v <= VK_FORMAT_G16_B16R16_2PLANE_444_UNORM) ||
           (v >= VK_FORMAT_A4R4G4B4_UNORM_PACK16 && v <= VK_FORMAT_A4B4G4R4_UNORM_PACK16) ||
           (v >= VK_FORMAT_ASTC_4x4_SFLOAT_BLOCK && v <= VK_FORMAT_ASTC_12x12_SFLOAT_BLOCK);
}

}  // namespace

void checkGeometryInfo(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info, const char* where) {
    v.check(info.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR,
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-sType-sType", "%s.sType is %d.", where, int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-pNext-pNext",
            "%s.pNext is not NULL.", where);
    v.check((info.flags & ~kKnownBuildFlags) == 0, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-parameter",
            "%s.flags 0x%x has bits that are not VkBuildAccelerationStructureFlagBitsKHR of an enabled extension.",
            where, info.flags);
    // [EXT-OMM] "If flags has the VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_BIT_KHR bit set then
    // it must not have the VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT bit set"
    v.check(!((info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT) &&
              (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT)),
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-11558",
            "%s.flags has both ALLOW_OPACITY_MICROMAP_UPDATE and ALLOW_OPACITY_MICROMAP_DATA_UPDATE.", where);
    v.check(info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ||
                info.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR ||
                info.type == VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR,
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-parameter", "%s.type %d is not a valid value.",
            where, int(info.type));
    v.check(info.type != VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR,
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03654", "%s.type is GENERIC.", where);
    v.check(!((info.flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) &&
              (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)),
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-03796",
            "%s.flags has both PREFER_FAST_TRACE and PREFER_FAST_BUILD.", where);
    v.check(!(motion::isMotionBuild(info.flags) && info.type == VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR),
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04929",
            "%s.flags has VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV but type is GENERIC.", where);
    if (info.geometryCount != 0) {
        v.check((info.pGeometries == nullptr) != (info.ppGeometries == nullptr),
                "VUID-VkAccelerationStructureBuildGeometryInfoKHR-pGeometries-03788",
                "%s: exactly one of pGeometries and ppGeometries must be non-NULL (geometryCount %u).", where,
                info.geometryCount);
    }
    if (info.pGeometries == nullptr && info.ppGeometries == nullptr) return;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) {
        v.check(info.geometryCount == 1, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03790",
                "%s is a top-level build with geometryCount %u.", where, info.geometryCount);
    } else if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR) {
        v.check(info.geometryCount <= limits::kMaxGeometryCount,
                "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03793",
                "%s.geometryCount %u exceeds maxGeometryCount.", where, info.geometryCount);
    }
    // Never walk more geometries than a valid build can have: the arrays may be that short.
    if (info.geometryCount > limits::kMaxGeometryCount) return;
    VkGeometryTypeKHR firstType = VK_GEOMETRY_TYPE_MAX_ENUM_KHR;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const VkAccelerationStructureGeometryKHR* geom = geometryAt(info, g);
        if (!v.check(geom != nullptr, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-ppGeometries-parameter",
                     "%s.ppGeometries[%u] is NULL.", where, g))
            continue;
        v.check(geom->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR,
                "VUID-VkAccelerationStructureGeometryKHR-sType-sType", "%s geometry %u: sType is %d.", where, g,
                int(geom->sType));
        if (geom->geometryType != VK_GEOMETRY_TYPE_SPHERES_NV &&
            geom->geometryType != VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV) {
            char name[72];
            std::snprintf(name, sizeof name, "%s geometry %u", where, g);
            checkNextChain(v, geom->pNext,
                           {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV,
                            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV},
                           "VUID-VkAccelerationStructureGeometryKHR-pNext-pNext",
                           "VUID-VkAccelerationStructureGeometryKHR-sType-unique", name);
        }
        v.check(geom->geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR || geom->geometryType == VK_GEOMETRY_TYPE_AABBS_KHR ||
                    geom->geometryType == VK_GEOMETRY_TYPE_INSTANCES_KHR ||
                    geom->geometryType == VK_GEOMETRY_TYPE_SPHERES_NV ||
                    geom->geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV,
                "VUID-VkAccelerationStructureGeometryKHR-geometryType-parameter",
                "%s geometry %u: geometryType %d is not supported by vkas yet.", where, g, int(geom->geometryType));
        v.check((geom->flags & ~uint32_t(VK_GEOMETRY_OPAQUE_BIT_KHR | VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR)) == 0,
                "VUID-VkAccelerationStructureGeometryKHR-flags-parameter", "%s geometry %u: flags 0x%x has unknown bits.",
                where, g, geom->flags);
        if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) {
            v.check(geom->geometryType == VK_GEOMETRY_TYPE_INSTANCES_KHR,
                    "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03789",
                    "%s is a top-level build but geometry %u has geometryType %d.", where, g, int(geom->geometryType));
        } else if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR) {
            v.check(geom->geometryType != VK_GEOMETRY_TYPE_INSTANCES_KHR,
                    "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03791",
                    "%s is a bottom-level build but geometry %u is INSTANCES.", where, g);
            if (g == 0) firstType = geom->geometryType;
            v.check(geom->geometryType == firstType, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03792",
                    "%s: geometry %u has geometryType %d but geometry 0 has %d.", where, g, int(geom->geometryType),
                    int(firstType));
        }
        if (geom->geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR) {
            const auto& t = geom->geometry.triangles;
            v.check(t.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR,
                    "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-sType-sType",
                    "%s geometry %u: triangles.sType is %d.", where, g, int(t.sType));
            {
                char name[72];
                std::snprintf(name, sizeof name, "%s geometry %u: triangles", where, g);
                checkNextChain(v, t.pNext,
                               {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV,
                                VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT},
                               "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-pNext-pNext",
                               "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-sType-unique", name);
            }
            if (const auto* omm = opacityMicromapOf(t)) checkOpacityMicromapStructure(v, *omm, where, g);
            const VertexFormatInfo* fmt = vertexFormatInfo(t.vertexFormat);
            if (v.check(isFormatValue(t.vertexFormat),
                        "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexFormat-parameter",
                        "%s geometry %u: vertexFormat %d is not a VkFormat value.", where, g, int(t.vertexFormat)))
                v.check(fmt != nullptr, "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexFormat-03797",
                        "%s geometry %u: vertexFormat %d lacks "
                        "VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR.",
                        where, g, int(t.vertexFormat));
            if (fmt)
                v.check(t.vertexStride % fmt->componentSize == 0,
                        "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexStride-03735",
                        "%s geometry %u: vertexStride %llu is not a multiple of the component size %u.", where, g,
                        (ull)t.vertexStride, fmt->componentSize);
            v.check(t.vertexStride <= UINT32_MAX, "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexStride-03819",
                    "%s geometry %u: vertexStride %llu exceeds 2^32-1.", where, g, (ull)t.vertexStride);
            // VK_INDEX_TYPE_UINT8 (core in Vulkan 1.4) is a VkIndexType value, but not one a build accepts.
            if (v.check(t.indexType == VK_INDEX_TYPE_UINT16 || t.indexType == VK_INDEX_TYPE_UINT32 ||
                            t.indexType == VK_INDEX_TYPE_NONE_KHR || t.indexType == kIndexTypeUint8,
                        "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-indexType-parameter",
                        "%s geometry %u: indexType %d is not a VkIndexType value.", where, g, int(t.indexType)))
                v.check(t.indexType != kIndexTypeUint8,
                        "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-indexType-03798",
                        "%s geometry %u: indexType is VK_INDEX_TYPE_UINT8, not UINT16, UINT32 or NONE_KHR.", where, g);
        }
        if (geom->geometryType == VK_GEOMETRY_TYPE_AABBS_KHR) {
            const auto& a = geom->geometry.aabbs;
            v.check(a.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR,
                    "VUID-VkAccelerationStructureGeometryAabbsDataKHR-sType-sType",
                    "%s geometry %u: aabbs.sType is %d.", where, g, int(a.sType));
            v.check(a.pNext == nullptr, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-pNext-pNext",
                    "%s geometry %u: aabbs.pNext is not NULL.", where, g);
            v.check(a.stride % 8 == 0, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03545",
                    "%s geometry %u: aabbs.stride %llu is not a multiple of 8.", where, g, (ull)a.stride);
            v.check(a.stride <= UINT32_MAX, "VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03820",
                    "%s geometry %u: aabbs.stride %llu exceeds 2^32-1.", where, g, (ull)a.stride);
        }
        if (geom->geometryType == VK_GEOMETRY_TYPE_SPHERES_NV ||
            geom->geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV)
            checkSweptSpheresGeometry(v, *geom, where, g);
        if (geom->geometryType == VK_GEOMETRY_TYPE_INSTANCES_KHR) {
            v.check(geom->geometry.instances.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR,
                    "VUID-VkAccelerationStructureGeometryInstancesDataKHR-sType-sType",
                    "%s geometry %u: instances.sType is %d.", where, g, int(geom->geometry.instances.sType));
            v.check(geom->geometry.instances.pNext == nullptr,
                    "VUID-VkAccelerationStructureGeometryInstancesDataKHR-pNext-pNext",
                    "%s geometry %u: instances.pNext is not NULL.", where, g);
        }
    }
}

bool checkPrimitiveTotal(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t total,
                         const char* where) {
    if (info.type != VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR || total <= limits::kMaxPrimitiveCount) return true;
    // "If type is VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR and the geometryType member of elements of either
    // pGeometries or ppGeometries is VK_GEOMETRY_TYPE_AABBS_KHR, the total number of AABBs in all geometries must be
    // less than or equal to VkPhysicalDeviceAccelerationStructurePropertiesKHR::maxPrimitiveCount" (03794; 03795
    // says the same of triangles).
    const VkAccelerationStructureGeometryKHR* first = info.geometryCount ? geometryAt(info, 0) : nullptr;
    const bool aabbs = first && first->geometryType == VK_GEOMETRY_TYPE_AABBS_KHR;
    return v.check(false,
                   aabbs ? "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03794"
                         : "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03795",
                   "%s: the geometries hold %llu %s, more than maxPrimitiveCount (%llu).", where, (ull)total,
                   aabbs ? "AABBs" : "primitives", (ull)limits::kMaxPrimitiveCount);
}

}  // namespace vkas
