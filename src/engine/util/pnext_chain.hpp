// The one walk over a Vulkan pNext chain: every structure in order (forEachInChain), or the first of a given sType
// (findInChain).
#pragma once

#include <vulkan/vulkan_core.h>

namespace vkas {

// fn(structure) for each structure of the chain, in order. The chain's structures are the application's: `Base` is
// VkBaseInStructure for a chain vkas reads, VkBaseOutStructure for one it fills.
template <class Base = const VkBaseInStructure, class Next, class Fn>
void forEachInChain(Next* pNext, const Fn& fn) {
    for (auto* s = static_cast<Base*>(pNext); s; s = s->pNext) fn(s);
}

inline const void* findInChain(const void* pNext, VkStructureType sType) {
    for (auto* s = static_cast<const VkBaseInStructure*>(pNext); s; s = s->pNext)
        if (s->sType == sType) return s;
    return nullptr;  // (forEachInChain cannot stop early; this walk does)
}

template <class T>
const T* findInChain(const void* pNext, VkStructureType sType) {
    return static_cast<const T*>(findInChain(pNext, sType));
}

}  // namespace vkas
