// Shadow maps for punctual lights: a cube map per point light, a perspective map per spot light,
// an orthographic map fitted to the scene per directional light. A light with no power gets no
// map (it cannot reach the view).
#pragma once

#include "renderer/passes/pass_context.hpp"

#include <cstdint>
#include <vector>

namespace bounce::passes {

class ShadowMaps {
public:
    // Renders a map of `size` texels per side for every light of the scene that has power. Each map is
    // kept while its light's place and shape, the object transforms and the size stay the same
    // (shadow_map_fingerprint): a light dimmed or recoloured keeps it, and a light moved redraws its
    // own map alone.
    void render(const PassContext& context, int size);
    // Whether the last render() reused every map instead of drawing any.
    bool last_render_reused() const { return last_reused_; }
    std::size_t frames_drawn() const { return frames_drawn_; }
    std::size_t frames_reused() const { return frames_reused_; }
    std::size_t maps_drawn() const { return maps_drawn_; }  // light maps drawn, over every render()
    // Whether light `index` has a map (false for lights without power).
    bool has_map(std::size_t light_index) const;
    // Sets the shadow uniforms of common/shadows.glsl on `program` and binds the light's map.
    void bind(const gpu::ShaderProgram& program, std::size_t light_index) const;
    std::size_t bytes() const;
    // What render(scene, size) will hold: a 32-bit depth map per light with power, six faces for a
    // point light.
    static std::uint64_t bytes_for(const scene::Scene& scene, int size);
    std::size_t map_count() const;

private:
    struct LightMap {
        scene::LightType type = scene::LightType::point;
        gpu::Texture depth;
        glm::mat4 view_projection{1.0f};
        float far = 1.0f;
        float texel_angle = 0.0f;  // world texel size per unit distance (perspective maps)
        float texel_world = 0.0f;  // world texel size (orthographic maps)
        bool valid = false;
        std::uint64_t fingerprint = 0;  // shadow_map_fingerprint it was drawn for; 0: never drawn
    };
    void render_view(const PassContext& context, const gpu::ShaderProgram& program, const glm::mat4& view_projection);
    std::vector<LightMap> maps_;
    gpu::Framebuffer framebuffer_;
    bool last_reused_ = false;
    std::size_t maps_drawn_ = 0;
    std::size_t frames_drawn_ = 0;
    std::size_t frames_reused_ = 0;
};

}  // namespace bounce::passes
