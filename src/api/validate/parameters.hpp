// The parameter rules every command shares: handles (-parameter, -parent, -commonparent), the allocator of a
// vkDestroy*, pNext chains, and the deferredOperation of a deferrable command.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <initializer_list>

#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// The Vulkan type name of an object magic, for messages.
const char* objectTypeName(ObjectMagic magic);

// The live object of type T that `handle` names on `device`, or nullptr after reporting why not: `parameterVuid`
// when no live object of that type has the handle (unknown, destroyed or of another type), `parentVuid` when it
// belongs to another device (`parameterVuid` again when the rule has no -parent VUID). `name` is the parameter, as
// the message shows it ("pInfo->src"). The handle is looked up in the registry before it is dereferenced.
template <class T>
T* checkHandle(Validator& v, const Device& device, const void* handle, ObjectMagic magic, const char* parameterVuid,
               const char* parentVuid, const char* name) {
    const Device* owner = Device::ownerOf(handle);
    T* object = owner ? static_cast<T*>(const_cast<void*>(handle)) : nullptr;
    if (!object || object->magic != magic) {
        v.fail(parameterVuid, "%s (0x%llx) is not a live %s.", name,
               static_cast<unsigned long long>(reinterpret_cast<uintptr_t>(handle)), objectTypeName(magic));
        return nullptr;
    }
    if (owner != &device) {
        v.fail(parentVuid ? parentVuid : parameterVuid, "%s (0x%llx) was created from another VkDevice.", name,
               static_cast<unsigned long long>(reinterpret_cast<uintptr_t>(handle)));
        return nullptr;
    }
    return object;
}

// The allocator rules of vkDestroy*: callbacks given at creation need (compatible) callbacks at destruction
// (`withVuid`); none at creation need NULL (`withoutVuid`). `created` is what the object kept (zero: none).
void checkDestroyAllocator(Validator& v, const VkAllocationCallbacks& created, const VkAllocationCallbacks* given,
                           const char* withVuid, const char* withoutVuid);

// Checks a pNext chain whose structures must each be one of `allowed` (sType values), each at most once: reports
// `pNextVuid` for any other structure and `uniqueVuid` for a repeated one. `name` names the chain's owner.
void checkNextChain(Validator& v, const void* pNext, std::initializer_list<VkStructureType> allowed,
                    const char* pNextVuid, const char* uniqueVuid, const char* name);

// The deferredOperation VUIDs of one deferrable command.
struct DeferredOperationVuids {
    const char* parameter;  // -deferredOperation-parameter: a live VkDeferredOperationKHR
    const char* parent;     // -deferredOperation-parent: of this device
    const char* pending;    // -deferredOperation-03678: no deferred command still pending on it
};

// Checks a deferrable command's deferredOperation parameter. VK_NULL_HANDLE is always valid.
void checkDeferredOperation(Validator& v, const Device& device, VkDeferredOperationKHR operation,
                            const DeferredOperationVuids& vuids);

}  // namespace vkas
