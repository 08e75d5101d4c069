// The kinds of primitive a structure can hold, and what a build and an update need of each. Everything specific to
// one kind (how its inputs become records and boxes, how an update re-reads them, which inputs are active) lives in
// one file of this folder; this table is the only place that lists them. Adding a kind: its file, its entry in
// kind_table.cpp, its reader in input/ and its intersection test in trace/.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/assemble/refit.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/builders/tree_builder.hpp"
#include "engine/format/layout.hpp"
#include "vkas/vkas_compat.h"

namespace vkas {

struct PrimitiveKind {
    // Reads the active primitives of the build's inputs into temp[] (records of recordSize bytes) and refs[] (their
    // boxes, refs[j].index naming the temp slot); returns how many. Inactive and invalid primitives are left out
    // (they still count in primitive indices).
    uint32_t (*gather)(const BuildJob& job, PrimRef* refs, std::byte* temp);
    // Refits job.src into job.dst (assemble/refit.hpp: shape and size already checked).
    void (*refit)(const RefitJob& job);
    // VUIDs 03663 / 03664 for this kind (assemble/refit.hpp, checkUpdateActivity).
    ActivityViolation (*checkActivity)(const RefitJob& job);
};

// The kind of a structure: a top level (motion or not) or a bottom level of the given VkGeometryTypeKHR (motion
// matters for triangles only; any other type value is read as triangles).
const PrimitiveKind& primitiveKind(bool topLevel, uint32_t primitiveType, bool motion);

// The kinds, one file each.
extern const PrimitiveKind kTriangleKind, kMotionTriangleKind, kAabbKind, kSphereKind, kLssKind, kInstanceKind,
    kMotionInstanceKind;

// The record flags of a geometry's VkGeometryFlagsKHR: the same bits for every bottom-level kind (layout.hpp).
inline uint32_t recordFlags(VkGeometryFlagsKHR flags) {
    uint32_t f = 0;
    if (flags & VK_GEOMETRY_OPAQUE_BIT_KHR) f |= format::kTriangleOpaque;
    if (flags & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR) f |= format::kTriangleNoDuplicateAnyHit;
    return f;
}

// Whether a build keeps degenerate primitives (zero area or radius): only ALLOW_UPDATE builds, because an update
// may give them a size again (spec digest 5).
inline bool keepsDegenerate(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    return (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) != 0;
}

}  // namespace vkas
