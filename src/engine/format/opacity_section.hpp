// [EXT-OMM] The opacity micromaps of a bottom-level structure (docs/FORMAT.md, "Opacity micromaps").
//
// vkas copies what a geometry uses of its micromap into the structure at build time (so
// VkMicromapBuildSizesInfoEXT::discardable is VK_TRUE: "the information in the micromap will be copied by value into
// the acceleration structure, and the micromap can be destroyed after the acceleration structure build concludes").
// The section starts at Header::opacityOffset (8-byte aligned, inside usedSize):
//   u64 geometryBlock[geometryCount]      offset from the block start of the geometry's OpacityGeometry, 0 for none
// and each OpacityGeometry (8-byte aligned) is
//   OpacityGeometry | OpacityPrimitive[primitiveCount] | data[dataSize]
// where primitive i of the geometry (its primitive index, inactive ones included) reads its states at
// data + prims[i].dataOffset. The data starts with the four bytes 0, 1, 2, 3: a special index (-1 - k) is stored as a
// 4-state triangle of level 0 whose one state is k, at data offset k, which gives it exactly the special index's row
// of the spec's opacity table. The micromap triangles the geometry references follow, one copy each however many
// primitives share it, in order of first use.
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/micromap_layout.hpp"

namespace vkas::format {

struct OpacityGeometry {
    uint32_t primitiveCount;
    uint32_t reserved;
    uint64_t dataOffset;  // from the block start
    uint64_t dataSize;
};
static_assert(sizeof(OpacityGeometry) == 24);

// Where a primitive's states are: as a MicromapTriangle, with dataOffset relative to the geometry's data.
using OpacityPrimitive = MicromapTriangle;

// The special indices' states: VK_OPACITY_MICROMAP_SPECIAL_INDEX_FULLY_TRANSPARENT_EXT (-1) .. FULLY_UNKNOWN_OPAQUE
// (-4) read as the 4-state values 0 .. 3, the rows of the spec's table they share.
constexpr uint32_t kSpecialStateBytes = 4;
constexpr uint32_t specialState(int32_t specialIndex) { return uint32_t(-1 - specialIndex); }
constexpr bool isSpecialPrimitive(const OpacityPrimitive& p) { return p.dataOffset < kSpecialStateBytes; }

inline const uint64_t* opacityGeometryBlocks(const std::byte* base) {
    return reinterpret_cast<const uint64_t*>(base + header(base)->opacityOffset);
}
inline const OpacityGeometry* opacityGeometry(const std::byte* base, uint32_t geometryIndex) {
    return reinterpret_cast<const OpacityGeometry*>(base + opacityGeometryBlocks(base)[geometryIndex]);
}
inline const OpacityPrimitive* opacityPrimitives(const OpacityGeometry* g) {
    return reinterpret_cast<const OpacityPrimitive*>(g + 1);
}

constexpr uint64_t alignOpacity(uint64_t v) { return (v + 7) & ~uint64_t(7); }

}  // namespace vkas::format
