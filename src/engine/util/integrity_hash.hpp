// The integrity hash of a serialized blob (serialized layout 2, docs/FORMAT.md): XXH3-64, seed 0, of the header's
// first 56 bytes (UUIDs, sizes, handle count) followed by the block, the handle array left out because the
// application rewrites it. xxHash (Debian's libxxhash) computes it; this class only feeds it byte ranges.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vkas::serial {

class IntegrityHash {
public:
    IntegrityHash();
    void add(const void* data, size_t size);
    uint64_t digest() const;

    // Bytes a caller hashes at a time when it must change some of them first (a copy on the stack).
    static constexpr size_t kChunk = 16 * 1024;

private:
    // XXH3_state_t, kept opaque so that xxhash.h stays inside integrity_hash.cpp (static_assert there).
    alignas(64) unsigned char state_[640];
};

}  // namespace vkas::serial
