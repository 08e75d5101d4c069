#include "engine/assemble/size_query.hpp"

#include "engine/builders/tree_builder.hpp"
#include "engine/format/sizes.hpp"
#include "engine/input/build_inputs.hpp"

namespace vkas {

uint64_t gatheredRecordSize(format::StructureType type, bool motion) {
    if (type == format::StructureType::TopLevel)
        return motion ? sizeof(format::MotionInstanceRecord) : sizeof(format::InstanceRecord);
    return motion ? sizeof(format::MotionTriangleRecord) : sizeof(format::TriangleRecord);
}

BvhBuildSettings structureBuildSettings(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                        uint64_t primitiveCount) {
    const format::StructureType type = structureTypeOf(uint32_t(info.type));  // (the enum's values are Vulkan's)
    BvhBuildSettings settings = buildSettingsFor(maxLeafSize(type), info.flags);
    if (settings.builder == TreeBuilder::Quality && usesSpatialSplits(type, recordPrimitiveType(info), usesMotionRecords(info), info.flags))
        settings.splitBudget = uint32_t(spatialSplitBudget(primitiveCount));
    return settings;
}

StructureSizes structureSizes(const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t primitiveCount) {
    const format::StructureType type = structureTypeOf(uint32_t(info.type));  // (the enum's values are Vulkan's)
    const bool motion = usesMotionRecords(info);
    const BvhBuildSettings settings = structureBuildSettings(info, primitiveCount);
    StructureSizes s;
    s.structureSize =
        maxStructureSize(type, recordPrimitiveType(info), info.geometryCount, primitiveCount, motion, info.flags);
    s.buildScratchSize = primitiveCount == 0
                             ? 0
                             : kScratchAlignment + primitiveCount * (sizeof(PrimRef) + gatheredRecordSize(type, motion) +
                                                                     treeWorkspacePerPrimitive(settings));
    s.updateScratchSize = 0;  // a refit works in the structure itself (assemble/refit.hpp)
    return s;
}

std::byte* alignedScratch(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    auto p = reinterpret_cast<uintptr_t>(info.scratchData.hostAddress);
    p = (p + kScratchAlignment - 1) & ~uintptr_t(kScratchAlignment - 1);
    return reinterpret_cast<std::byte*>(p);
}

}  // namespace vkas
