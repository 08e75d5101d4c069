#include "sah.hpp"

#include <cstring>

namespace vb {
namespace {

template <class T>
T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// Box of slot `s` of the node at `node` (SoA: lowerX, upperX, lowerY, upperY, lowerZ, upperZ, 8 floats each).
Box slotBox(const unsigned char* node, int s) {
    Box b;
    for (int k = 0; k < 3; ++k) {
        b.lo[k] = load<float>(node + 64 * k + 4 * s);
        b.hi[k] = load<float>(node + 64 * k + 32 + 4 * s);
    }
    return b;
}

}  // namespace

SahCost vkasSah(const unsigned char* block) {
    SahCost c;
    const uint64_t root = load<uint64_t>(block + 24);
    Box bounds;
    for (int k = 0; k < 3; ++k) bounds.lo[k] = load<float>(block + 32 + 4 * k), bounds.hi[k] = load<float>(block + 44 + 4 * k);
    c.rootArea = bounds.area();
    const uint64_t nodeOffset = load<uint64_t>(block + 80);
    auto kind = [](uint64_t ref) { return unsigned(ref >> 62); };
    auto leafCount = [](uint64_t ref) { return size_t((ref >> 40) & 0xFF); };
    if (root == 0) return c;
    if (kind(root) == 2) {
        c.leaf(c.rootArea, leafCount(root));
        return c;
    }
    std::vector<uint32_t> stack{uint32_t(root & 0xFFFFFFFFu)};
    while (!stack.empty()) {
        const unsigned char* node = block + nodeOffset + 256 * uint64_t(stack.back());
        stack.pop_back();
        Box nodeBox;
        for (int s = 0; s < 8; ++s) {
            const uint64_t ref = load<uint64_t>(node + 192 + 8 * s);
            if (ref == 0) continue;
            const Box b = slotBox(node, s);
            nodeBox.grow(b);
            if (kind(ref) == 1) stack.push_back(uint32_t(ref & 0xFFFFFFFFu));
            else if (kind(ref) == 2) c.leaf(b.area(), leafCount(ref));
        }
        c.node(nodeBox.area());
    }
    return c;
}

}  // namespace vb
