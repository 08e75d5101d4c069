// What the micromap commands share: the block of a constructed micromap, and the resolver bottom-level builds use
// to turn a VkMicromapEXT into the block it names.
#pragma once

#include <cstddef>
#include <cstdint>

#include "api/objects.hpp"

namespace vkas {

// The block of `micromap` when it holds a micromap vkas wrote (built, copied or deserialized) that fits in its
// range, else nullptr.
const std::byte* constructedMicromapBlock(const Micromap& micromap);

// A build, copy or deserialization that failed part-way leaves its destination unconstructed: the header no longer
// names a micromap, so nothing reads the half-written contents.
void markMicromapUnconstructed(Micromap& micromap) noexcept;

// MicromapResolver (engine/format/micromap_layout.hpp): the block of the live, constructed micromap a VkMicromapEXT
// (as a 64-bit value) names, or nullptr. Looks the handle up in the registry: a destroyed or unknown handle gives
// nullptr, never a dereference.
const std::byte* resolveMicromap(uint64_t micromap);

}  // namespace vkas
