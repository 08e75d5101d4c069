#include "api/validate/validator.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <string>

#include "api/device.hpp"
#include "engine/util/host_memory.hpp"

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
    // The whole message, never truncated: on the stack when it fits (most do; reporting then allocates nothing),
    // otherwise in the command's host memory (engine/util/host_memory.hpp: the application's allocator, scope
    // COMMAND). Out of memory for a long message: written to stderr in pieces when there is no messenger (that
    // needs no buffer), otherwise std::bad_alloc (the command returns VK_ERROR_OUT_OF_HOST_MEMORY).
    static constexpr const char* kPrefix = "Validation Error: [ %s ] | %s(): ";
    PFN_vkDebugUtilsMessengerCallbackEXT callback = device_ ? device_->createInfo().pfnMessenger : nullptr;
    va_list args;
    va_start(args, format);
    va_list measure;
    va_copy(measure, args);
    const int detailLength = std::vsnprintf(nullptr, 0, format, measure);
    va_end(measure);
    const int prefixLength = std::snprintf(nullptr, 0, kPrefix, vuid, command_);
    const size_t length = size_t(std::max(prefixLength, 0)) + size_t(std::max(detailLength, 0));
    char local[1536];
    HostVector<char> heap;
    char* message = local;
    if (length + 1 > sizeof local) {
        try {
            heap.resize(length + 1);
        } catch (...) {
            if (callback) {
                va_end(args);
                throw;
            }
            std::fprintf(stderr, kPrefix, vuid, command_);
            std::vfprintf(stderr, format, args);
            std::fputc('\n', stderr);
            va_end(args);
            return;
        }
        message = heap.data();
    }
    std::snprintf(message, length + 1, kPrefix, vuid, command_);
    std::vsnprintf(message + std::max(prefixLength, 0), length + 1 - size_t(std::max(prefixLength, 0)), format, args);
    va_end(args);

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

}  // namespace vkas
