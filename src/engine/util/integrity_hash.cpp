#include "engine/util/integrity_hash.hpp"

#include <cstring>
#include <new>

#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t's definition, so the state lives on the stack (no allocation)
#include <xxhash.h>
#if defined(__x86_64__)
#include <xxh_x86dispatch.h>  // libxxhash's run-time choice of SSE2 / AVX2 / AVX-512 for XXH3
#endif

namespace vkas::serial {

namespace {
XXH3_state_t* state(unsigned char* storage) { return std::launder(reinterpret_cast<XXH3_state_t*>(storage)); }
const XXH3_state_t* state(const unsigned char* storage) {
    return std::launder(reinterpret_cast<const XXH3_state_t*>(storage));
}
}  // namespace

IntegrityHash::IntegrityHash() {
    static_assert(sizeof(XXH3_state_t) <= sizeof(state_) && alignof(XXH3_state_t) <= 64);
    XXH3_state_t* s = new (state_) XXH3_state_t;
    XXH3_INITSTATE(s);
    XXH3_64bits_reset(s);
}

void IntegrityHash::add(const void* data, size_t size) {
    if (size != 0) XXH3_64bits_update(state(state_), data, size);
}

uint64_t IntegrityHash::digest() const { return XXH3_64bits_digest(state(state_)); }

}  // namespace vkas::serial
