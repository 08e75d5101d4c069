#include "api/validate/update.hpp"

#include <cstdio>

#include <algorithm>

#include "api/build_geometry_info.hpp"
#include "api/validate/opacity_micromaps.hpp"
#include "api/validate/parameters.hpp"
#include "engine/assemble/refit.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/format/layout.hpp"
#include "engine/input/build_inputs.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

bool aliases(const AccelerationStructure* a, const AccelerationStructure* b) {
    const auto pa = reinterpret_cast<uintptr_t>(a->block()), pb = reinterpret_cast<uintptr_t>(b->block());
    if (!pa || !pb || a->size == 0 || b->size == 0) return false;
    return pa < pb + b->size && pb < pa + a->size;
}

}  // namespace

const std::byte* checkUpdateSource(Validator& v, const Device& dev, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                   const VkAccelerationStructureBuildRangeInfoKHR* ranges,
                                   const AccelerationStructure* dst, const char* where) {
    if (!v.check(info.srcAccelerationStructure != VK_NULL_HANDLE, "VUID-vkBuildAccelerationStructuresKHR-pInfos-04630",
                 "%s.mode is UPDATE but srcAccelerationStructure is VK_NULL_HANDLE.", where))
        return nullptr;
    char name[64];
    std::snprintf(name, sizeof name, "%s.srcAccelerationStructure", where);
    const auto* src = checkHandle<AccelerationStructure>(
        v, dev, info.srcAccelerationStructure, ObjectMagic::AccelerationStructure,
        "VUID-vkBuildAccelerationStructuresKHR-srcAccelerationStructure-04629",
        "VUID-VkAccelerationStructureBuildGeometryInfoKHR-commonparent", name);
    if (!src) return nullptr;
    if (!v.check(src->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03708",
                 "%s.srcAccelerationStructure's buffer is not bound to memory.", where))
        return nullptr;
    const std::byte* block = src->block();
    const format::Header* h = format::header(block);
    if (!v.check(src->constructed && h->magic == format::kMagic, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667",
                 "%s.srcAccelerationStructure has not been built.", where))
        return nullptr;
    if (!v.check(h->buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR,
                 "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667",
                 "%s.srcAccelerationStructure was not built with ALLOW_UPDATE (its flags were 0x%x).", where,
                 h->buildFlags))
        return nullptr;
    if (dst && dst != src)
        v.check(!aliases(src, dst), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03668",
                "%s: srcAccelerationStructure and dstAccelerationStructure are different structures whose memory "
                "overlaps.", where);
    // What the last build recorded (format::Header, format::GeometryDesc).
    // A different type makes every geometry different too: 03760 alone says it.
    if (!v.check(uint32_t(info.type) == h->type, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03760",
                 "%s.type is %d but srcAccelerationStructure was last built with type %u.", where, int(info.type),
                 h->type))
        return block;
    v.check(info.flags == h->buildFlags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03759",
            "%s.flags is 0x%x but srcAccelerationStructure was last built with flags 0x%x.", where, info.flags,
            h->buildFlags);
    v.check(info.geometryCount == h->geometryCount, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03758",
            "%s.geometryCount is %u but srcAccelerationStructure was last built with %u.", where, info.geometryCount,
            h->geometryCount);
    if (!info.pGeometries && !info.ppGeometries) return block;
    const format::GeometryDesc* descs = format::geometries(block);
    const uint32_t n = std::min(info.geometryCount, h->geometryCount);
    for (uint32_t g = 0; g < n; ++g) {
        const VkAccelerationStructureGeometryKHR* geom = geometryAt(info, g);
        if (!geom) continue;
        const format::GeometryDesc& d = descs[g];
        if (!v.check(uint32_t(geom->geometryType) == d.geometryType,
                     "VUID-vkBuildAccelerationStructuresKHR-pInfos-03761",
                     "%s geometry %u: geometryType is %d but it was %u in the last build of srcAccelerationStructure.",
                     where, g, int(geom->geometryType), d.geometryType))
            continue;
        v.check(geom->flags == d.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03762",
                "%s geometry %u: flags is 0x%x but it was 0x%x in the last build of srcAccelerationStructure.", where, g,
                geom->flags, d.flags);
        if (ranges)
            v.check(ranges[g].primitiveCount == d.primitiveCount, "VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769",
                    "%s geometry %u: primitiveCount is %u but it was %u in the last build of srcAccelerationStructure.",
                    where, g, ranges[g].primitiveCount, d.primitiveCount);
        if (geom->geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR) continue;
        const auto& t = geom->geometry.triangles;
        v.check(uint32_t(t.vertexFormat) == d.vertexFormat, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03763",
                "%s geometry %u: vertexFormat is %d but it was %u in the last build of srcAccelerationStructure.", where,
                g, int(t.vertexFormat), d.vertexFormat);
        v.check(t.maxVertex == d.maxVertex, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03764",
                "%s geometry %u: maxVertex is %u but it was %u in the last build of srcAccelerationStructure.", where, g,
                t.maxVertex, d.maxVertex);
        v.check(uint32_t(t.indexType) == d.indexType, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03765",
                "%s geometry %u: indexType is %d but it was %u in the last build of srcAccelerationStructure.", where, g,
                int(t.indexType), d.indexType);
        const bool hasTransform = t.transformData.hostAddress != nullptr;
        v.check(d.hasTransform || !hasTransform, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03766",
                "%s geometry %u: transformData is not NULL but it was NULL in the last build of "
                "srcAccelerationStructure.", where, g);
        v.check(!d.hasTransform || hasTransform, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03767",
                "%s geometry %u: transformData is NULL but it was not NULL in the last build of "
                "srcAccelerationStructure.", where, g);
    }
    return block;
}

