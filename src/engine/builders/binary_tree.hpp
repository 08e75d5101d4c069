// The binary BVH that PREFER_FAST_TRACE builds first (quality_builder.hpp): the binned SAH splits it down to single
// primitives (sah_builder.hpp), and an optimal collapse turns it into 8-wide nodes (wide_collapse.hpp). It lives in the build's scratch memory, 2n - 1 nodes for n primitives.
#pragma once

#include <cstdint>

#include "engine/util/math.hpp"

namespace vkas {

struct BinaryNode {
    static constexpr uint32_t kNone = 0xFFFF'FFFFu;
    float lower[3];
    float upper[3];
    // An internal node's children; a leaf has child[1] == kNone and child[0] the position of its one primitive's
    // PrimRef in the builder's array.
    uint32_t child[2];
    uint32_t parent;     // kNone at the root
    uint32_t primCount;  // primitives in the subtree

    bool isLeaf() const { return child[1] == kNone; }
    float halfArea() const {
        const float dx = upper[0] - lower[0], dy = upper[1] - lower[1], dz = upper[2] - lower[2];
        return dx * dy + dy * dz + dz * dx;
    }
    void setBox(const Aabb& b) {
        lower[0] = b.lower.x, lower[1] = b.lower.y, lower[2] = b.lower.z;
        upper[0] = b.upper.x, upper[1] = b.upper.y, upper[2] = b.upper.z;
    }
};
static_assert(sizeof(BinaryNode) == 40);

// The box of a and b together; a NaN coordinate spreads, as in the builders' boxes (SimdBoxNanSpreads).
inline void unionBox(const BinaryNode& a, const BinaryNode& b, float lower[3], float upper[3]) {
    for (int k = 0; k < 3; ++k) {
        lower[k] = a.lower[k] < b.lower[k] ? a.lower[k] : b.lower[k];
        upper[k] = a.upper[k] > b.upper[k] ? a.upper[k] : b.upper[k];
        if (a.lower[k] != a.lower[k] || b.lower[k] != b.lower[k]) lower[k] = a.lower[k] + b.lower[k];
        if (a.upper[k] != a.upper[k] || b.upper[k] != b.upper[k]) upper[k] = a.upper[k] + b.upper[k];
    }
}

}  // namespace vkas
