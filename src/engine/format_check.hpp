// Checks untrusted bytes before vkas uses them as an acceleration structure: a serialized blob given to
// vkCopyMemoryToAccelerationStructureKHR, or any block a fuzzer hands in. The checks run with validation on or off.
// They never read outside [data, data + size), read through memcpy (no alignment needed), and accept everything
// the builder writes. A block that passes can be traversed, copied, serialized and updated without reading or
// writing outside [0, usedSize) of it, and without loops (traversal's fixed stack cannot overflow).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/serialize.hpp"

namespace vkas::format {

enum class CheckStatus {
    Ok,
    Incompatible,  // the UUIDs are not ones this build loads (VK_ERROR_INCOMPATIBLE_VERSION_KHR)
    Corrupt,       // truncated, inconsistent sizes, offsets or counts out of range, a malformed tree or record
};

struct CheckResult {
    CheckStatus status = CheckStatus::Ok;
    const char* reason = "";  // a static string naming the first rule broken
    bool ok() const { return status == CheckStatus::Ok; }
};

// A structure's block of `size` readable bytes (usedSize must fit in them).
CheckResult checkBlock(const std::byte* block, uint64_t size);

// A serialized blob of `size` readable bytes (the header's serialized size must fit in them). On success fills
// `view` (optional).
CheckResult checkSerialized(const std::byte* data, uint64_t size, serial::SerializedView* view = nullptr);

}  // namespace vkas::format
