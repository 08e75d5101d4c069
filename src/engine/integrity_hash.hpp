// The integrity hash of a serialized blob (serialized layout 2, docs/FORMAT.md): XXH3-64, seed 0, of the header's
// first 56 bytes (UUIDs, sizes, handle count) followed by the block, the handle array left out because the
// application rewrites it. xxHash (Debian's libxxhash) computes it; this class only feeds it byte ranges, so the
// serializer and the loader can hash a chunk while it is in cache, right after copying it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vkas::serial {

class IntegrityHash {
public:
    IntegrityHash();
    void add(const void* data, size_t size);
    uint64_t digest() const;

    // Copies `size` bytes from `src` to `dst` (not overlapping) and hashes them on the way, a cache-sized chunk
    // at a time; as fast as the copy alone where memory bandwidth is the limit.
    void copyAndAdd(std::byte* dst, const std::byte* src, size_t size);

    static constexpr size_t kChunk = 16 * 1024;  // fits the first-level data cache with room to spare

private:
    // XXH3_state_t, kept opaque so that xxhash.h stays inside integrity_hash.cpp (static_assert there).
    alignas(64) unsigned char state_[640];
};

}  // namespace vkas::serial
