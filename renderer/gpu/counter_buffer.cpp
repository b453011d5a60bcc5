#include "renderer/gpu/counter_buffer.hpp"

#include "renderer/base/error.hpp"

namespace bounce::gpu {

CounterBuffer::CounterBuffer(std::size_t count)
    : buffer_(count * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT), count_(count) {
    reset();
}

void CounterBuffer::reset() {
    write(std::vector<std::uint32_t>(count_, 0u));
}

void CounterBuffer::write(std::span<const std::uint32_t> values) {
    BOUNCE_CHECK(values.size() <= count_, "{} counter values for a buffer of {} counters", values.size(), count_);
    buffer_.upload(0, values.size_bytes(), values.data());
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
}

void CounterBuffer::bind(GLuint binding) const { bind_storage(binding, buffer_); }

CounterValues CounterBuffer::read() const {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    CounterValues values{std::vector<std::uint32_t>(count_, 0u)};
    glGetNamedBufferSubData(buffer_.id(), 0, static_cast<GLsizeiptr>(values.words.size() * sizeof(std::uint32_t)),
                            values.words.data());
    return values;
}

}  // namespace bounce::gpu
