#include "renderer/gpu/gl_objects.hpp"

#include "renderer/base/error.hpp"

#include <algorithm>
#include <cmath>

namespace bounce::gpu {

VertexArray make_vertex_array() {
    GLuint id = 0;
    glCreateVertexArrays(1, &id);
    return VertexArray(id);
}

Query make_query(GLenum target) {
    GLuint id = 0;
    glCreateQueries(target, 1, &id);
    return Query(id);
}

Sampler make_sampler() {
    GLuint id = 0;
    glCreateSamplers(1, &id);
    return Sampler(id);
}

Buffer::Buffer(std::size_t bytes, const void* data, GLbitfield flags) : bytes_(bytes) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    handle_ = GlHandle<BufferTraits>(id);
    // Zero-sized storage is an error in GL; keep one byte so empty meshes still have a buffer.
    glNamedBufferStorage(id, static_cast<GLsizeiptr>(std::max<std::size_t>(bytes, 1)), bytes ? data : nullptr, flags);
}

void Buffer::upload(std::size_t offset, std::size_t bytes, const void* data) {
    BOUNCE_CHECK(offset + bytes <= bytes_, "upload of {} bytes at {} past a {}-byte buffer", bytes, offset, bytes_);
    glNamedBufferSubData(id(), static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), data);
}

std::size_t bytes_per_texel(GLenum format) {
    switch (format) {
        case GL_R8: return 1;
        case GL_RG8: return 2;
        case GL_RGBA8:
        case GL_SRGB8_ALPHA8:
        case GL_R32F:
        case GL_R32UI:
        case GL_RG16F:
        case GL_DEPTH_COMPONENT32F:
        case GL_DEPTH24_STENCIL8:
        case GL_DEPTH_COMPONENT24: return 4;
        case GL_RGBA16F:
        case GL_RG32F: return 8;
        case GL_RGBA32F:
        case GL_RGBA32UI: return 16;
        case GL_DEPTH_COMPONENT16:
        case GL_R16F: return 2;
        default: return 4;
    }
}

Texture::Texture(const TextureDesc& desc) : desc_(desc) {
    BOUNCE_CHECK(desc.width > 0 && desc.height > 0 && desc.depth > 0, "texture size {}x{}x{}", desc.width,
                 desc.height, desc.depth);
    GLuint id = 0;
    glCreateTextures(desc.target, 1, &id);
    handle_ = GlHandle<TextureTraits>(id);
    const int largest = std::max({desc.width, desc.height, desc.target == GL_TEXTURE_3D ? desc.depth : 1});
    const int full_chain = 1 + static_cast<int>(std::floor(std::log2(static_cast<double>(largest))));
    desc_.levels = desc.levels <= 0 ? full_chain : std::min(desc.levels, full_chain);
    switch (desc.target) {
        case GL_TEXTURE_3D:
        case GL_TEXTURE_2D_ARRAY:
        case GL_TEXTURE_CUBE_MAP_ARRAY:
            glTextureStorage3D(id, desc_.levels, desc.format, desc.width, desc.height, desc.depth);
            break;
        default:
            glTextureStorage2D(id, desc_.levels, desc.format, desc.width, desc.height);
            break;
    }
    const std::size_t faces = desc.target == GL_TEXTURE_CUBE_MAP ? 6 : 1;
    std::size_t texels = 0;
    for (int level = 0; level < desc_.levels; ++level) {
        const std::size_t w = std::max(1, desc.width >> level);
        const std::size_t h = std::max(1, desc.height >> level);
        const std::size_t d = desc.target == GL_TEXTURE_3D ? std::max(1, desc.depth >> level) : desc.depth;
        texels += w * h * d * faces;
    }
    bytes_ = texels * bytes_per_texel(desc.format);
    const bool integer = desc.format == GL_R32UI || desc.format == GL_RGBA32UI;
    set_filter(integer ? GL_NEAREST : (desc_.levels > 1 ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR),
               integer ? GL_NEAREST : GL_LINEAR);
    set_wrap(GL_CLAMP_TO_EDGE);
}

void Texture::set_filter(GLenum min_filter, GLenum mag_filter) {
    glTextureParameteri(id(), GL_TEXTURE_MIN_FILTER, static_cast<GLint>(min_filter));
    glTextureParameteri(id(), GL_TEXTURE_MAG_FILTER, static_cast<GLint>(mag_filter));
}

void Texture::set_wrap(GLenum wrap) {
    glTextureParameteri(id(), GL_TEXTURE_WRAP_S, static_cast<GLint>(wrap));
    glTextureParameteri(id(), GL_TEXTURE_WRAP_T, static_cast<GLint>(wrap));
    glTextureParameteri(id(), GL_TEXTURE_WRAP_R, static_cast<GLint>(wrap));
}

Framebuffer::Framebuffer() {
    GLuint id = 0;
    glCreateFramebuffers(1, &id);
    handle_ = GlHandle<FramebufferTraits>(id);
}

void Framebuffer::attach_color(int index, const Texture& texture, int level) {
    glNamedFramebufferTexture(id(), GL_COLOR_ATTACHMENT0 + index, texture.id(), level);
}

void Framebuffer::attach_color_layer(int index, const Texture& texture, int layer, int level) {
    glNamedFramebufferTextureLayer(id(), GL_COLOR_ATTACHMENT0 + index, texture.id(), level, layer);
}

void Framebuffer::attach_depth(const Texture& texture, int level) {
    glNamedFramebufferTexture(id(), GL_DEPTH_ATTACHMENT, texture.id(), level);
}

void Framebuffer::attach_depth_layer(const Texture& texture, int layer, int level) {
    glNamedFramebufferTextureLayer(id(), GL_DEPTH_ATTACHMENT, texture.id(), level, layer);
}

void Framebuffer::attach_depth_stencil(const Texture& texture) {
    glNamedFramebufferTexture(id(), GL_DEPTH_STENCIL_ATTACHMENT, texture.id(), 0);
}

void Framebuffer::set_draw_buffers(int count) {
    GLenum buffers[8];
    for (int i = 0; i < count && i < 8; ++i) buffers[i] = GL_COLOR_ATTACHMENT0 + i;
    if (count == 0) {
        glNamedFramebufferDrawBuffer(id(), GL_NONE);
    } else {
        glNamedFramebufferDrawBuffers(id(), count, buffers);
    }
}

void Framebuffer::check_complete(const char* what) const {
    const GLenum status = glCheckNamedFramebufferStatus(id(), GL_FRAMEBUFFER);
    if (status == GL_FRAMEBUFFER_COMPLETE) return;
    const char* name = "unknown";
    switch (status) {
        case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT: name = "INCOMPLETE_ATTACHMENT"; break;
        case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT: name = "MISSING_ATTACHMENT"; break;
        case GL_FRAMEBUFFER_UNSUPPORTED: name = "UNSUPPORTED"; break;
        case GL_FRAMEBUFFER_INCOMPLETE_LAYER_TARGETS: name = "INCOMPLETE_LAYER_TARGETS"; break;
        default: break;
    }
    BOUNCE_FAIL("framebuffer for {} is incomplete: {} (0x{:x})", what, name, status);
}

void bind_storage(GLuint binding, const Buffer& buffer) {
    if (buffer) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer.id());
}

void storage_barrier() { glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT); }

}  // namespace bounce::gpu
