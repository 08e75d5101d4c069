// vkCreate/DestroyAccelerationStructureKHR, the address and size queries, and vkBuildAccelerationStructuresKHR:
// valid-usage checks first (nothing is written when one fails), then the engine builds on plain memory.
#include <algorithm>
#include <cmath>
#include <cinttypes>
#include <memory>
#include <new>
#include <unordered_set>

#include "api/deferred_operation.hpp"
#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/guard.hpp"
#include "api/limits.hpp"
#include "api/sphere_validation.hpp"
#include "api/update_validation.hpp"
#include "api/validation.hpp"
#include "engine/build/size_query.hpp"
#include "engine/build/structure_build.hpp"
#include "engine/input/aabbs.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/instances.hpp"
#include "engine/input/motion_inputs.hpp"
#include "engine/format/sizes.hpp"
#include "engine/format/layout.hpp"
#include "engine/input/triangles.hpp"
#include "engine/format/motion.hpp"
#include "engine/build/refit.hpp"
#include "engine/input/vertex_format.hpp"

namespace vkas::entry {

namespace {

using ull = unsigned long long;

format::StructureType structureType(VkAccelerationStructureTypeKHR t) {
    return t == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ? format::StructureType::TopLevel
                                                             : format::StructureType::BottomLevel;
}

const VkAccelerationStructureGeometryKHR* geometryAt(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                     uint32_t i) {
    if (info.pGeometries) return &info.pGeometries[i];
    return info.ppGeometries ? info.ppGeometries[i] : nullptr;
}

constexpr VkBuildAccelerationStructureFlagsKHR kKnownBuildFlags =
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR |
    VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR |
    VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV |
    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
constexpr VkGeometryInstanceFlagsKHR kKnownInstanceFlags =
    VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR | VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR |
    VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR | VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR;
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

// The left 3x3 of a VkTransformMatrixKHR is invertible (VUID-VkTransformMatrixKHR-matrix-03799).
bool invertible3x3(const float m[3][4]) {
    const double det = double(m[0][0]) * (double(m[1][1]) * m[2][2] - double(m[1][2]) * m[2][1]) -
                       double(m[0][1]) * (double(m[1][0]) * m[2][2] - double(m[1][2]) * m[2][0]) +
                       double(m[0][2]) * (double(m[1][0]) * m[2][1] - double(m[1][1]) * m[2][0]);
    return det != 0.0 && std::isfinite(det);
}

// Rules on VkAccelerationStructureBuildGeometryInfoKHR that do not depend on range infos or handles; shared by
// the build and the size query. `where` names the info in messages, e.g. "pInfos[2]".
void checkGeometryInfo(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info, const char* where) {
    v.check(info.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR,
            "VUID-VkAccelerationStructureBuildGeometryInfoKHR-sType-sType", "%s.sType is %d.", where, int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-pNext-pNext",
            "%s.pNext is not NULL.", where);
    v.check((info.flags & ~kKnownBuildFlags) == 0, "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-parameter",
            "%s.flags 0x%x has bits that are not VkBuildAccelerationStructureFlagBitsKHR of an enabled extension.",
            where, info.flags);
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
            char name[48];
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
                char name[48];
                std::snprintf(name, sizeof name, "%s geometry %u: triangles", where, g);
                checkNextChain(v, t.pNext, {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV},
                               "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-pNext-pNext",
                               "VUID-VkAccelerationStructureGeometryTrianglesDataKHR-sType-unique", name);
            }
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

// Byte ranges [begin, end) in host memory, for the overlap rules.
struct Span {
    uintptr_t begin = 0, end = 0;
    bool overlaps(const Span& o) const { return begin < o.end && o.begin < end && begin != end && o.begin != o.end; }
};

Span blockSpan(const AccelerationStructure* as) {
    auto b = reinterpret_cast<uintptr_t>(as->block());
    return {b, b + as->size};
}

}  // namespace

VKAPI_ATTR void VKAPI_CALL GetAccelerationStructureBuildSizesKHR(
    VkDevice device, VkAccelerationStructureBuildTypeKHR buildType,
    const VkAccelerationStructureBuildGeometryInfoKHR* pBuildInfo, const uint32_t* pMaxPrimitiveCounts,
    VkAccelerationStructureBuildSizesInfoKHR* pSizeInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetAccelerationStructureBuildSizesKHR");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-device-parameter",
                "device is not a valid VkDevice.");
        v.check(buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR ||
                    buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR ||
                    buildType == VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_OR_DEVICE_KHR,
                "VUID-vkGetAccelerationStructureBuildSizesKHR-buildType-parameter", "buildType %d is not valid.",
                int(buildType));
        if (v.check(pBuildInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-parameter",
                    "pBuildInfo is NULL.")) {
            checkGeometryInfo(v, *pBuildInfo, "pBuildInfo");
            if (pBuildInfo->geometryCount != 0)
                v.check(pMaxPrimitiveCounts != nullptr,
                        "VUID-vkGetAccelerationStructureBuildSizesKHR-pMaxPrimitiveCounts-11612",
                        "pMaxPrimitiveCounts is NULL but pBuildInfo->geometryCount is %u.", pBuildInfo->geometryCount);
            if (pMaxPrimitiveCounts && pBuildInfo->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR &&
                pBuildInfo->geometryCount == 1)
                v.check(pMaxPrimitiveCounts[0] <= limits::kMaxInstanceCount,
                        "VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-03785",
                        "pMaxPrimitiveCounts[0] %u exceeds maxInstanceCount.", pMaxPrimitiveCounts[0]);
        }
        if (v.check(pSizeInfo != nullptr, "VUID-vkGetAccelerationStructureBuildSizesKHR-pSizeInfo-parameter",
                    "pSizeInfo is NULL."))
        {
            v.check(pSizeInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR,
                    "VUID-VkAccelerationStructureBuildSizesInfoKHR-sType-sType", "pSizeInfo->sType is %d.",
                    int(pSizeInfo->sType));
            v.check(pSizeInfo->pNext == nullptr, "VUID-VkAccelerationStructureBuildSizesInfoKHR-pNext-pNext",
                    "pSizeInfo->pNext is not NULL.");
        }
        if (v.failed()) return;
    }
    uint64_t primitives = 0;
    for (uint32_t g = 0; g < pBuildInfo->geometryCount; ++g) primitives += pMaxPrimitiveCounts[g];
    StructureSizes s = structureSizes(structureType(pBuildInfo->type), pBuildInfo->geometryCount, primitives,
                                      usesMotionRecords(*pBuildInfo));
    pSizeInfo->accelerationStructureSize = s.structureSize;
    pSizeInfo->buildScratchSize = s.buildScratchSize;
    pSizeInfo->updateScratchSize = s.updateScratchSize;
}

