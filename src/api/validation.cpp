#include "api/validation.hpp"

#include <cstdarg>
#include <cstdio>
#include <string>

namespace vkas {

namespace {
// The validation layers' MessageID: a 32-bit FNV-1a hash of the VUID string.
int32_t messageId(const char* vuid) {
    uint32_t h = 2166136261u;
    for (const char* p = vuid; *p; ++p) h = (h ^ uint8_t(*p)) * 16777619u;
    return int32_t(h);
}
}  // namespace

Validator::Validator(const Device* device, const char* command)
    : device_(device), command_(command), enabled_(!device || device->validationEnabled()) {}

void Validator::fail(const char* vuid, const char* format, ...) {
    ++failures_;
    char detail[1024];
    va_list args;
    va_start(args, format);
    std::vsnprintf(detail, sizeof detail, format, args);
    va_end(args);
    // A fixed buffer: reporting allocates nothing, so it works out of memory and in functions that cannot fail.
    char message[1536];
    std::snprintf(message, sizeof message, "Validation Error: [ %s ] | %s(): %s", vuid, command_, detail);

    PFN_vkDebugUtilsMessengerCallbackEXT callback = device_ ? device_->createInfo().pfnMessenger : nullptr;
    if (!callback) {
        std::fprintf(stderr, "%s\n", message);
        return;
    }
    VkDebugUtilsMessengerCallbackDataEXT data{};
    data.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CALLBACK_DATA_EXT;
    data.pMessageIdName = vuid;
    data.messageIdNumber = messageId(vuid);
    data.pMessage = message;
    callback(VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT, VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT, &data,
             device_->createInfo().pMessengerUserData);
}

const char* objectTypeName(ObjectMagic magic) {
    switch (magic) {
        case ObjectMagic::Memory: return "VkDeviceMemory";
        case ObjectMagic::Buffer: return "VkBuffer";
        case ObjectMagic::AccelerationStructure: return "VkAccelerationStructureKHR";
        case ObjectMagic::DeferredOperation: return "VkDeferredOperationKHR";
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

}  // namespace vkas
