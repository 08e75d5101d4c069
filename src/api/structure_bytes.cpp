#include "api/structure_bytes.hpp"

#include <algorithm>
#include <cstring>

#include "engine/format/layout.hpp"
#include "engine/format/serialize.hpp"
#include "engine/util/byte_io.hpp"

namespace vkas {

bool rangesOverlap(uintptr_t a, uint64_t aSize, uintptr_t b, uint64_t bSize) {
    return aSize != 0 && bSize != 0 && a < b + bSize && b < a + aSize;
}

uint64_t blobExtent(const void* src) {
    return std::max<uint64_t>(serial::kHeaderSize,
                              load64(static_cast<const std::byte*>(src) + serial::kSerializedSizeOffset));
}

const std::byte* constructedBlock(const AccelerationStructure& as) {
    const std::byte* block = as.block();
    if (!as.constructed || !block || as.size < sizeof(format::Header)) return nullptr;
    format::Header h;
    std::memcpy(&h, block, sizeof h);
    if (h.magic != format::kMagic || h.usedSize < sizeof h || h.usedSize > as.size) return nullptr;
    return block;
}


uint64_t SerializedReferences::toReference(uint64_t value) {
    if (value == 0) return 0;
    if (!indexed_) {
        byAddress_ = device_.bottomLevelsByAddress();
        indexed_ = true;
    }
    // Spec (vkCopyMemoryToAccelerationStructureKHR): the data must have "any acceleration structure handles filled
    // in with the newly-queried handles to bottom level acceleration structures created before deserialization.
    // These do not need to be built at deserialize time, but must be created." The loaded instance stores the
    // structure's handle, so it traces whatever that structure holds once it is built.
    if (auto it = byAddress_.find(value); it != byAddress_.end()) return reinterpret_cast<uint64_t>(it->second);
    if (layout_ == serial::Layout::V1) {
        const auto* as = device_.live<AccelerationStructure>(reinterpret_cast<const void*>(value),
                                                            ObjectMagic::AccelerationStructure);
        if (as && as->type != VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return value;
    }
    return 0;
}

}  // namespace vkas
