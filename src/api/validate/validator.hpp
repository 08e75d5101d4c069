// Reports valid-usage violations the way the Khronos validation layers do: one message per violated rule,
// severity ERROR, type VALIDATION, pMessageIdName = the full VUID. A command that found a violation does
// nothing else and returns VK_ERROR_VALIDATION_FAILED_EXT. The rules themselves are in the other files of
// api/validate/, one subject each; parameters.hpp has the ones every command shares.
#pragma once

#include <cstdint>

namespace vkas {

class Device;

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

}  // namespace vkas