VKAPI_ATTR VkResult VKAPI_CALL CreateAccelerationStructureKHR(VkDevice device,
                                                              const VkAccelerationStructureCreateInfoKHR* pCreateInfo,
                                                              const VkAllocationCallbacks* pAllocator,
                                                              VkAccelerationStructureKHR* pAccelerationStructure) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateAccelerationStructureKHR");
    if (!dev) {
        v.fail("VUID-vkCreateAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (v.enabled()) {
        if (v.check(pCreateInfo != nullptr, "VUID-vkCreateAccelerationStructureKHR-pCreateInfo-parameter",
                    "pCreateInfo is NULL.")) {
            const auto& ci = *pCreateInfo;
            v.check(ci.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR,
                    "VUID-VkAccelerationStructureCreateInfoKHR-sType-sType", "pCreateInfo->sType is %d.",
                    int(ci.sType));
            v.check(ci.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ||
                        ci.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR ||
                        ci.type == VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR,
                    "VUID-VkAccelerationStructureCreateInfoKHR-type-parameter", "pCreateInfo->type %d is not valid.",
                    int(ci.type));
            checkNextChain(v, ci.pNext, {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV},
                           "VUID-VkAccelerationStructureCreateInfoKHR-pNext-pNext",
                           "VUID-VkAccelerationStructureCreateInfoKHR-sType-unique", "pCreateInfo");
            constexpr VkAccelerationStructureCreateFlagsKHR kKnownFlags =
                VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR |
                VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
            v.check((ci.createFlags & ~kKnownFlags) == 0, "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-parameter",
                    "pCreateInfo->createFlags 0x%x has bits that are not VkAccelerationStructureCreateFlagBitsKHR of an "
                    "enabled extension.",
                    ci.createFlags);
            // accelerationStructureCaptureReplay is not supported: a deviceAddress always breaks 03488, and 03612
            // or 03613 too (with or without the CAPTURE_REPLAY flag).
            v.check(ci.deviceAddress == 0, "VUID-vkCreateAccelerationStructureKHR-deviceAddress-03488",
                    "pCreateInfo->deviceAddress is 0x%llx but accelerationStructureCaptureReplay is not enabled.",
                    (ull)ci.deviceAddress);
            if (ci.deviceAddress != 0)
                v.check(ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR,
                        "VUID-VkAccelerationStructureCreateInfoKHR-deviceAddress-03612",
                        "pCreateInfo->deviceAddress is 0x%llx but createFlags lacks "
                        "VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR.",
                        (ull)ci.deviceAddress);
            v.check((ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR) == 0,
                    "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-03613",
                    "createFlags has DEVICE_ADDRESS_CAPTURE_REPLAY but the feature is not enabled.");
            if ((ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) &&
                ci.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) {  // [NV-motion]
                const VkAccelerationStructureMotionInfoNV* motionInfo = nullptr;
                for (auto* p = static_cast<const VkBaseInStructure*>(ci.pNext); p; p = p->pNext)
                    if (p->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV)
                        motionInfo = reinterpret_cast<const VkAccelerationStructureMotionInfoNV*>(p);
                if (v.check(motionInfo != nullptr, "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04954",
                            "createFlags has VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV and type is TOP_LEVEL, but "
                            "the pNext chain has no VkAccelerationStructureMotionInfoNV."))
                    v.check(motionInfo->flags == 0, "VUID-VkAccelerationStructureMotionInfoNV-flags-zerobitmask",
                            "VkAccelerationStructureMotionInfoNV::flags is 0x%x.", motionInfo->flags);
            }
            v.check(ci.offset % limits::kAccelerationStructureOffsetAlignment == 0,
                    "VUID-VkAccelerationStructureCreateInfoKHR-offset-03734",
                    "pCreateInfo->offset %llu is not a multiple of 256.", (ull)ci.offset);
            if (const Buffer* b = checkHandle<Buffer>(v, *dev, ci.buffer, ObjectMagic::Buffer,
                                                      "VUID-VkAccelerationStructureCreateInfoKHR-buffer-parameter",
                                                      nullptr, "pCreateInfo->buffer")) {
                v.check(b->usage & VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR,
                        "VUID-VkAccelerationStructureCreateInfoKHR-buffer-03614",
                        "pCreateInfo->buffer lacks VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR.");
                v.check(!(b->flags & VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT),
                        "VUID-VkAccelerationStructureCreateInfoKHR-buffer-03615",
                        "pCreateInfo->buffer was created with SPARSE_RESIDENCY.");
                v.check(ci.offset <= b->size && ci.size <= b->size - ci.offset,
                        "VUID-VkAccelerationStructureCreateInfoKHR-offset-03616",
                        "offset %llu + size %llu exceeds the buffer size %llu.", (ull)ci.offset, (ull)ci.size,
                        (ull)b->size);
            }
        }
        v.check(pAccelerationStructure != nullptr,
                "VUID-vkCreateAccelerationStructureKHR-pAccelerationStructure-parameter",
                "pAccelerationStructure is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    auto* as = createObject<AccelerationStructure>(pAllocator);
    if (!as) return VK_ERROR_OUT_OF_HOST_MEMORY;
    as->device = dev;
    as->buffer = fromHandle<Buffer>(pCreateInfo->buffer);
    as->offset = pCreateInfo->offset;
    as->size = pCreateInfo->size;
    as->type = pCreateInfo->type;
    as->createFlags = pCreateInfo->createFlags;
    if (!dev->track(as)) {
        destroyObject(as);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pAccelerationStructure = toHandle<VkAccelerationStructureKHR>(as);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyAccelerationStructureKHR(VkDevice device,
                                                           VkAccelerationStructureKHR accelerationStructure,
                                                           const VkAllocationCallbacks* pAllocator) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyAccelerationStructureKHR");
    if (!dev)
        return v.fail("VUID-vkDestroyAccelerationStructureKHR-device-parameter", "device is not a valid VkDevice.");
    if (accelerationStructure == VK_NULL_HANDLE) return;
    if (v.enabled()) {
        const auto* as = checkHandle<AccelerationStructure>(
            v, *dev, accelerationStructure, ObjectMagic::AccelerationStructure,
            "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parameter",
            "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parent", "accelerationStructure");
        if (!as) return;
        checkDestroyAllocator(v, as->allocator, pAllocator,
                              "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02443",
                              "VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02444");
        if (v.failed()) return;
    }
    auto* as = fromHandle<AccelerationStructure>(accelerationStructure);
    if (dev) dev->untrack(as);
    destroyObject(as);
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL
GetAccelerationStructureDeviceAddressKHR(VkDevice device, const VkAccelerationStructureDeviceAddressInfoKHR* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetAccelerationStructureDeviceAddressKHR");
    if (!dev) {
        v.fail("VUID-vkGetAccelerationStructureDeviceAddressKHR-device-parameter", "device is not a valid VkDevice.");
        return 0;
    }
    if (v.enabled()) {
        if (v.check(pInfo != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-parameter",
                    "pInfo is NULL.")) {
            v.check(pInfo->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                    "VUID-VkAccelerationStructureDeviceAddressInfoKHR-sType-sType", "pInfo->sType is %d.",
                    int(pInfo->sType));
            v.check(pInfo->pNext == nullptr, "VUID-VkAccelerationStructureDeviceAddressInfoKHR-pNext-pNext",
                    "pInfo->pNext is not NULL.");
            if (const auto* as = checkHandle<AccelerationStructure>(
                    v, *dev, pInfo->accelerationStructure, ObjectMagic::AccelerationStructure,
                    "VUID-VkAccelerationStructureDeviceAddressInfoKHR-accelerationStructure-parameter", nullptr,
                    "pInfo->accelerationStructure")) {
                v.check(as->buffer->memory != nullptr, "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09541",
                        "the buffer of pInfo->accelerationStructure is not bound to memory.");
                v.check(as->buffer->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                        "VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09542",
                        "the buffer of pInfo->accelerationStructure lacks SHADER_DEVICE_ADDRESS usage.");
            }
        }
        if (v.failed()) return 0;
    }
    return reinterpret_cast<VkDeviceAddress>(fromHandle<AccelerationStructure>(pInfo->accelerationStructure)->block());
}

namespace {

// The range and data rules of one AABB geometry of a build.
void checkAabbRange(Validator& v, const VkAccelerationStructureGeometryAabbsDataKHR& a,
                    const VkAccelerationStructureBuildRangeInfoKHR& r, const char* where, uint32_t g) {
    v.check(r.primitiveOffset % 8 == 0, "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03659",
            "%s geometry %u: primitiveOffset %u is not a multiple of 8.", where, g, r.primitiveOffset);
    if (r.primitiveCount == 0) return;
    if (!v.check(a.data.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03774",
                 "%s geometry %u: aabbs.data.hostAddress is NULL.", where, g))
        return;
    if (v.failureCount() != 0) return;  // read the boxes only through a range that passed its rules
    // VkAabbPositionsKHR needs min <= max on each axis; inactive boxes (minX NaN) are exempt. One message per
    // axis, naming the first box that breaks it.
    static const char* const kAxisVuids[3] = {"VUID-VkAabbPositionsKHR-minX-03546",
                                              "VUID-VkAabbPositionsKHR-minY-03547",
                                              "VUID-VkAabbPositionsKHR-minZ-03548"};
    static const char kAxisNames[3] = {'X', 'Y', 'Z'};
    int64_t firstBad[3] = {-1, -1, -1};
    float badMin[3] = {}, badMax[3] = {};
    AabbSource source(a, r);
    for (uint32_t i = 0; i < r.primitiveCount; ++i) {
        float lower[3], upper[3];
        if (!source.fetch(i, lower, upper)) continue;
        for (int axis = 0; axis < 3; ++axis)
            if (firstBad[axis] < 0 && !(lower[axis] <= upper[axis])) {
                firstBad[axis] = i;
                badMin[axis] = lower[axis];
                badMax[axis] = upper[axis];
            }
    }
    for (int axis = 0; axis < 3; ++axis)
        if (firstBad[axis] >= 0)
            v.fail(kAxisVuids[axis], "%s geometry %u: AABB %lld has min%c %g greater than max%c %g.", where, g,
                   (long long)firstBad[axis], kAxisNames[axis], double(badMin[axis]), kAxisNames[axis],
                   double(badMax[axis]));
}

// What one info of a build touches, for the rules between infos: its destination, update source, scratch range and
// the structures its instances reference.
struct InfoFootprint {
    const AccelerationStructure* dst = nullptr;
    const AccelerationStructure* src = nullptr;  // UPDATE only
    Span scratch;
    std::vector<const AccelerationStructure*> referenced;
};

// The structure a build info names as dstAccelerationStructure or srcAccelerationStructure: reports a handle that
// is no live structure (`parameterVuid`) or one of another device (VkAccelerationStructureBuildGeometryInfoKHR-
// commonparent: the structures of an info share the command's device).
const AccelerationStructure* buildInfoStructure(Validator& v, const Device& dev, VkAccelerationStructureKHR handle,
                                                const char* parameterVuid, const char* where, const char* member) {
    char name[80];
    std::snprintf(name, sizeof name, "%s.%s", where, member);
    return checkHandle<AccelerationStructure>(v, dev, handle, ObjectMagic::AccelerationStructure, parameterVuid,
                                              "VUID-VkAccelerationStructureBuildGeometryInfoKHR-commonparent", name);
}

// An instance's rules (the VkAccelerationStructureInstanceKHR, or the static member of a motion instance): flags and
// an invertible transform. `flagsVuid` names the structure the flags belong to.
void checkInstanceBody(Validator& v, const float transform[3][4], uint32_t sbtOffsetAndFlags, const char* flagsVuid,
                       const char* where, uint32_t k) {
    const uint32_t flags = sbtOffsetAndFlags >> 24;
    v.check((flags & ~kKnownInstanceFlags) == 0, flagsVuid,
            "%s: instance %u has flags 0x%x, with bits that are not VkGeometryInstanceFlagBitsKHR of an enabled "
            "extension.",
            where, k, flags);
    if (transform)
        v.check(invertible3x3(transform), "VUID-VkTransformMatrixKHR-matrix-03799",
                "%s: the transform of instance %u is not invertible (its first three columns).", where, k);
}

// Checks one info of vkBuildAccelerationStructuresKHR against everything it can see of itself.
void checkBuildInfo(Validator& v, const Device& dev, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                    const VkAccelerationStructureBuildRangeInfoKHR* ranges, uint32_t i, InfoFootprint& footprint) {
    char where[32];
    std::snprintf(where, sizeof where, "pInfos[%u]", i);
    checkGeometryInfo(v, info, where);
    v.check(info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR ||
                info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR,
            "VUID-vkBuildAccelerationStructuresKHR-mode-04628", "%s.mode %d is not valid.", where, int(info.mode));
    const auto* dst = buildInfoStructure(v, dev, info.dstAccelerationStructure,
                                         "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03800", where,
                                         "dstAccelerationStructure");
    footprint.dst = dst;
    if (dst) {
        v.check(dst->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03707",
                "%s.dstAccelerationStructure's buffer is not bound to memory.", where);
        if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR)
            v.check(dst->type != VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-03699",
                    "%s is a top-level build into a bottom-level structure.", where);
        if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR)
            v.check(dst->type != VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR,
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-03700",
                    "%s is a bottom-level build into a top-level structure.", where);
        // [NV-motion] The build's MOTION flag and the structure's CREATE_MOTION flag go together.
        const bool createdMotion = (dst->createFlags & VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) != 0;
        v.check(!createdMotion || motion::isMotionBuild(info.flags),
                "VUID-VkAccelerationStructureBuildGeometryInfoKHR-dstAccelerationStructure-04927",
                "%s.dstAccelerationStructure was created with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV but "
                "flags lacks VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV.", where);
        v.check(createdMotion || !motion::isMotionBuild(info.flags),
                "VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04928",
                "%s.flags has VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV but dstAccelerationStructure was not "
                "created with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV.", where);
        const uint32_t walk = info.geometryCount <= limits::kMaxGeometryCount ? info.geometryCount : 0;
        for (uint32_t g = 0; g < walk && !createdMotion; ++g) {
            const VkAccelerationStructureGeometryKHR* geom = geometryAt(info, g);
            if (geom && geom->geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR &&
                !v.check(motion::findMotionTriangles(geom->geometry.triangles) == nullptr,
                         "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04955",
                         "%s geometry %u has VkAccelerationStructureGeometryMotionTrianglesDataNV but "
                         "dstAccelerationStructure was not created with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV.",
                         where, g))
                break;
        }
    }
    // UPDATE: the source, and what must match its last build (update_validation.hpp).
    const std::byte* updateSrc = nullptr;
    if (info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) {
        updateSrc = checkUpdateSource(v, dev, info, ranges, dst, where);
        if (updateSrc) footprint.src = fromHandle<AccelerationStructure>(info.srcAccelerationStructure);
    }
    if (info.pGeometries == nullptr && info.ppGeometries == nullptr && info.geometryCount != 0) return;
    // A build of no geometries may pass no range array; everything below still applies to it (the destination's size).
    if ((!ranges && info.geometryCount != 0) || info.geometryCount > limits::kMaxGeometryCount) return;
    uint64_t total = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) total += ranges[g].primitiveCount;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR) {
        const VkAccelerationStructureGeometryKHR* first = info.geometryCount ? geometryAt(info, 0) : nullptr;
        const bool aabbs = first && first->geometryType == VK_GEOMETRY_TYPE_AABBS_KHR;
        if (!v.check(total <= limits::kMaxPrimitiveCount,
                     aabbs ? "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03794"
                           : "VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03795",
                     "%s: the geometries hold %llu %s, more than maxPrimitiveCount.", where, (ull)total,
                     aabbs ? "AABBs" : "triangles"))
            return;  // nothing is read from a build that large
    }
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const VkAccelerationStructureGeometryKHR* geom = geometryAt(info, g);
        if (!geom) continue;
        const auto& r = ranges[g];
        if (geom->geometryType == VK_GEOMETRY_TYPE_AABBS_KHR) {
            checkAabbRange(v, geom->geometry.aabbs, r, where, g);
        } else if (geom->geometryType == VK_GEOMETRY_TYPE_SPHERES_NV ||
                   geom->geometryType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV) {
            checkSweptSpheresRange(v, *geom, r, where, g);
        } else if (geom->geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR) {
            const auto& t = geom->geometry.triangles;
            const VertexFormatInfo* fmt = vertexFormatInfo(t.vertexFormat);
            const bool indexed = t.indexType != VK_INDEX_TYPE_NONE_KHR;
            if (r.primitiveCount != 0) {
                v.check(t.vertexData.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03771",
                        "%s geometry %u: triangles.vertexData.hostAddress is NULL.", where, g);
                if (indexed)
                    v.check(t.indexData.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03772",
                            "%s geometry %u: triangles.indexData.hostAddress is NULL with indexType %d.", where, g,
                            int(t.indexType));
            }
            if (indexed) {
                uint32_t indexSize = t.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
                v.check(r.primitiveOffset % indexSize == 0,
                        "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03656",
                        "%s geometry %u: primitiveOffset %u is not a multiple of the index size %u.", where, g,
                        r.primitiveOffset, indexSize);
            } else if (fmt) {
                uint32_t unit = fmt->packed ? fmt->size : fmt->componentSize;
                v.check(r.primitiveOffset % unit == 0,
                        "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03657",
                        "%s geometry %u: primitiveOffset %u is not a multiple of %u.", where, g, r.primitiveOffset,
                        unit);
            }
            if (t.transformData.hostAddress != nullptr &&
                v.check(r.transformOffset % 16 == 0,
                        "VUID-VkAccelerationStructureBuildRangeInfoKHR-transformOffset-03658",
                        "%s geometry %u: transformOffset %u is not a multiple of 16.", where, g, r.transformOffset)) {
                float m[3][4];
                std::memcpy(m, static_cast<const std::byte*>(t.transformData.hostAddress) + r.transformOffset,
                            sizeof m);
                v.check(invertible3x3(m), "VUID-VkTransformMatrixKHR-matrix-03799",
                        "%s geometry %u: the transform at transformData + %u is not invertible.", where, g,
                        r.transformOffset);
            }
            if (const auto* motionData = motion::findMotionTriangles(t))
                v.check(motionData->vertexData.hostAddress != nullptr,
                        "VUID-vkBuildAccelerationStructuresKHR-pInfos-11820",
                        "%s geometry %u: VkAccelerationStructureGeometryMotionTrianglesDataNV::vertexData.hostAddress "
                        "is NULL.",
                        where, g);
            // maxVertex against the vertices actually read.
            if (r.primitiveCount != 0 && t.vertexData.hostAddress && (!indexed || t.indexData.hostAddress) &&
                v.failureCount() == 0) {
                if (!indexed) {
                    uint64_t last = uint64_t(r.firstVertex) + 3ull * r.primitiveCount - 1;
                    v.check(last <= t.maxVertex, "VUID-VkAccelerationStructureBuildRangeInfoKHR-None-10775",
                            "%s geometry %u: firstVertex %u + 3 * primitiveCount %u - 1 = %llu exceeds maxVertex %u.",
                            where, g, r.firstVertex, r.primitiveCount, (ull)last, t.maxVertex);
                } else {
                    TriangleSource source(t, r);
                    uint64_t maxIndex = 0;
                    for (uint32_t p = 0; p < r.primitiveCount; ++p)
                        for (uint32_t j = 0; j < 3; ++j) maxIndex = std::max(maxIndex, source.vertexIndex(p, j));
                    uint64_t last = uint64_t(r.firstVertex) + maxIndex;
                    v.check(last <= t.maxVertex, "VUID-VkAccelerationStructureBuildRangeInfoKHR-maxVertex-10774",
                            "%s geometry %u: firstVertex %u + the largest index %llu exceeds maxVertex %u.", where, g,
                            r.firstVertex, (ull)maxIndex, t.maxVertex);
                }
            }
        } else if (geom->geometryType == VK_GEOMETRY_TYPE_INSTANCES_KHR) {
            const auto& inst = geom->geometry.instances;
            v.check(r.primitiveOffset % 16 == 0, "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03660",
                    "%s: primitiveOffset %u is not a multiple of 16.", where, r.primitiveOffset);
            if (!v.check(r.primitiveCount <= limits::kMaxInstanceCount,
                         "VUID-vkBuildAccelerationStructuresKHR-pInfos-03801",
                         "%s: primitiveCount %u exceeds maxInstanceCount.", where, r.primitiveCount))
                return;  // nothing is read from a build that large
            if (r.primitiveCount != 0 && motion::isMotionBuild(info.flags) && inst.data.hostAddress != nullptr &&
                r.primitiveOffset % 16 == 0) {
                // [NV-motion] VkAccelerationStructureMotionInstanceNV records (or typed pointers to their members).
                motion::MotionInstanceSource source(inst, r);
                for (uint32_t k = 0; k < r.primitiveCount; ++k) {
                    if (inst.arrayOfPointers &&
                        !v.check((source.rawAddress(k) & ~uintptr_t(0xF)) != 0,
                                 "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                                 "%s: instance pointer %u is NULL.", where, k))
                        continue;
                    motion::RawMotionInstance mi;
                    source.fetch(k, mi);
                    if (!v.check(mi.type <= motion::kSrt, "VUID-VkAccelerationStructureMotionInstanceNV-type-parameter",
                                 "%s: motion instance %u has type %u, not a VkAccelerationStructureMotionInstanceTypeNV.",
                                 where, k, mi.type))
                        continue;
                    v.check(mi.flags == 0, "VUID-VkAccelerationStructureMotionInstanceNV-flags-zerobitmask",
                            "%s: motion instance %u has flags 0x%x.", where, k, mi.flags);
                    static const char* const kFlagVuids[3] = {
                        "VUID-VkAccelerationStructureInstanceKHR-flags-parameter",
                        "VUID-VkAccelerationStructureMatrixMotionInstanceNV-flags-parameter",
                        "VUID-VkAccelerationStructureSRTMotionInstanceNV-flags-parameter"};
                    checkInstanceBody(v, mi.type == motion::kStatic ? mi.staticTransform : nullptr,
                                      mi.sbtOffsetAndFlags, kFlagVuids[mi.type], where, k);
                    if (mi.reference == 0) continue;
                    const auto* blas = dev.live<AccelerationStructure>(reinterpret_cast<const void*>(mi.reference),
                                                                       ObjectMagic::AccelerationStructure);
                    if (!v.check(blas != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-04930",
                                 "%s: motion instance %u references 0x%llx, which is not a live "
                                 "VkAccelerationStructureKHR.",
                                 where, k, (ull)mi.reference))
                        continue;
                    v.check(blas->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03709",
                            "%s: instance %u references a structure whose buffer is not bound to memory.", where, k);
                    footprint.referenced.push_back(blas);
                    if (v.failureCount() > 16) break;  // enough said
                }
            } else if (r.primitiveCount != 0 &&
                v.check(inst.data.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                        "%s: instances.data.hostAddress is NULL.", where) &&
                r.primitiveOffset % 16 == 0) {
                InstanceSource source(inst, r);
                for (uint32_t k = 0; k < r.primitiveCount; ++k) {
                    if (inst.arrayOfPointers &&
                        !v.check(loadUnaligned<const void*>(static_cast<const std::byte*>(inst.data.hostAddress) +
                                                           r.primitiveOffset + 8ull * k) != nullptr,
                                 "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                                 "%s: instance pointer %u is NULL.", where, k))
                        continue;
                    RawInstance ri = source.fetch(k);
                    checkInstanceBody(v, ri.transform, ri.sbtOffsetAndFlags,
                                      "VUID-VkAccelerationStructureInstanceKHR-flags-parameter", where, k);
                    if (ri.reference == 0) continue;
                    const auto* blas = dev.live<AccelerationStructure>(reinterpret_cast<const void*>(ri.reference),
                                                                       ObjectMagic::AccelerationStructure);
                    if (!v.check(blas != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03779",
                                 "%s: instance %u references 0x%llx, which is not a live VkAccelerationStructureKHR.",
                                 where, k, (ull)ri.reference))
                        continue;
                    v.check(blas->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03709",
                            "%s: instance %u references a structure whose buffer is not bound to memory.", where, k);
                    footprint.referenced.push_back(blas);
                    if (v.failureCount() > 16) break;  // enough said
                }
            }
        }
    }
    if (dst && info.type != VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR) {
        StructureSizes sizes =
            structureSizes(structureType(info.type), info.geometryCount, total, usesMotionRecords(info));
        // An update may also go into a structure of the source's compacted size: a refit writes usedSize bytes.
        const uint64_t needed =
            updateSrc ? std::min(sizes.structureSize, format::header(updateSrc)->usedSize) : sizes.structureSize;
        v.check(dst->size >= needed, "VUID-vkBuildAccelerationStructuresKHR-pInfos-10126",
                "%s.dstAccelerationStructure has size %llu but the %s needs %llu.", where, (ull)dst->size,
                updateSrc ? "update" : "build", (ull)needed);
        uint64_t scratchSize = info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR ? sizes.updateScratchSize
                                                                                            : sizes.buildScratchSize;
        if (scratchSize != 0) {
            v.check(info.scratchData.hostAddress != nullptr,
                    info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR
                        ? "VUID-vkBuildAccelerationStructuresKHR-pInfos-12245"
                        : "VUID-vkBuildAccelerationStructuresKHR-pInfos-12244",
                    "%s.scratchData.hostAddress is NULL but %llu bytes of scratch are needed.", where,
                    (ull)scratchSize);
            auto s = reinterpret_cast<uintptr_t>(info.scratchData.hostAddress);
            if (s) footprint.scratch = Span{s, s + scratchSize};
            if (dst->buffer->memory) {
                v.check(!blockSpan(dst).overlaps(Span{s, s + scratchSize}),
                        "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03703",
                        "%s.scratchData overlaps the memory of its dstAccelerationStructure.", where);
            }
        }
    }
    checkUpdateData(v, info, ranges, updateSrc, where);
}

}  // namespace

VKAPI_ATTR VkResult VKAPI_CALL BuildAccelerationStructuresKHR(
    VkDevice device, VkDeferredOperationKHR deferredOperation, uint32_t infoCount,
    const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
    const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBuildAccelerationStructuresKHR");
    if (v.enabled()) {
        if (!v.check(dev != nullptr, "VUID-vkBuildAccelerationStructuresKHR-device-parameter",
                     "device is not a valid VkDevice."))
            return VK_ERROR_VALIDATION_FAILED_EXT;
        checkDeferredOperation(v, *dev, deferredOperation,
                               {"VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parameter",
                                "VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parent",
                                "VUID-vkBuildAccelerationStructuresKHR-deferredOperation-03678"});
        v.check(infoCount > 0, "VUID-vkBuildAccelerationStructuresKHR-infoCount-arraylength", "infoCount is 0.");
        v.check(pInfos != nullptr || infoCount == 0, "VUID-vkBuildAccelerationStructuresKHR-pInfos-parameter",
                "pInfos is NULL.");
        v.check(ppBuildRangeInfos != nullptr || infoCount == 0,
                "VUID-vkBuildAccelerationStructuresKHR-ppBuildRangeInfos-parameter", "ppBuildRangeInfos is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
        std::vector<InfoFootprint> footprints(infoCount);
        std::unordered_set<const void*> dsts;
        for (uint32_t i = 0; i < infoCount; ++i) {
            v.check(ppBuildRangeInfos[i] != nullptr || pInfos[i].geometryCount == 0,
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-11702", "ppBuildRangeInfos[%u] is NULL.", i);
            checkBuildInfo(v, *dev, pInfos[i], ppBuildRangeInfos[i], i, footprints[i]);
            const void* dst = pInfos[i].dstAccelerationStructure;
            v.check(dsts.insert(dst).second, "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03698",
                    "pInfos[%u].dstAccelerationStructure is also the destination of an earlier info.", i);
        }
        // Between infos: the builds have no order, so none may read or write what another writes.
        for (uint32_t i = 0; i < infoCount; ++i) {
            const InfoFootprint& fi = footprints[i];
            for (uint32_t j = 0; j < infoCount; ++j) {
                if (j == i) continue;
                const InfoFootprint& fj = footprints[j];
                if (pInfos[i].mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR &&
                    !v.check(pInfos[i].srcAccelerationStructure != pInfos[j].dstAccelerationStructure,
                             "VUID-vkBuildAccelerationStructuresKHR-pInfos-03403",
                             "pInfos[%u].srcAccelerationStructure is the destination of pInfos[%u].", i, j))
                    continue;
                if (fi.src && fj.dst && fi.src->block() && fj.dst->block())
                    v.check(!blockSpan(fj.dst).overlaps(blockSpan(fi.src)),
                            "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03701",
                            "the memory of pInfos[%u].dstAccelerationStructure overlaps pInfos[%u]'s update source.",
                            j, i);
                if (j > i && fi.dst && fj.dst && fi.dst != fj.dst && fi.dst->block() && fj.dst->block())
                    v.check(!blockSpan(fi.dst).overlaps(blockSpan(fj.dst)),
                            "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03702",
                            "the memory of pInfos[%u].dstAccelerationStructure overlaps that of pInfos[%u].", i, j);
                if (fj.dst && fj.dst->block() && fi.scratch.begin != fi.scratch.end)
                    v.check(!blockSpan(fj.dst).overlaps(fi.scratch),
                            "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03703",
                            "pInfos[%u].scratchData overlaps the memory of pInfos[%u].dstAccelerationStructure.", i, j);
                if (j > i)
                    v.check(!fi.scratch.overlaps(fj.scratch), "VUID-vkBuildAccelerationStructuresKHR-scratchData-03704",
                            "the scratch memory of pInfos[%u] and pInfos[%u] overlaps.", i, j);
                for (const AccelerationStructure* referenced : fj.referenced) {
                    if (!v.check(referenced != fi.dst, "VUID-vkBuildAccelerationStructuresKHR-None-03407",
                                 "pInfos[%u].dstAccelerationStructure is referenced by an instance of pInfos[%u].", i,
                                 j))
                        break;
                    if (fi.dst && fi.dst->block() && referenced->block() &&
                        !v.check(!blockSpan(fi.dst).overlaps(blockSpan(referenced)),
                                 "VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03706",
                                 "the memory of pInfos[%u].dstAccelerationStructure overlaps a structure an instance of "
                                 "pInfos[%u] references.",
                                 i, j))
                        break;
                }
            }
            // An update source's memory is read: no scratch may overlap it, its own info's included.
            if (fi.src && fi.src->block())
                for (uint32_t j = 0; j < infoCount; ++j)
                    v.check(!footprints[j].scratch.overlaps(blockSpan(fi.src)),
                            "VUID-vkBuildAccelerationStructuresKHR-scratchData-03705",
                            "the scratch memory of pInfos[%u] overlaps pInfos[%u].srcAccelerationStructure.", j, i);
        }
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    // One info's work; `parallel` spreads a build over the threads joined to a deferred operation.
    auto runInfo = [pInfos, ppBuildRangeInfos](uint32_t i, const ParallelFor* parallel) {
        auto* dst = fromHandle<AccelerationStructure>(pInfos[i].dstAccelerationStructure);
        VkResult r;
        if (pInfos[i].mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) {
            // A refit of the source's tree (engine/refit.hpp); src == dst refits in place.
            const auto* src = fromHandle<AccelerationStructure>(pInfos[i].srcAccelerationStructure);
            const std::byte* srcBlock = src ? src->block() : nullptr;
            RefitJob job{&pInfos[i], ppBuildRangeInfos[i], srcBlock, dst->block(), dst->size,
                         resolveAccelerationStructure};
            r = srcBlock && job.dst ? refitAccelerationStructure(job) : VK_ERROR_UNKNOWN;
        } else {
            BuildJob job{&pInfos[i], ppBuildRangeInfos[i], dst->block(), dst->size, resolveAccelerationStructure,
                         parallel};
            try {
                r = buildAccelerationStructure(job);
            } catch (...) {
                markUnconstructed(*dst);  // out of memory part-way: dst holds no structure (an update never allocates)
                throw;
            }
        }
        if (r == VK_SUCCESS) dst->constructed = true;
        return r;
    };
    if (deferredOperation != VK_NULL_HANDLE) {
        // Nothing runs now: each info becomes a task of the operation, run by the threads that join it.
        auto* op = fromHandle<DeferredOperation>(deferredOperation);
        auto results = std::make_shared<std::vector<VkResult>>(infoCount, VK_SUCCESS);
        std::vector<DeferredOperation::Task> tasks;
        uint64_t primitives = 0;
        for (uint32_t i = 0; i < infoCount; ++i) {
            tasks.push_back([=] { (*results)[i] = runInfo(i, &op->parallelFor()); });
            for (uint32_t g = 0; g < pInfos[i].geometryCount; ++g) primitives += ppBuildRangeInfos[i][g].primitiveCount;
        }
        const uint32_t hint = uint32_t(std::min<uint64_t>(infoCount + primitives / 4096, 256));
        op->start(std::move(tasks), [results] {
            for (VkResult r : *results)
                if (r != VK_SUCCESS) return r;
            return VK_SUCCESS;
        }, hint);
        return VK_OPERATION_DEFERRED_KHR;
    }
    VkResult result = VK_SUCCESS;
    for (uint32_t i = 0; i < infoCount; ++i)
        if (VkResult r = runInfo(i, nullptr); r != VK_SUCCESS) result = r;
    return result;
}

}  // namespace vkas::entry
