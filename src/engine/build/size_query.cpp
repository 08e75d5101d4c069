#include "engine/build/size_query.hpp"

#include "engine/build/tree_builder.hpp"
#include "engine/format/sizes.hpp"

namespace vkas {

StructureSizes structureSizes(format::StructureType type, uint32_t geometryCount, uint64_t primitiveCount,
                              bool motion) {
    StructureSizes s;
    s.structureSize = maxStructureSize(type, geometryCount, primitiveCount, motion);
    s.buildScratchSize =
        primitiveCount == 0 ? 0 : kScratchAlignment + primitiveCount * (sizeof(PrimRef) + recordSize(type, motion));
    s.updateScratchSize = 0;  // a refit works in the structure itself (build/refit.hpp)
    return s;
}

std::byte* alignedScratch(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    auto p = reinterpret_cast<uintptr_t>(info.scratchData.hostAddress);
    p = (p + kScratchAlignment - 1) & ~uintptr_t(kScratchAlignment - 1);
    return reinterpret_cast<std::byte*>(p);
}

}  // namespace vkas
