#include "engine/util/host_memory.hpp"
#include "api/validate/build_infos.hpp"

#include <algorithm>
#include <cstdio>
#include <unordered_set>
#include <vector>

#include "api/build_geometry_info.hpp"
#include "api/limits.hpp"
#include "api/validate/build_ranges.hpp"
#include "api/validate/geometry_info.hpp"
#include "api/validate/opacity_micromaps.hpp"
#include "api/validate/parameters.hpp"
#include "api/validate/swept_spheres.hpp"
#include "api/validate/update.hpp"
#include "engine/assemble/opacity_section_build.hpp"
#include "engine/assemble/size_query.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/motion.hpp"
#include "engine/format/sizes.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/motion_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

// Byte ranges [begin, end) in host memory, for the overlap rules.
struct Span {
    uintptr_t begin = 0, end = 0;
    bool overlaps(const Span& o) const { return begin < o.end && o.begin < end && begin != end && o.begin != o.end; }
};

Span blockSpan(const AccelerationStructure* as) {
    auto b = reinterpret_cast<uintptr_t>(as->block());
    return {b, b + as->size};
}

// What one info of a build touches, for the rules between infos: its destination, update source, scratch range and
// the structures its instances reference.
struct InfoFootprint {
    const AccelerationStructure* dst = nullptr;
    const AccelerationStructure* src = nullptr;  // UPDATE only
    Span scratch;
    HostVector<const AccelerationStructure*> referenced;
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
    // UPDATE: the source, and what must match its last build (update.hpp).
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
    if (!checkPrimitiveTotal(v, info, total, where)) return;  // nothing is read from a build that large
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
            checkTrianglesRange(v, geom->geometry.triangles, r, where, g);
            // The micromap's data is read only once the structure's own rules passed (its index type and stride).
            if (const auto* omm = opacityMicromapOf(geom->geometry.triangles); omm && !v.failed())
                checkOpacityMicromapRange(v, dev, *omm, r.primitiveCount, where, g);
        } else if (geom->geometryType == VK_GEOMETRY_TYPE_INSTANCES_KHR) {
            if (!checkInstancesRange(v, dev, geom->geometry.instances, r, info.flags, where, footprint.referenced))
                return;  // nothing is read from a build that large
        }
    }
    if (dst && info.type != VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR) {
        StructureSizes sizes = structureSizes(info, total);
        // [EXT-OMM] The room for the geometries' opacity micromaps (engine/format/opacity_section.hpp).
        if (allGeometriesPresent(info))
            sizes.structureSize += opacitySectionBound(info, [&](uint32_t g) { return ranges[g].primitiveCount; });
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

void checkBuildAccelerationStructures(Validator& v, const Device& dev, VkDeferredOperationKHR deferredOperation,
                                      uint32_t infoCount, const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
                                      const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos) {
    checkDeferredOperation(v, dev, deferredOperation,
                           {"VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parameter",
                            "VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parent",
                            "VUID-vkBuildAccelerationStructuresKHR-deferredOperation-03678"});
    v.check(infoCount > 0, "VUID-vkBuildAccelerationStructuresKHR-infoCount-arraylength", "infoCount is 0.");
    v.check(pInfos != nullptr || infoCount == 0, "VUID-vkBuildAccelerationStructuresKHR-pInfos-parameter",
            "pInfos is NULL.");
    v.check(ppBuildRangeInfos != nullptr || infoCount == 0,
            "VUID-vkBuildAccelerationStructuresKHR-ppBuildRangeInfos-parameter", "ppBuildRangeInfos is NULL.");
    if (v.failed()) return;
    HostVector<InfoFootprint> footprints(infoCount);
    HostUnorderedSet<const void*> dsts;
    for (uint32_t i = 0; i < infoCount; ++i) {
        v.check(ppBuildRangeInfos[i] != nullptr || pInfos[i].geometryCount == 0,
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-11702", "ppBuildRangeInfos[%u] is NULL.", i);
        checkBuildInfo(v, dev, pInfos[i], ppBuildRangeInfos[i], i, footprints[i]);
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
}

}  // namespace vkas
