#include "engine/builders/tree_builder.hpp"

#include <vulkan/vulkan_core.h>

#include "engine/builders/morton_builder.hpp"
#include "engine/builders/quality_builder.hpp"
#include "engine/builders/sah_builder.hpp"
#include "engine/builders/spatial_split_builder.hpp"

namespace vkas {

BvhBuildSettings buildSettingsFor(uint32_t maxLeafSize, uint32_t buildFlags) {
    BvhBuildSettings s{maxLeafSize};
    // PREFER_FAST_BUILD wins where an application sets both preferences.
    if (buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)
        s.builder = TreeBuilder::Morton;
    else if (buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR)
        s.builder = TreeBuilder::Quality;
    if ((buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) ||
        maxLeafSize == format::kMaxInstancesPerLeaf)
        s.fewBinsBelow = 0;
    if (s.builder == TreeBuilder::Sah && maxLeafSize != format::kMaxInstancesPerLeaf)
        s.binSampleTarget = kDefaultBinSampleTarget;
    return s;
}

uint64_t treeWorkspacePerPrimitive(const BvhBuildSettings& settings) {
    switch (settings.builder) {
        case TreeBuilder::Quality:
            return settings.splitBudget != 0 ? spatialSplitWorkspacePerPrimitive() : qualityWorkspacePerPrimitive();
        case TreeBuilder::Sah:
        case TreeBuilder::Morton: break;
    }
    return kTreeWorkspacePerPrimitive;
}

BvhBuildResult buildTree(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                         std::byte* workspace, const ParallelFor* parallel) {
    switch (settings.builder) {
        case TreeBuilder::Morton: return buildMortonBvh(refs, n, settings.maxLeafSize, nodes, workspace, parallel);
        case TreeBuilder::Quality:
            if (settings.splitBudget != 0 && settings.triangles)
                return buildSpatialSplitBvh(refs, n, settings, nodes, workspace, parallel);
            return buildQualityBvh(refs, n, settings, nodes, workspace, parallel);
        case TreeBuilder::Sah: break;
    }
    return buildSahBvh(refs, n, settings, nodes, workspace, parallel);
}

}  // namespace vkas
