// The one walk over a Vulkan pNext chain: the structure of a given sType, or null.
#pragma once

#include <vulkan/vulkan_core.h>

namespace vkas {

inline const void* findInChain(const void* pNext, VkStructureType sType) {
    for (auto* s = static_cast<const VkBaseInStructure*>(pNext); s; s = s->pNext)
        if (s->sType == sType) return s;
    return nullptr;
}

template <class T>
const T* findInChain(const void* pNext, VkStructureType sType) {
    return static_cast<const T*>(findInChain(pNext, sType));
}

}  // namespace vkas
