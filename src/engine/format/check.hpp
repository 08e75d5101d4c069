// Checks untrusted bytes before vkas uses them as an acceleration structure: a serialized blob given to
// vkCopyMemoryToAccelerationStructureKHR, or any block a fuzzer hands in. The checks run with validation on or off.
// They never read outside [data, data + size), read through memcpy (no alignment needed), and accept everything
// the builder writes. A block that passes can be traversed, copied, serialized and updated without reading or
// writing outside [0, usedSize) of it, and without loops (traversal's fixed stack cannot overflow).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/serialize.hpp"

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

// A serialized blob of `size` readable bytes (the header's serialized size must fit in them): the UUIDs, sizes and
// counts, the integrity hash (layout 2) and the block (checkLoadedBlock). On success fills `view` (optional).
CheckResult checkSerialized(const std::byte* data, uint64_t size, serial::SerializedView* view = nullptr);

// The parts of checkSerialized: the header alone (UUIDs, sizes, counts; reads only the first kHeaderSize bytes and,
// in layout 2, the stored hash);
CheckResult checkSerializedLayout(const std::byte* data, uint64_t size, serial::SerializedView* view);
// and a block of view.deserializedSize bytes (the blob's or a copy of it) against that header.
CheckResult checkLoadedBlock(const serial::SerializedView& view, const std::byte* block);

}  // namespace vkas::format
