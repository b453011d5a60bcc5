// Move-only RAII owners for every kind of OpenGL object Bounce uses. No raw glGen/glDelete
// outside this file. Textures and buffers know their size, which memory accounting reports.
#pragma once

#include "renderer/gpu/gl.hpp"

#include <algorithm>
#include <vector>
#include <cstddef>
#include <cstdint>
#include <utility>

namespace bounce::gpu {

template <typename Traits>
class GlHandle {
public:
    GlHandle() = default;
    explicit GlHandle(GLuint id) : id_(id) {}
    ~GlHandle() { reset(); }
    GlHandle(GlHandle&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    GlHandle& operator=(GlHandle&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
        }
        return *this;
    }
    GlHandle(const GlHandle&) = delete;
    GlHandle& operator=(const GlHandle&) = delete;

    GLuint id() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void reset() {
        if (id_ != 0) Traits::destroy(id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

struct BufferTraits { static void destroy(GLuint id) { glDeleteBuffers(1, &id); } };
struct TextureTraits { static void destroy(GLuint id) { glDeleteTextures(1, &id); } };
struct FramebufferTraits { static void destroy(GLuint id) { glDeleteFramebuffers(1, &id); } };
struct VertexArrayTraits { static void destroy(GLuint id) { glDeleteVertexArrays(1, &id); } };
struct QueryTraits { static void destroy(GLuint id) { glDeleteQueries(1, &id); } };
struct SamplerTraits { static void destroy(GLuint id) { glDeleteSamplers(1, &id); } };
struct ProgramTraits { static void destroy(GLuint id) { glDeleteProgram(id); } };
struct ShaderTraits { static void destroy(GLuint id) { glDeleteShader(id); } };

using VertexArray = GlHandle<VertexArrayTraits>;
using Query = GlHandle<QueryTraits>;
using Sampler = GlHandle<SamplerTraits>;
using ShaderObject = GlHandle<ShaderTraits>;
using ProgramObject = GlHandle<ProgramTraits>;

VertexArray make_vertex_array();
Query make_query(GLenum target);
Sampler make_sampler();

// An immutable-storage buffer.
class Buffer {
public:
    Buffer() = default;
    // `flags` as for glNamedBufferStorage (GL_DYNAMIC_STORAGE_BIT to allow updates).
    Buffer(std::size_t bytes, const void* data, GLbitfield flags = 0);
    GLuint id() const { return handle_.id(); }
    std::size_t bytes() const { return bytes_; }
    explicit operator bool() const { return static_cast<bool>(handle_); }
    void upload(std::size_t offset, std::size_t bytes, const void* data);

private:
    GlHandle<BufferTraits> handle_;
    std::size_t bytes_ = 0;
};

// Binds `buffer` to shader-storage binding point `binding` (nothing when the buffer is empty).
void bind_storage(GLuint binding, const Buffer& buffer);
// Makes shader writes to storage buffers visible to later shader reads and buffer updates.
void storage_barrier();
// A storage buffer holding `data`, at least one element long (GL allows no empty storage).
template <typename T>
Buffer storage_of(const std::vector<T>& data, GLbitfield flags = 0) {
    return Buffer(std::max<std::size_t>(sizeof(T), data.size() * sizeof(T)), data.empty() ? nullptr : data.data(), flags);
}

struct TextureDesc {
    GLenum target = GL_TEXTURE_2D;  // GL_TEXTURE_2D, GL_TEXTURE_CUBE_MAP, GL_TEXTURE_3D, GL_TEXTURE_2D_ARRAY
    GLenum format = GL_RGBA8;       // sized internal format
    int width = 1;
    int height = 1;
    int depth = 1;   // layers or depth for 3D/array targets
    int levels = 1;  // 0: a full mip chain
};

// An immutable-storage texture.
class Texture {
public:
    Texture() = default;
    explicit Texture(const TextureDesc& desc);
    GLuint id() const { return handle_.id(); }
    const TextureDesc& desc() const { return desc_; }
    int width() const { return desc_.width; }
    int height() const { return desc_.height; }
    std::size_t bytes() const { return bytes_; }
    explicit operator bool() const { return static_cast<bool>(handle_); }
    void set_filter(GLenum min_filter, GLenum mag_filter);
    void set_wrap(GLenum wrap);

private:
    GlHandle<TextureTraits> handle_;
    TextureDesc desc_;
    std::size_t bytes_ = 0;
};

// Bytes per texel of a sized internal format (the formats Bounce allocates).
std::size_t bytes_per_texel(GLenum format);

// A framebuffer with a completeness check that names the failing status.
class Framebuffer {
public:
    Framebuffer();
    GLuint id() const { return handle_.id(); }
    void attach_color(int index, const Texture& texture, int level = 0);
    void attach_color_layer(int index, const Texture& texture, int layer, int level = 0);
    void attach_depth(const Texture& texture, int level = 0);
    void attach_depth_layer(const Texture& texture, int layer, int level = 0);
    void attach_depth_stencil(const Texture& texture);  // a GL_DEPTH24_STENCIL8 texture
    void set_draw_buffers(int count);
    // Throws Error with the status name and `what` when incomplete.
    void check_complete(const char* what) const;

private:
    GlHandle<FramebufferTraits> handle_;
};

}  // namespace bounce::gpu
