// Checks untrusted bytes before vkas uses them as a micromap: a serialized micromap given to
// vkCopyMemoryToMicromapEXT, or any block a fuzzer hands in. The checks run with validation on or off, never read
// outside [data, data + size), read through memcpy (no alignment needed) and accept exactly what the build writes: a
// block that passes can be copied, serialized and read by bottom-level builds (every triangle's states lie inside it).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/check.hpp"
#include "engine/format/micromap_serialize.hpp"

namespace vkas::format {

// A micromap block of `size` readable bytes (its usedSize must fit in them).
CheckResult checkMicromapBlock(const std::byte* block, uint64_t size);

// A serialized micromap of `size` readable bytes (the header's serialized size must fit in them): the UUIDs
// (Incompatible when they are not the pair vkas writes for micromaps), the sizes, the integrity hash and the block.
// On success fills `view` (optional).
CheckResult checkSerializedMicromap(const std::byte* data, uint64_t size,
                                    serial::SerializedMicromapView* view = nullptr);

}  // namespace vkas::format
