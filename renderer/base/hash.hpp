// Content hashing for cache keys and checksums: XXH3-64 (Debian's libxxhash), streamed. One hash
// serves the bake cache's keys and checksums, the light-geometry change detection and the bench's
// reference-image cache, so a key means the same everywhere.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>

struct XXH3_state_s;

namespace bounce {

class Hasher {
public:
    Hasher();
    ~Hasher();
    Hasher(const Hasher&) = delete;
    Hasher& operator=(const Hasher&) = delete;

    Hasher& add_bytes(const void* data, std::size_t bytes);
    // The object representation of a trivially copyable value (no padding-sensitive types: glm
    // vectors and matrices, integers, floats, enums).
    template <typename T>
    Hasher& add(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>, "hash values by their bytes");
        return add_bytes(&value, sizeof(T));
    }
    template <typename T>
    Hasher& add_span(std::span<const T> values) {
        static_assert(std::is_trivially_copyable_v<T>, "hash values by their bytes");
        add(values.size());
        return add_bytes(values.data(), values.size_bytes());
    }
    Hasher& add_string(std::string_view text) {
        add(text.size());
        return add_bytes(text.data(), text.size());
    }
    std::uint64_t value() const;

private:
    XXH3_state_s* state_;
};

// The hash of one block of bytes.
std::uint64_t hash_bytes(const void* data, std::size_t bytes);

}  // namespace bounce
