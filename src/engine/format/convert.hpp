// Loading blocks written by an earlier release: format 1 (docs/FORMAT.md, "Format 1") becomes format 2 on load.
// Only bottom levels of triangles without motion change shape (48-byte TriangleRecords become triangle leaves, so the
// block shrinks: 44 bytes a triangle and a 4-byte tail); every other block keeps its bytes and gets version 2. The
// tree, the geometry table and every other record are kept, so a converted structure visits the same nodes and leaves
// in the same order and tests the same triangles with the same positions: it reports the same hits.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vkas::format {

// The used size of the format-2 block that `block` (a checked block of format 1 or 2) becomes.
uint64_t convertedSize(const std::byte* block);

// Writes the format-2 form of `src` (a block that format::checkBlock accepted) to `dst` (convertedSize(src) bytes,
// not overlapping src). A block of format 2 is copied as it is.
void convertToCurrentFormat(const std::byte* src, std::byte* dst);

}  // namespace vkas::format
