// The SAH cost, one formula for both engines' trees:
//   cost = ( sum over internal nodes n of A(n) * C_node  +  sum over leaves l of A(l) * |l| * C_prim ) / A(root)
// A = surface area of the box (an internal node's box is the union of its children's boxes), |l| = primitives
// referenced by the leaf (spatial-split duplicates counted), C_node = C_prim = 1. A node visit costs one C_node
// whatever its width: both trees here are 8-wide (vkas's nodes; Embree's user BVH built with branching factor 8).
#pragma once

#include "common.hpp"

namespace vb {

struct SahCost {
    double nodes = 0, leaves = 0, rootArea = 0;
    size_t nodeCount = 0, leafCount = 0, references = 0;
    void node(double area) { nodes += area, ++nodeCount; }
    void leaf(double area, size_t count) { leaves += area * double(count), ++leafCount, references += count; }
    double cost() const { return rootArea > 0 ? (nodes + leaves) / rootArea : 0; }
};

// The SAH cost of a vkas structure from its bytes, as engine/format/inspect.hpp reads them (the same walk and areas
// as `vkas inspect`).
SahCost vkasSah(const unsigned char* block);

}  // namespace vb
