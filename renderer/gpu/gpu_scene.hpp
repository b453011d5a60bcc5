// The GPU mirror of a scene: vertex and index buffers per primitive, material textures. Transforms,
// lights and materials' factors are read from the CPU scene at draw time, so moving an object or
// changing a light never re-uploads geometry.
#pragma once

#include "renderer/gpu/gl_objects.hpp"
#include "renderer/gpu/shader_program.hpp"
#include "renderer/scene/scene.hpp"

#include <vector>

namespace bounce::gpu {

struct GpuPrimitive {
    Buffer vertices;
    Buffer indices;
    VertexArray vertex_array;
    GLsizei index_count = 0;
    int material = -1;
};

class GpuScene {
public:
    // Must be called on the render thread with the context current.
    explicit GpuScene(const scene::Scene& scene);
    // What the constructor will allocate for `scene`: vertex and index buffers, and every decoded
    // texture with its full mip chain.
    static std::uint64_t bytes_for(const scene::Scene& scene);

    const scene::Scene& scene() const { return *scene_; }

    // Calls draw(object, primitive) for every primitive of every object, in a stable order.
    template <typename DrawFunction>
    void for_each_primitive(DrawFunction&& draw) const {
        for (const scene::Object& object : scene_->objects) {
            if (object.mesh < 0) continue;
            for (const GpuPrimitive& primitive : meshes_[object.mesh]) draw(object, primitive);
        }
    }
    static void draw(const GpuPrimitive& primitive);

    // Sets the material uniforms of gbuffer.frag and binds the material's textures.
    void bind_material(const ShaderProgram& program, int material) const;

    std::size_t geometry_bytes() const { return geometry_bytes_; }
    std::size_t texture_bytes() const { return texture_bytes_; }

private:
    const scene::Scene* scene_;
    std::vector<std::vector<GpuPrimitive>> meshes_;
    std::vector<Texture> textures_;
    std::vector<Sampler> samplers_;  // per texture: its glTF sampler
    std::size_t geometry_bytes_ = 0;
    std::size_t texture_bytes_ = 0;
};

// The model and normal matrices a draw needs.
void set_object_transform(const ShaderProgram& program, const glm::mat4& model);

}  // namespace bounce::gpu
