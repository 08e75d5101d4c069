// Unaligned little-endian reads and writes of plain values: serialized data and application buffers may sit at any
// address, and memcpy is the defined way to read them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace vkas {

inline uint64_t load64(const std::byte* p) {
    uint64_t v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
inline uint32_t load32(const std::byte* p) {
    uint32_t v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
inline void store64(std::byte* p, uint64_t v) { std::memcpy(p, &v, sizeof v); }

// An application address moved by an offset, or null for a null address: a geometry with no primitives may give no
// data, and offsetting a null pointer is undefined behaviour even when nothing is read.
inline const std::byte* offsetAddress(const void* base, uint64_t offset) {
    return base ? static_cast<const std::byte*>(base) + offset : nullptr;
}

}  // namespace vkas
