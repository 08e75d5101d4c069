#include "api/validate/parameters.hpp"

#include "api/deferred_operation.hpp"

namespace vkas {

const char* objectTypeName(ObjectMagic magic) {
    switch (magic) {
        case ObjectMagic::Memory: return "VkDeviceMemory";
        case ObjectMagic::Buffer: return "VkBuffer";
        case ObjectMagic::AccelerationStructure: return "VkAccelerationStructureKHR";
        case ObjectMagic::DeferredOperation: return "VkDeferredOperationKHR";
        case ObjectMagic::Micromap: return "VkMicromapEXT";
        default: return "object";
    }
}

void checkDestroyAllocator(Validator& v, const VkAllocationCallbacks& created, const VkAllocationCallbacks* given,
                           const char* withVuid, const char* withoutVuid) {
    if (created.pfnAllocation)
        v.check(given != nullptr && given->pfnFree == created.pfnFree, withVuid,
                "the object was created with VkAllocationCallbacks but pAllocator %s.",
                given ? "has another pfnFree" : "is NULL");
    else
        v.check(given == nullptr, withoutVuid,
                "the object was created without VkAllocationCallbacks but pAllocator is not NULL.");
}

void checkNextChain(Validator& v, const void* pNext, std::initializer_list<VkStructureType> allowed,
                    const char* pNextVuid, const char* uniqueVuid, const char* name) {
    uint32_t seen = 0;  // bit i: allowed[i] was seen
    uint32_t depth = 0;
    for (auto* s = static_cast<const VkBaseInStructure*>(pNext); s; s = s->pNext) {
        if (++depth > 64) {  // a cycle, or a chain no application builds
            v.fail(pNextVuid, "%s: the pNext chain is longer than 64 structures (a cycle?).", name);
            return;
        }
        uint32_t i = 0;
        for (VkStructureType t : allowed) {
            if (t == s->sType) break;
            ++i;
        }
        if (i == allowed.size()) {
            v.fail(pNextVuid, "%s: the pNext chain holds a structure with sType %d, which vkas does not accept there.",
                   name, int(s->sType));
            continue;
        }
        if (seen & (1u << i)) {
            if (uniqueVuid)
                v.fail(uniqueVuid, "%s: the pNext chain holds two structures with sType %d.", name, int(s->sType));
        }
        seen |= 1u << i;
    }
}

void checkDeferredOperation(Validator& v, const Device& device, VkDeferredOperationKHR operation,
                            const DeferredOperationVuids& vuids) {
    if (operation == VK_NULL_HANDLE) return;
    if (auto* op = checkHandle<DeferredOperation>(v, device, operation, ObjectMagic::DeferredOperation,
                                                  vuids.parameter, vuids.parent, "deferredOperation"))
        v.check(!op->pending(), vuids.pending,
                "deferredOperation still has a deferred command pending: join it until it completes first.");
}

}  // namespace vkas
