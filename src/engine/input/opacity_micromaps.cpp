#include "engine/input/opacity_micromaps.hpp"

#include "engine/util/math.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas {

const TrianglesOpacityMicromap* opacityMicromapOf(const VkAccelerationStructureGeometryTrianglesDataKHR& triangles) {
    return findInChain<TrianglesOpacityMicromap>(triangles.pNext,
                                                 VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT);
}

OpacityIndex opacityIndexOf(const TrianglesOpacityMicromap& omm, uint32_t triangle) {
    const auto* base = static_cast<const std::byte*>(omm.indexBuffer.hostAddress);
    uint32_t value = triangle;
    uint32_t specialLimit = 0xFFFF'FFFFu - 3;  // the unsigned cast of -4 in 32 bits
    if (omm.indexType == VK_INDEX_TYPE_UINT16) {
        value = loadUnaligned<uint16_t>(base + uint64_t(triangle) * omm.indexStride);
        specialLimit = 0xFFFFu - 3;  // ... and in 16 bits
    } else if (omm.indexType == VK_INDEX_TYPE_UINT32) {
        value = loadUnaligned<uint32_t>(base + uint64_t(triangle) * omm.indexStride);
    }
    if (omm.indexType != VK_INDEX_TYPE_NONE_KHR && value >= specialLimit) {
        const uint32_t k = (omm.indexType == VK_INDEX_TYPE_UINT16 ? 0xFFFFu : 0xFFFF'FFFFu) - value;  // 0 .. 3
        return {true, -1 - int32_t(k), 0};
    }
    return {false, 0, uint64_t(value) + omm.baseTriangle};
}

const VkMicromapUsageEXT* usageCountAt(const TrianglesOpacityMicromap& omm, uint32_t i) {
    if (omm.pUsageCounts) return omm.pUsageCounts + i;
    return omm.ppUsageCounts ? omm.ppUsageCounts[i] : nullptr;
}

}  // namespace vkas
