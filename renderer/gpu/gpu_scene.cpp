#include "renderer/gpu/gpu_scene.hpp"

#include "common/shared_layout.h"

#include <cstddef>

namespace bounce::gpu {

static_assert(static_cast<int>(scene::AlphaMode::opaque) == BOUNCE_ALPHA_OPAQUE &&
                  static_cast<int>(scene::AlphaMode::mask) == BOUNCE_ALPHA_MASK &&
                  static_cast<int>(scene::AlphaMode::blend) == BOUNCE_ALPHA_BLEND,
              "scene::AlphaMode numbers its modes as the shaders do");
namespace {

// A GL sampler object with a glTF sampler's filters and wraps.
Sampler make_texture_sampler(const scene::TextureSampler& source) {
    using Min = scene::TextureSampler::MinFilter;
    using Wrap = scene::TextureSampler::Wrap;
    const auto wrap = [](Wrap mode) -> GLint {
        return mode == Wrap::clamp_to_edge ? GL_CLAMP_TO_EDGE : mode == Wrap::mirrored_repeat ? GL_MIRRORED_REPEAT : GL_REPEAT;
    };
    GLint min_filter = GL_LINEAR_MIPMAP_LINEAR;
    switch (source.min_filter) {
    case Min::nearest: min_filter = GL_NEAREST; break;
    case Min::linear: min_filter = GL_LINEAR; break;
    case Min::nearest_mipmap_nearest: min_filter = GL_NEAREST_MIPMAP_NEAREST; break;
    case Min::linear_mipmap_nearest: min_filter = GL_LINEAR_MIPMAP_NEAREST; break;
    case Min::nearest_mipmap_linear: min_filter = GL_NEAREST_MIPMAP_LINEAR; break;
    case Min::linear_mipmap_linear: break;
    }
    Sampler sampler = make_sampler();
    glSamplerParameteri(sampler.id(), GL_TEXTURE_MIN_FILTER, min_filter);
    glSamplerParameteri(sampler.id(), GL_TEXTURE_MAG_FILTER, source.mag_nearest ? GL_NEAREST : GL_LINEAR);
    glSamplerParameteri(sampler.id(), GL_TEXTURE_WRAP_S, wrap(source.wrap_s));
    glSamplerParameteri(sampler.id(), GL_TEXTURE_WRAP_T, wrap(source.wrap_t));
    return sampler;
}

struct Vertex {
    glm::vec3 position;
    glm::vec3 normal;
    glm::vec4 tangent;
    glm::vec2 uv0;
    glm::vec2 uv1;
};

GpuPrimitive upload(const scene::Primitive& source) {
    std::vector<Vertex> vertices(source.positions.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        Vertex& v = vertices[i];
        v.position = source.positions[i];
        v.normal = i < source.normals.size() ? source.normals[i] : glm::vec3(0.0f, 1.0f, 0.0f);
        v.tangent = i < source.tangents.size() ? source.tangents[i] : glm::vec4(1.0f, 0.0f, 0.0f, 1.0f);
        v.uv0 = i < source.uv0.size() ? source.uv0[i] : glm::vec2(0.0f);
        v.uv1 = i < source.uv1.size() ? source.uv1[i] : v.uv0;
    }
    GpuPrimitive primitive;
    primitive.vertices = Buffer(vertices.size() * sizeof(Vertex), vertices.data());
    primitive.indices = Buffer(source.indices.size() * sizeof(std::uint32_t), source.indices.data());
    primitive.index_count = static_cast<GLsizei>(source.indices.size());
    primitive.material = source.material;
    primitive.vertex_array = make_vertex_array();

    const GLuint vao = primitive.vertex_array.id();
    glVertexArrayVertexBuffer(vao, 0, primitive.vertices.id(), 0, sizeof(Vertex));
    glVertexArrayElementBuffer(vao, primitive.indices.id());
    auto attribute = [vao](GLuint location, GLint components, std::size_t offset) {
        glEnableVertexArrayAttrib(vao, location);
        glVertexArrayAttribFormat(vao, location, components, GL_FLOAT, GL_FALSE, static_cast<GLuint>(offset));
        glVertexArrayAttribBinding(vao, location, 0);
    };
    attribute(BOUNCE_ATTR_POSITION, 3, offsetof(Vertex, position));
    attribute(BOUNCE_ATTR_NORMAL, 3, offsetof(Vertex, normal));
    attribute(BOUNCE_ATTR_TANGENT, 4, offsetof(Vertex, tangent));
    attribute(BOUNCE_ATTR_UV0, 2, offsetof(Vertex, uv0));
    attribute(BOUNCE_ATTR_UV1, 2, offsetof(Vertex, uv1));
    return primitive;
}

Texture upload(const scene::Texture& source) {
    const GLenum format = source.srgb ? GL_SRGB8_ALPHA8 : GL_RGBA8;
    Texture texture({GL_TEXTURE_2D, format, source.width, source.height, 1, 0});
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(texture.id(), 0, 0, 0, source.width, source.height, GL_RGBA, GL_UNSIGNED_BYTE,
                        source.rgba8.data());
    glGenerateTextureMipmap(texture.id());
    return texture;
}

}  // namespace

std::uint64_t GpuScene::bytes_for(const scene::Scene& scene) {
    std::uint64_t bytes = 0;
    for (const scene::Mesh& mesh : scene.meshes)
        for (const scene::Primitive& primitive : mesh.primitives)
            bytes += primitive.positions.size() * sizeof(Vertex) + primitive.indices.size() * sizeof(std::uint32_t);
    for (const scene::Texture& texture : scene.textures) {
        if (texture.width <= 0 || texture.height <= 0 || texture.rgba8.empty()) continue;
        for (std::uint64_t w = static_cast<std::uint64_t>(texture.width), h = static_cast<std::uint64_t>(texture.height);;
             w = std::max<std::uint64_t>(1, w / 2), h = std::max<std::uint64_t>(1, h / 2)) {
            bytes += w * h * 4;
            if (w == 1 && h == 1) break;
        }
    }
    return bytes;
}

GpuScene::GpuScene(const scene::Scene& scene) : scene_(&scene) {
    for (const scene::Mesh& mesh : scene.meshes) {
        auto& primitives = meshes_.emplace_back();
        for (const scene::Primitive& source : mesh.primitives) {
            primitives.push_back(upload(source));
            geometry_bytes_ += primitives.back().vertices.bytes() + primitives.back().indices.bytes();
        }
    }
    for (const scene::Texture& source : scene.textures) {
        if (source.width <= 0 || source.height <= 0 || source.rgba8.empty()) {
            textures_.emplace_back();  // decoding failed at import: the material uses its factors only
            continue;
        }
        textures_.push_back(upload(source));
        texture_bytes_ += textures_.back().bytes();
    }
    for (const scene::Texture& source : scene.textures) samplers_.push_back(make_texture_sampler(source.sampler));
}

void GpuScene::draw(const GpuPrimitive& primitive) {
    if (primitive.index_count == 0) return;
    glBindVertexArray(primitive.vertex_array.id());
    glDrawElements(GL_TRIANGLES, primitive.index_count, GL_UNSIGNED_INT, nullptr);
}

void GpuScene::bind_material(const ShaderProgram& program, int material_index) const {
    const scene::Material& material = scene_->material(material_index);
    program.set("u_base_color", material.base_color);
    program.set("u_metallic", material.metallic);
    program.set("u_roughness", material.roughness);
    program.set("u_specular", material.specular);
    program.set("u_specular_f0", material.dielectric_f0());
    program.set("u_specular_color", material.specular_color);
    const float r = (material.ior - 1.0f) / (material.ior + 1.0f);
    program.set("u_ior_f0", r * r);
    program.set("u_emissive", material.emissive);
    program.set("u_normal_scale", material.normal_scale);
    program.set("u_double_sided", material.double_sided ? 1 : 0);
    program.set("u_alpha_mode", static_cast<int>(material.alpha_mode));
    program.set("u_alpha_cutoff", material.alpha_cutoff);
    auto bind = [&](const scene::TextureRef& ref, GLuint unit, const char* uv_uniform) {
        const bool usable = ref.valid() && ref.texture < static_cast<int>(textures_.size()) &&
                            static_cast<bool>(textures_[ref.texture]);
        program.set(uv_uniform, usable ? ref.uv_set : -1);
        program.set(std::string(uv_uniform) + "_transform", ref.uv_transform);
        if (usable) {
            glBindTextureUnit(unit, textures_[ref.texture].id());
            glBindSampler(unit, samplers_[ref.texture].id());
        }
    };
    bind(material.base_color_texture, BOUNCE_UNIT_BASE_COLOR, "u_base_color_uv");
    bind(material.metallic_roughness_texture, BOUNCE_UNIT_METALLIC_ROUGHNESS, "u_metallic_roughness_uv");
    bind(material.normal_texture, BOUNCE_UNIT_NORMAL, "u_normal_uv");
    bind(material.emissive_texture, BOUNCE_UNIT_EMISSIVE, "u_emissive_uv");
    bind(material.specular_texture, BOUNCE_UNIT_SPECULAR, "u_specular_uv");
    bind(material.specular_color_texture, BOUNCE_UNIT_SPECULAR_COLOR, "u_specular_color_uv");
}

void set_object_transform(const ShaderProgram& program, const glm::mat4& model) {
    program.set("u_model", model);
    program.set("u_normal_matrix", glm::mat3(glm::transpose(glm::inverse(model))));
}

}  // namespace bounce::gpu
