// [EXT-OMM] Writes the opacity-micromap section of a bottom level of triangles (format/opacity_section.hpp) from
// the VkAccelerationStructureTrianglesOpacityMicromapEXT structures of its geometries and the micromaps they name.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/micromap_layout.hpp"
#include "engine/format/opacity_section.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"

namespace vkas {

// Whether any triangle geometry of `info` has an opacity micromap.
bool hasOpacityMicromaps(const VkAccelerationStructureBuildGeometryInfoKHR& info);

// Bytes the section of `geometryCount` geometries can take at most when geometry g has an opacity micromap
// (`omm`, or nullptr) and `primitiveCount` triangles: the usage counts bound the micromap triangles it copies ("For
// a given format and subdivisionLevel the number of triangles in this geometry matching those values after
// indirection and special index handling must be equal to the sum of matching count provided").
uint64_t opacityGeometryBound(const TrianglesOpacityMicromap* omm, uint64_t primitiveCount);
template <class CountAt>
uint64_t opacitySectionBound(const VkAccelerationStructureBuildGeometryInfoKHR& info, const CountAt& primitiveCountOf) {
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR || !hasOpacityMicromaps(info)) return 0;
    uint64_t bytes = format::alignOpacity(8ull * info.geometryCount) + 8;  // the directory, and the section's alignment
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR) continue;
        bytes += opacityGeometryBound(opacityMicromapOf(geom.geometry.triangles), primitiveCountOf(g));
    }
    return bytes;
}

// Writes the section at base + offset: returns its size, or UINT64_MAX (nothing usable written) when a micromap
// does not resolve, an index is past its micromap's triangles, a NULL micromap meets a non-special index, or the
// section would pass `capacity` bytes. Validation reports each of these first (api/validate/opacity_micromaps.cpp).
uint64_t writeOpacitySection(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                             const VkAccelerationStructureBuildRangeInfoKHR* ranges, MicromapResolver resolve,
                             std::byte* base, uint64_t offset, uint64_t capacity);

// The size writeOpacitySection would write, without writing (UINT64_MAX where it would fail).
uint64_t opacitySectionSize(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                            const VkAccelerationStructureBuildRangeInfoKHR* ranges, MicromapResolver resolve);

// Whether an update of the structure `block` copies its micromaps again: it has some, and its build allowed
// ALLOW_OPACITY_MICROMAP_UPDATE or ALLOW_OPACITY_MICROMAP_DATA_UPDATE (without either, the copy is kept).
inline bool updateRewritesMicromaps(const format::Header& h) {
    return h.opacityOffset != 0 && (h.buildFlags & (VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT |
                                                    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_DATA_UPDATE_EXT));
}

// Whether the geometries of `info` that have an opacity micromap are exactly those of `block`'s section: what an
// update that rewrites the section needs (its triangle records keep asking their geometry's micromap).
bool opacityPresenceMatches(const VkAccelerationStructureBuildGeometryInfoKHR& info, const std::byte* block);

}  // namespace vkas