void checkUpdateData(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                     const VkAccelerationStructureBuildRangeInfoKHR* ranges, const std::byte* src, const char* where) {
    if (!src || !ranges || v.failureCount() != 0) return;
    checkOpacityMicromapUpdate(v, info, ranges, src, where);  // [EXT-OMM]
    if (v.failureCount() != 0) return;
    RefitJob job{&info, ranges, src, nullptr, 0, nullptr};
    if (!refitShapeMatches(job)) return;
    const format::GeometryDesc* descs = format::geometries(src);
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const VkAccelerationStructureGeometryKHR* geom = geometryAt(info, g);
        if (geom->geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR ||
            geom->geometry.triangles.indexType == VK_INDEX_TYPE_NONE_KHR || ranges[g].primitiveCount == 0)
            continue;
        v.check(referencedIndexHash(geom->geometry.triangles, ranges[g]) == descs[g].indexHash,
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03768",
                "%s geometry %u: the index values differ from those of the last build of srcAccelerationStructure.",
                where, g);
    }
    if (v.failureCount() != 0) return;
    const ActivityViolation a = checkUpdateActivity(job);
    const bool top = info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    if (a.vuid == 3663) {
        if (top)
            v.fail("VUID-vkBuildAccelerationStructuresKHR-pInfos-03663",
                   "%s: instance %u was active in the last build of srcAccelerationStructure but is inactive now.",
                   where, a.primitive);
        else
            v.fail("VUID-vkBuildAccelerationStructuresKHR-pInfos-03663",
                   "%s geometry %u: primitive %u was active in the last build of srcAccelerationStructure but is "
                   "inactive now.", where, a.geometry, a.primitive);
    } else if (a.vuid == 3664) {
        if (top)
            v.fail("VUID-vkBuildAccelerationStructuresKHR-pInfos-03664",
                   "%s: instance %u was inactive in the last build of srcAccelerationStructure but is active now.",
                   where, a.primitive);
        else
            v.fail("VUID-vkBuildAccelerationStructuresKHR-pInfos-03664",
                   "%s geometry %u: primitive %u was inactive in the last build of srcAccelerationStructure but is "
                   "active now.", where, a.geometry, a.primitive);
    }
}

}  // namespace vkas
