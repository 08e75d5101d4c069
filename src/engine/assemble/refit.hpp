// VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR: refit a structure to new inputs without changing its tree.
//
// The source's topology is kept: every node keeps its children, every record keeps its slot and the primitive it
// names (geometryIndex / primitiveIndex, or instanceId), and the record is re-fetched from the update's inputs the
// way a build fetches it. Node boxes are then recomputed bottom-up (nodes are numbered in preorder, so a reverse
// sweep sees every child before its parent) and the header's bounds become the root's. The refit reads the source
// only in [0, usedSize) and writes the destination only in [0, usedSize): a compacted structure (a byte copy of
// that range) updates like the original. It needs no scratch memory and no allocation (except the table of the
// micromap triangles an update of opacity micromaps copies); it runs on the calling thread, so its bytes never
// depend on threading. See docs/FORMAT.md, "Update (refit)".
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/format/micromap_layout.hpp"

namespace vkas {

struct RefitJob {
    const VkAccelerationStructureBuildGeometryInfoKHR* info;
    const VkAccelerationStructureBuildRangeInfoKHR* ranges;  // info->geometryCount entries
    const std::byte* src;                                     // the source block (may equal dst)
    std::byte* dst;                                           // the destination block
    uint64_t dstSize;                                         // bytes available at dst
    BlasResolver resolver;
    MicromapResolver micromaps = nullptr;  // [EXT-OMM] the micromaps an update that may change them names
};

// Whether the inputs have the source's shape: structure type, geometry count, each geometry's type and
// primitive count, and the motion flag. refitAccelerationStructure refuses (writes nothing) when they do not; the
// API layer reports the precise VUIDs first.
bool refitShapeMatches(const RefitJob& job);

// Refits job.src into job.dst (src == dst: in place). VK_ERROR_UNKNOWN, with nothing written, when the source is
// not a vkas structure, the shapes differ or dst is smaller than the source's usedSize.
VkResult refitAccelerationStructure(const RefitJob& job);

// A 32-bit hash of the index values an indexed triangle geometry reads (3 per primitive, before firstVertex is
// added), in order. A build with ALLOW_UPDATE stores it in GeometryDesc::indexHash so that an update can check
// VUID 03768 (the index values must not change) without a copy of the indices.
uint32_t referencedIndexHash(const VkAccelerationStructureGeometryTrianglesDataKHR& triangles,
                             const VkAccelerationStructureBuildRangeInfoKHR& range);

// VUIDs 03663 / 03664: an update must not make an active primitive (instance) inactive, nor an inactive one
// active. `vuid` is 3663 or 3664 for the first violation found (3663 in record order first, then 3664 in
// geometry / primitive order), 0 when there is none. Reads every input primitive once; allocates a bitmap of
// one bit per primitive. Call only after the shape and the ranges have passed validation.
struct ActivityViolation {
    uint32_t vuid = 0;
    uint32_t geometry = 0;
    uint32_t primitive = 0;
};
ActivityViolation checkUpdateActivity(const RefitJob& job);

}  // namespace vkas
