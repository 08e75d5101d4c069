// The steps both traversal paths (the ray query, ray_query.cpp, and the batch kernel, batch_kernel_body.hpp) take
// alike, written once so that they visit the same structures and children in the same order and so report the same
// hit, ties included: which structure may be entered, which instances the ray flags skip, the order of the hit
// children of a node, and the traversal stack.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/trace/hit_rules.hpp"

namespace vkas {

// The header of `block` when it is a vkas structure of `type` with a tree to traverse; null otherwise (a null
// acceleration structure, an empty one, or bytes that are not a structure: every ray misses it).
inline const format::Header* traversableStructure(const std::byte* block, format::StructureType type) {
    if (!block) return nullptr;
    const format::Header* h = format::header(block);
    if (h->magic != format::kMagic || h->type != uint32_t(type) || h->root == format::kEmptyRef) return nullptr;
    return h;
}

// A bottom-level structure holds one primitive type, so the Skip ray flags cull whole instances: SkipAABBs those of
// AABBs, SkipTriangles (SkipBuiltinPrimitivesNV) those of triangles, spheres and LSS.
inline bool skippedByRayFlags(const format::Header& bottomLevel, uint32_t rayFlags) {
    const bool aabbs = bottomLevel.primitiveType == VK_GEOMETRY_TYPE_AABBS_KHR;
    return (rayFlags & (aabbs ? kRaySkipAabbs : kRaySkipTriangles)) != 0;
}

// Each wide level pushes at most 7 siblings; two levels (top and bottom) share the stack.
constexpr uint32_t kStackCapacity = 2 * ((format::kNodeWidth - 1) * format::kMaxTreeDepth + 1);

inline void pushChild(format::ChildRef* stackRef, float* stackDist, uint32_t& sp, format::ChildRef ref, float dist) {
    if (sp < kStackCapacity) {  // the depth bound of the format makes overflow impossible for valid data
        stackRef[sp] = ref;
        stackDist[sp] = dist;
        ++sp;
    }
}

// The children of `node` in `mask` (entry distances in entry[], from the node test) in the order a traversal
// pushes them: by descending entry distance, a later slot after an earlier one at equal distance, so the nearest
// is last (popped first). Returns their number.
//
// An empty slot (bounds +inf / -inf) never has a finite entry distance for a ray of finite origin and direction;
// for one with a NaN it may, and then its reference, kEmptyRef (0), is ordered like any other: a traversal pops it
// as neither a node nor a leaf, so no slot is tested for emptiness here.
inline uint32_t orderHitChildren(const format::Node& node, uint32_t mask, const float entry[format::kNodeWidth],
                                 format::ChildRef ref[format::kNodeWidth], float dist[format::kNodeWidth]) {
    if (mask == 0) return 0;
    const uint32_t first = uint32_t(__builtin_ctz(mask));
    const uint32_t rest = mask & (mask - 1);
    if (rest == 0) {  // one child: most nodes of an incoherent ray
        ref[0] = node.child[first];
        dist[0] = entry[first];
        return 1;
    }
    if ((rest & (rest - 1)) == 0) {  // two children: the later slot goes first only when strictly farther
        const uint32_t second = uint32_t(__builtin_ctz(rest));
        const bool swap = entry[first] < entry[second];
        const uint32_t a = swap ? second : first, b = swap ? first : second;
        ref[0] = node.child[a], dist[0] = entry[a];
        ref[1] = node.child[b], dist[1] = entry[b];
        return 2;
    }
    uint32_t hits = 0;
    // Only the children hit are visited, in slot order (bit scan), so the branches follow the hits, not the slots.
    for (; mask != 0; mask &= mask - 1) {
        const uint32_t i = uint32_t(__builtin_ctz(mask));
        const float tNear = entry[i];
        uint32_t k = hits++;  // insertion by descending distance
        while (k > 0 && dist[k - 1] < tNear) {
            dist[k] = dist[k - 1];
            ref[k] = ref[k - 1];
            --k;
        }
        dist[k] = tNear;
        ref[k] = node.child[i];
    }
    return hits;
}

}  // namespace vkas
