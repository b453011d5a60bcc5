#include "renderer/base/hash.hpp"

#include "renderer/base/error.hpp"

#include <xxhash.h>

namespace bounce {

Hasher::Hasher() : state_(XXH3_createState()) {
    BOUNCE_CHECK(state_ != nullptr, "XXH3_createState returned null");
    XXH3_64bits_reset(state_);
}

Hasher::~Hasher() { XXH3_freeState(state_); }

Hasher& Hasher::add_bytes(const void* data, std::size_t bytes) {
    if (bytes > 0) XXH3_64bits_update(state_, data, bytes);
    return *this;
}

std::uint64_t Hasher::value() const { return XXH3_64bits_digest(state_); }

std::uint64_t hash_bytes(const void* data, std::size_t bytes) { return XXH3_64bits(data, bytes); }

}  // namespace bounce
