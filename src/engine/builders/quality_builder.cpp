#include "engine/builders/quality_builder.hpp"

#include "engine/builders/binary_tree.hpp"
#include "engine/builders/sah_builder.hpp"
#include "engine/builders/wide_collapse.hpp"

namespace vkas {

uint64_t qualityWorkspacePerPrimitive() { return sizeof(PrimRef) + 2 * (sizeof(BinaryNode) + sizeof(CollapseEntry)); }

BvhBuildResult buildQualityBvh(PrimRef* refs, uint32_t n, const BvhBuildSettings& settings, format::Node* nodes,
                               std::byte* workspace, const ParallelFor* parallel) {
    if (n == 0) return {};
    // Workspace: the spare PrimRefs, 2n binary nodes, 2n collapse entries (quality_builder.hpp).
    auto* spare = reinterpret_cast<PrimRef*>(workspace);
    auto* binary = reinterpret_cast<BinaryNode*>(spare + n);
    auto* table = reinterpret_cast<CollapseEntry*>(binary + 2 * uint64_t(n));
    const uint32_t binaryCount = buildBinarySahTree(refs, n, settings, binary, spare, parallel);
    const CollapseResult wide = collapseToWide(binary, binaryCount, refs, n, settings.maxLeafSize, CollapseCosts{},
                                               table, spare, nodes);
    if (wide.ok) return wide.tree;
    BvhBuildSettings fallback = settings;
    fallback.builder = TreeBuilder::Sah;
    return buildSahBvh(refs, n, fallback, nodes, workspace, parallel);
}

}  // namespace vkas
