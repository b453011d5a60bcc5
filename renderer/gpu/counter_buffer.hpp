// A small shader storage buffer of 32-bit counters that shaders add to atomically: set (usually to
// zero) before the work, bound at the binding the shaders declare, read back after it. A count
// that may pass 2^32 is kept in two words, low and high, the shader carrying into the high one.
#pragma once

#include "renderer/gpu/gl_objects.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace bounce::gpu {

// Counters as read back.
struct CounterValues {
    std::vector<std::uint32_t> words;

    std::uint32_t operator[](std::size_t index) const { return words.at(index); }
    // The count kept in words `low` and `high`.
    std::uint64_t wide(std::size_t low, std::size_t high) const {
        return (static_cast<std::uint64_t>(words.at(high)) << 32) | words.at(low);
    }
};

class CounterBuffer {
public:
    CounterBuffer() = default;
    // `count` counters, zeroed.
    explicit CounterBuffer(std::size_t count);
    GLuint id() const { return buffer_.id(); }
    std::size_t count() const { return count_; }
    std::size_t bytes() const { return buffer_.bytes(); }
    explicit operator bool() const { return static_cast<bool>(buffer_); }

    // Every counter to zero.
    void reset();
    // The first values.size() counters (at most count()) to `values`.
    void write(std::span<const std::uint32_t> values);
    void bind(GLuint binding) const;
    // Waits for the shaders' atomic writes (which later shaders see too), then reads every counter.
    CounterValues read() const;

private:
    Buffer buffer_;
    std::size_t count_ = 0;
};

}  // namespace bounce::gpu
