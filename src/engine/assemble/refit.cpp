#include "engine/assemble/refit.hpp"

#include <cstring>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/opacity_section_build.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/motion.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/util/math.hpp"

namespace vkas {

using namespace format;

namespace {

const PrimitiveKind& kindOf(const Header* h) {
    return primitiveKind(h->type == uint32_t(StructureType::TopLevel), h->primitiveType,
                         motion::isMotionBuild(h->buildFlags));
}

}  // namespace

bool refitShapeMatches(const RefitJob& job) {
    const Header* h = header(job.src);
    const auto& info = *job.info;
    if (h->magic != kMagic || h->version != kVersion) return false;
    if (h->type != uint32_t(structureTypeOf(info.type))) return false;
    if (h->geometryCount != info.geometryCount) return false;
    if (motion::isMotionBuild(h->buildFlags) != motion::isMotionBuild(info.flags)) return false;
    if (info.geometryCount != 0 && !info.pGeometries && !info.ppGeometries) return false;
    const GeometryDesc* descs = geometries(job.src);
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        if (descs[g].geometryType != uint32_t(buildGeometry(info, g).geometryType)) return false;
        if (descs[g].primitiveCount != job.ranges[g].primitiveCount) return false;
    }
    return true;
}

VkResult refitAccelerationStructure(const RefitJob& job) {
    if (!refitShapeMatches(job)) return VK_ERROR_UNKNOWN;
    const Header* h = header(job.src);
    if (h->usedSize > job.dstSize) return VK_ERROR_UNKNOWN;
    const bool rewritesMicromaps = updateRewritesMicromaps(*h);
    // Lay out the new micromap section before anything is written: an update that cannot hold it changes nothing.
    if (rewritesMicromaps && (!opacityPresenceMatches(*job.info, job.src) ||
                              opacitySectionSize(*job.info, job.ranges, job.micromaps) > h->opacityReserved))
        return VK_ERROR_UNKNOWN;
    const uint64_t opacityOffset = h->opacityOffset, opacityReserved = h->opacityReserved;
    kindOf(h).refit(job);
    // [EXT-OMM] "If the original acceleration structure was built using opacity micromaps and
    // VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_BIT_KHR was set in flags, the application must
    // provide a micromap to the update operation" (with ALLOW_OPACITY_MICROMAP_DATA_UPDATE_BIT_EXT, "a micromap
    // matching the original micromap in structure with only opacity values updated"): the section is copied again
    // from it. Without either flag the application provides the original micromap, whose copy the structure holds.
    if (rewritesMicromaps) {
        const uint64_t written =
            writeOpacitySection(*job.info, job.ranges, job.micromaps, job.dst, opacityOffset, opacityReserved);
        std::memset(job.dst + opacityOffset + written, 0, opacityReserved - written);
    }
    return VK_SUCCESS;
}

uint32_t referencedIndexHash(const VkAccelerationStructureGeometryTrianglesDataKHR& triangles,
                             const VkAccelerationStructureBuildRangeInfoKHR& range) {
    if (triangles.indexType != VK_INDEX_TYPE_UINT16 && triangles.indexType != VK_INDEX_TYPE_UINT32) return 0;
    if (!triangles.indexData.hostAddress) return 0;
    const auto* p = static_cast<const std::byte*>(triangles.indexData.hostAddress) + range.primitiveOffset;
    const uint64_t n = 3ull * range.primitiveCount;
    uint64_t hash = 0x9E37'79B9'7F4A'7C15ull ^ n;
    if (triangles.indexType == VK_INDEX_TYPE_UINT16) {
        for (uint64_t k = 0; k < n; ++k) hash = (hash ^ loadUnaligned<uint16_t>(p + 2 * k)) * 0x0000'0100'0000'01B3ull;
    } else {
        for (uint64_t k = 0; k < n; ++k) hash = (hash ^ loadUnaligned<uint32_t>(p + 4 * k)) * 0x0000'0100'0000'01B3ull;
    }
    hash ^= hash >> 33;
    hash *= 0xFF51'AFD7'ED55'8CCDull;
    hash ^= hash >> 33;
    return uint32_t(hash ^ (hash >> 32));
}

ActivityViolation checkUpdateActivity(const RefitJob& job) { return kindOf(header(job.src)).checkActivity(job); }

}  // namespace vkas
