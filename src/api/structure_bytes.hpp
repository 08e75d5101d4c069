// What a command may read of the memory the application gave it, shared by the commands and their valid-usage rules
// (api/validate/): whether two host ranges overlap, how far a serialized blob reaches, and the block a structure
// holds when vkas wrote it, and which of the device's structures a serialized handle entry names.
#pragma once

#include <cstddef>
#include <cstdint>

#include "api/device.hpp"
#include "api/objects.hpp"
#include "engine/format/serialize.hpp"
#include "engine/util/host_memory.hpp"

namespace vkas {

// Whether the host ranges [a, a + aSize) and [b, b + bSize) overlap (an empty range overlaps nothing).
bool rangesOverlap(uintptr_t a, uint64_t aSize, uintptr_t b, uint64_t bSize);

// The readable extent the application promises for a serialized blob: its header's serialized size (at least the
// header itself, which every blob has).
uint64_t blobExtent(const void* src);

// The block of `as` when it holds a structure vkas wrote (built, copied or deserialized) that fits in its range,
// else nullptr.
const std::byte* constructedBlock(const AccelerationStructure& as);

// Maps handle-array entries of serialized data to the bottom levels of `device` they name: in layout 2 a device
// address (vkGetAccelerationStructureDeviceAddressKHR) of a live structure created as BOTTOM_LEVEL or GENERIC; in
// layout 1 (older vkas wrote handle values there) such an address or else such a VkAccelerationStructureKHR.
class SerializedReferences {
public:
    SerializedReferences(const Device& device, serial::Layout layout) : device_(device), layout_(layout) {}
    // The instance reference (a VkAccelerationStructureKHR handle) a loaded top level stores for `value`, or 0
    // when it names no such structure. Allocates (the address index, built on first use): may throw bad_alloc.
    uint64_t toReference(uint64_t value);

private:
    const Device& device_;
    serial::Layout layout_;
    bool indexed_ = false;
    HostUnorderedMap<uint64_t, const AccelerationStructure*> byAddress_;
};

}  // namespace vkas
