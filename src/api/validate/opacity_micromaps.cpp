#include "engine/util/host_memory.hpp"
#include "api/validate/opacity_micromaps.hpp"

#include <cstdio>
#include <map>
#include <utility>

#include "api/device.hpp"
#include "api/micromap.hpp"
#include "api/objects.hpp"
#include "api/validate/parameters.hpp"
#include "engine/assemble/opacity_section_build.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/format/opacity_section.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"

namespace vkas {

namespace {
using ull = unsigned long long;
}

void checkOpacityMicromapStructure(Validator& v, const VkAccelerationStructureTrianglesOpacityMicromapEXT& omm,
                                   const char* where, uint32_t g) {
    // "Only one of pUsageCounts or ppUsageCounts can be a valid pointer, the other must be NULL."
    v.check(!(omm.pUsageCounts && omm.ppUsageCounts),
            "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-pUsageCounts-07335",
            "%s geometry %u: VkAccelerationStructureTrianglesOpacityMicromapEXT has both pUsageCounts and "
            "ppUsageCounts.",
            where, g);
    v.check(omm.usageCountsCount == 0 || omm.pUsageCounts || omm.ppUsageCounts,
            "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-pUsageCounts-parameter",
            "%s geometry %u: usageCountsCount is %u but pUsageCounts and ppUsageCounts are NULL.", where, g,
            omm.usageCountsCount);
    if (omm.ppUsageCounts)
        for (uint32_t i = 0; i < omm.usageCountsCount; ++i)
            if (!v.check(omm.ppUsageCounts[i] != nullptr,
                         "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-ppUsageCounts-parameter",
                         "%s geometry %u: ppUsageCounts[%u] is NULL.", where, g, i))
                break;
    const bool indexed = omm.indexType != VK_INDEX_TYPE_NONE_KHR;
    // "indexType must be VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32, or VK_INDEX_TYPE_NONE_KHR"
    const bool indexTypeOk = omm.indexType == VK_INDEX_TYPE_UINT16 || omm.indexType == VK_INDEX_TYPE_UINT32 || !indexed;
    v.check(indexTypeOk, "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-indexType-10719",
            "%s geometry %u: the opacity micromap's indexType is %d.", where, g, int(omm.indexType));
    if (indexed && indexTypeOk) {
        const uint64_t size = omm.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        // "If indexType is not VK_INDEX_TYPE_NONE_KHR, then indexStride must be a multiple of the size in bytes of
        // indexType" and "must be less than or equal to 2^32-1".
        v.check(omm.indexStride % size == 0, "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-indexType-10722",
                "%s geometry %u: the opacity micromap's indexStride %llu is not a multiple of %llu.", where, g,
                (ull)omm.indexStride, (ull)size);
        v.check(omm.indexStride <= 0xFFFF'FFFFull,
                "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-indexType-10723",
                "%s geometry %u: the opacity micromap's indexStride %llu is more than 2^32-1.", where, g,
                (ull)omm.indexStride);
    }
    // The usage counts of a geometry with a micromap: valid formats, levels within the limits (11679-11681).
    if (omm.micromap == VK_NULL_HANDLE || (omm.pUsageCounts && omm.ppUsageCounts)) return;
    for (uint32_t i = 0; i < omm.usageCountsCount; ++i) {
        const VkMicromapUsageEXT* u = usageCountAt(omm, i);
        if (!u) continue;
        if (!v.check(format::isOpacityFormat(u->format),
                     "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-format-11679",
                     "%s geometry %u: usage count %u has format %u, not a VkOpacityMicromapFormatEXT.", where, g, i,
                     u->format))
            continue;
        const bool twoState = u->format == format::kOpacityFormat2State;
        v.check(u->subdivisionLevel <= format::maxOpacitySubdivisionLevel(u->format),
                twoState ? "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-subdivisionLevel-11680"
                         : "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-subdivisionLevel-11681",
                "%s geometry %u: usage count %u has subdivisionLevel %u, more than maxOpacity%sStateSubdivisionLevel "
                "(%u).",
                where, g, i, u->subdivisionLevel, twoState ? "2" : "4",
                format::maxOpacitySubdivisionLevel(u->format));
    }
}

void checkOpacityMicromapRange(Validator& v, const Device& dev,
                               const VkAccelerationStructureTrianglesOpacityMicromapEXT& omm, uint32_t primitiveCount,
                               const char* where, uint32_t g) {
    char name[128];
    std::snprintf(name, sizeof name, "%s geometry %u: the opacity micromap's micromap", where, g);
    const Micromap* micromap = nullptr;
    if (omm.micromap != VK_NULL_HANDLE) {
        micromap = checkHandle<Micromap>(v, dev, omm.micromap, ObjectMagic::Micromap,
                                         "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-parameter",
                                         nullptr, name);
        if (!micromap) return;
        // The build copies the micromap's states (engine/format/opacity_section.hpp): it must hold some.
        if (!v.check(resolveMicromap(uint64_t(omm.micromap)) != nullptr,
                     "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-vkasConstructed",
                     "%s (0x%llx) has not been built, copied or deserialized.", name, (ull)uint64_t(omm.micromap)))
            return;
    }
    // "if there is an instance of VkAccelerationStructureTrianglesOpacityMicromapEXT in the geometry.triangles.pNext
    // chain, and its indexType is VK_INDEX_TYPE_NONE_KHR, then its indexBuffer.hostAddress must be 0" (10892), "and
    // its indexType is not VK_INDEX_TYPE_NONE_KHR, then its indexBuffer.hostAddress must not be 0" (11821).
    if (omm.indexType == VK_INDEX_TYPE_NONE_KHR) {
        if (!v.check(omm.indexBuffer.hostAddress == nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-10892",
                     "%s geometry %u: the opacity micromap's indexType is VK_INDEX_TYPE_NONE_KHR but "
                     "indexBuffer.hostAddress is not NULL.",
                     where, g))
            return;
    } else if (!v.check(omm.indexBuffer.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-11821",
                        "%s geometry %u: the opacity micromap's indexBuffer.hostAddress is NULL with indexType %d.",
                        where, g, int(omm.indexType))) {
        return;
    }
    const std::byte* block = micromap ? resolveMicromap(uint64_t(omm.micromap)) : nullptr;
    const uint32_t triangles = block ? format::micromapHeader(block)->triangleCount : 0;
    const format::MicromapTriangle* tris = block ? format::micromapTriangles(block) : nullptr;
    // The (format, level) of each triangle after indirection, counted: "For a given format and subdivisionLevel the
    // number of triangles in this geometry matching those values after indirection and special index handling must
    // be equal to the sum of matching count provided."
    HostMap<std::pair<uint32_t, uint32_t>, uint64_t> used;
    for (uint32_t i = 0; i < primitiveCount; ++i) {
        const OpacityIndex index = opacityIndexOf(omm, i);
        if (index.special) continue;
        if (!block) {
            // "If micromap is VK_NULL_HANDLE, then every value read from indexBuffer must be one of the values in
            // VkOpacityMicromapSpecialIndexEXT." (With VK_INDEX_TYPE_NONE_KHR the values are the triangle indices.)
            v.fail("VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-vkasSpecial",
                   "%s geometry %u: triangle %u uses micromap triangle %llu but the micromap is VK_NULL_HANDLE.",
                   where, g, i, (ull)index.triangle);
            return;
        }
        // "that triangle uses the opacity micromap information from micromap at that index plus baseTriangle":
        // the micromap must have that triangle.
        if (!v.check(index.triangle < triangles, "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-vkasIndex",
                     "%s geometry %u: triangle %u uses micromap triangle %llu (index plus baseTriangle %u) but the "
                     "micromap has %u triangles.",
                     where, g, i, (ull)index.triangle, omm.baseTriangle, triangles))
            return;
        ++used[{tris[index.triangle].format, tris[index.triangle].subdivisionLevel}];
    }
    HostMap<std::pair<uint32_t, uint32_t>, uint64_t> declared;
    forEachUsageCount(omm, [&](const VkMicromapUsageEXT& u) {
        if (u.count) declared[{u.format, u.subdivisionLevel}] += u.count;
    });
    if (used != declared) {
        auto firstDifference = [&]() -> std::pair<std::pair<uint32_t, uint32_t>, std::pair<uint64_t, uint64_t>> {
            for (const auto& [key, n] : used)
                if (auto it = declared.find(key); it == declared.end() || it->second != n)
                    return {key, {n, it == declared.end() ? 0 : it->second}};
            for (const auto& [key, n] : declared)
                if (!used.count(key)) return {key, {0, n}};
            return {};
        };
        const auto [key, counts] = firstDifference();
        v.fail("VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-pUsageCounts-vkasCounts",
               "%s geometry %u: %llu triangles use micromap triangles of format %u and subdivision level %u, but the "
               "usage counts give %llu.",
               where, g, (ull)counts.first, key.first, key.second, (ull)counts.second);
    }
}

void checkOpacityMicromapUpdate(Validator& v, const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                const VkAccelerationStructureBuildRangeInfoKHR* ranges, const std::byte* src,
                                const char* where) {
    const format::Header* h = format::header(src);
    if (!updateRewritesMicromaps(*h)) return;
    // "[The application must not] Remove micromaps or VkOpacityMicromapSpecialIndexKHR values from a geometry which
    // previously had them, or vice versa": vkas holds every geometry to it, the triangles' records ask for them.
    if (!v.check(opacityPresenceMatches(info, src), "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-vkasPresence",
                 "%s: the geometries with an opacity micromap are not those of the source's last build.", where))
        return;
    if (h->buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT) {
        // "the application must provide a micromap matching the original micromap in structure with only opacity values
        // updated": no change "between use of VkOpacityMicromapSpecialIndexKHR values and explicit micro-map triangles",
        // nor of "the subdivision level or format of the micromap triangle associated with any acceleration-structure
        // triangle".
        for (uint32_t g = 0; g < info.geometryCount; ++g) {
            const auto& geom = buildGeometry(info, g);
            const auto* omm = geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR ? opacityMicromapOf(geom.geometry.triangles)
                                                                                : nullptr;
            if (!omm) continue;
            const format::OpacityGeometry* og = format::opacityGeometry(src, g);
            const format::OpacityPrimitive* before = format::opacityPrimitives(og);
            const std::byte* block = omm->micromap ? resolveMicromap(uint64_t(omm->micromap)) : nullptr;
            for (uint32_t i = 0; i < og->primitiveCount && i < ranges[g].primitiveCount; ++i) {
                const OpacityIndex index = opacityIndexOf(*omm, i);
                bool same = index.special == format::isSpecialPrimitive(before[i]);
                if (same && !index.special && block) {
                    const format::MicromapTriangle& t = format::micromapTriangles(block)[index.triangle];
                    same = t.format == before[i].format && t.subdivisionLevel == before[i].subdivisionLevel;
                }
                if (!v.check(same, "VUID-VkAccelerationStructureTrianglesOpacityMicromapEXT-micromap-vkasDataUpdate",
                             "%s geometry %u: triangle %u changes its opacity micromap's structure (special index, "
                             "subdivision level or format) in an ALLOW_OPACITY_MICROMAP_DATA_UPDATE update.",
                             where, g, i))
                    return;
            }
        }
    }
    const uint64_t size = opacitySectionSize(info, ranges, resolveMicromap);
    if (!v.check(size != UINT64_MAX && size <= h->opacityReserved, "VUID-vkBuildAccelerationStructuresKHR-pInfos-10126",
                 "%s: the update's opacity micromaps take %llu bytes, but the structure's build kept %llu for them.",
                 where, (ull)size, (ull)h->opacityReserved))
        return;
}

}  // namespace vkas
