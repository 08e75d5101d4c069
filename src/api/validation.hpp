// Reports valid-usage violations the way the Khronos validation layers do: one message per violated rule,
// severity ERROR, type VALIDATION, pMessageIdName = the full VUID. A command that found a violation does
// nothing else and returns VK_ERROR_VALIDATION_FAILED_EXT.
#pragma once

#include <cstdint>
#include <initializer_list>

#include "api/device.hpp"

namespace vkas {

class Validator {
public:
    Validator(const Device* device, const char* command);

    bool enabled() const { return enabled_; }
    bool failed() const { return failures_ != 0; }
    uint32_t failureCount() const { return failures_; }

    // Reports `vuid` with a printf-style message naming the offending info, geometry and value.
    void fail(const char* vuid, const char* format, ...) __attribute__((format(printf, 3, 4)));
    // Checks `ok`; reports when it is false. Returns ok.
    template <class... Args>
    bool check(bool ok, const char* vuid, const char* format, Args... args) {
        if (!ok) {
            if constexpr (sizeof...(Args) == 0)
                fail(vuid, "%s", format);  // a message without arguments is printed as is
            else
                fail(vuid, format, args...);
        }
        return ok;
    }

private:
    const Device* device_;
    const char* command_;
    bool enabled_;
    uint32_t failures_ = 0;
};

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

}  // namespace vkas
