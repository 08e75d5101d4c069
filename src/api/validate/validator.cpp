#include "api/validate/validator.hpp"

#include <cstdarg>
#include <cstdio>
#include <string>

#include "api/device.hpp"

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

}  // namespace vkas
