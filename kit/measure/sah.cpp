#include "sah.hpp"

#include <cstddef>
#include <cstring>

#include "engine/format/inspect.hpp"  // the one reader of the format: its tree walk and SAH

namespace vb {

SahCost vkasSah(const unsigned char* block) {
    // A structure vkas built, mapped whole: its header says how far it reaches.
    vkas::format::Header h;
    std::memcpy(&h, block, sizeof h);
    vkas::format::TreeInspection in;
    SahCost c;
    if (vkas::format::inspectTree(reinterpret_cast<const std::byte*>(block), h.usedSize, in)) return c;  // unreadable: 0
    c.nodes = in.sahNodes, c.leaves = in.sahLeaves, c.rootArea = in.rootArea;
    c.nodeCount = in.internalNodes, c.leafCount = in.leaves, c.references = in.references;
    return c;
}

}  // namespace vb
