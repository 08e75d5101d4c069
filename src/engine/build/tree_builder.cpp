#include "engine/build/tree_builder.hpp"

#include <vulkan/vulkan_core.h>

#include "engine/build/morton_builder.hpp"
#include "engine/build/quality_builder.hpp"
#include "engine/build/sah_builder.hpp"
#include "engine/build/spatial_split_builder.hpp"

namespace vkas {

BvhBuildSettings buildSettingsFor(uint32_t maxLeafSize, uint32_t buildFlags) {
    BvhBuildSettings s{maxLeafSize};
    if (buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR) s.morton = true;
    if ((buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) ||
        maxLeafSize == format::kMaxInstancesPerLeaf)
        s.fewBinsBelow = 0;
    if ((buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) && !s.morton) s.quality = true;
    if (!s.morton && !s.quality && maxLeafSize != format::kMaxInstancesPerLeaf) s.binSampleTarget = kDefaultBinSampleTarget;
    return s;
}

uint64_t treeWorkspacePerPrimitive(const BvhBuildSettings& settings) {
    if (settings.quality && settings.splitBudget != 0) return spatialSplitWorkspacePerPrimitive();
    return settings.quality ? qualityWorkspacePerPrimitive() : kTreeWorkspacePerPrimitive;
}

BvhBuildResult buildTree(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                         std::byte* workspace, const ParallelFor* parallel) {
    if (settings.morton) return buildMortonBvh(refs, n, settings.maxLeafSize, nodes, workspace, parallel);
    if (settings.quality && settings.splitBudget != 0 && settings.triangles)
        return buildSpatialSplitBvh(refs, n, settings, nodes, workspace, parallel);
    if (settings.quality) return buildQualityBvh(refs, n, settings, nodes, workspace, parallel);
    return buildSahBvh(refs, n, settings, nodes, workspace, parallel);
}

}  // namespace vkas
