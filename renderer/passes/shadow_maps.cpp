#include "renderer/passes/shadow_maps.hpp"

#include "common/shared_layout.h"
#include "renderer/base/error.hpp"
#include "renderer/passes/light_geometry.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace bounce::passes {
namespace {

gpu::Texture make_depth_map(GLenum target, int size) {
    gpu::Texture texture({target, GL_DEPTH_COMPONENT32F, size, size});
    glTextureParameteri(texture.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(texture.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    texture.set_filter(GL_LINEAR, GL_LINEAR);  // bilinear percentage-closer filtering
    return texture;
}

}  // namespace

void ShadowMaps::render_view(const PassContext& context, const gpu::ShaderProgram& program,
                             const glm::mat4& view_projection) {
    program.set("u_view_proj", view_projection);
    context.gpu_scene.for_each_primitive([&](const scene::Object& object, const gpu::GpuPrimitive& primitive) {
        program.set("u_model", object.transform);
        // Masked and blended materials need their alpha and its texture; every other surface only depth.
        if (context.scene.material(primitive.material).alpha_mode != scene::AlphaMode::opaque) {
            context.gpu_scene.bind_material(program, primitive.material);
        } else {
            program.set("u_alpha_mode", static_cast<int>(scene::AlphaMode::opaque));
        }
        gpu::GpuScene::draw(primitive);
    });
}

void ShadowMaps::render(const PassContext& context, int size) {
    const auto& lights = context.scene.lights;
    const std::uint64_t geometry = geometry_fingerprint(context.scene);
    std::vector<std::uint64_t> fingerprints(lights.size());
    bool stale = maps_.size() != lights.size();
    for (std::size_t i = 0; i < lights.size(); ++i) {
        fingerprints[i] = shadow_map_fingerprint(lights[i], geometry, size);
        stale = stale || maps_[i].fingerprint != fingerprints[i];
    }
    last_reused_ = !stale;
    if (last_reused_) {
        ++frames_reused_;
        return;
    }
    // Timed only where maps are drawn: a frame's `shadow_maps` pass says it drew them, and what that
    // took (the planner prices the maps by it, planning/costs.hpp).
    gpu::GpuTimers::Scope timing(context.timers, "shadow_maps");
    ++frames_drawn_;
    maps_.resize(lights.size());
    const scene::Aabb bounds = context.scene.world_bounds();
    if (bounds.empty()) {
        for (std::size_t i = 0; i < maps_.size(); ++i) {
            maps_[i] = LightMap{};
            maps_[i].fingerprint = fingerprints[i];
        }
        return;
    }
    const gpu::ShaderProgram& program =
        context.shaders.get({"passes/shadow_depth.vert", "passes/shadow_depth.frag", {}});
    program.use();
    framebuffer_.set_draw_buffers(0);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, size, size);
    // Both faces cast shadows: closed meshes and open single-sided walls alike.
    context.state.apply({.depth_test = true, .depth_write = true, .depth_func = GL_LESS, .cull = gpu::Cull::none});

    for (std::size_t i = 0; i < lights.size(); ++i) {
        const scene::Light& light = lights[i];
        LightMap& map = maps_[i];
        if (map.fingerprint == fingerprints[i]) continue;  // its light did not move or reshape
        map.fingerprint = fingerprints[i];
        map.valid = has_power(light);
        if (!map.valid) {
            map.depth = gpu::Texture();
            continue;
        }
        ++maps_drawn_;
        map.type = light.type;
        const GLenum target = light.type == scene::LightType::point ? GL_TEXTURE_CUBE_MAP : GL_TEXTURE_2D;
        if (!map.depth || map.depth.width() != size || map.depth.desc().target != target) {
            map.depth = make_depth_map(target, size);
        }
        const float far_depth = 1.0f;
        if (light.type == scene::LightType::point) {
            map.far = scene::far_plane_distance(bounds, light.position);
            map.texel_angle = 2.0f / static_cast<float>(size);  // 90-degree faces
            const glm::mat4 projection = glm::perspective(glm::radians(90.0f), 1.0f, map.far * 1e-4f, map.far);
            static const glm::vec3 forward[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            static const glm::vec3 up[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
            program.set("u_store_distance", 1);
            program.set("u_light_position", light.position);
            program.set("u_far", map.far);
            for (int face = 0; face < 6; ++face) {
                framebuffer_.attach_depth_layer(map.depth, face);
                framebuffer_.check_complete("a point-light shadow cube face");
                glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
                render_view(context, program,
                            projection * glm::lookAt(light.position, light.position + forward[face], up[face]));
            }
            continue;
        }
        framebuffer_.attach_depth(map.depth);
        framebuffer_.check_complete("a shadow map");
        glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
        const glm::vec3 direction = glm::normalize(light.direction);
        if (light.type == scene::LightType::spot) {
            map.far = scene::far_plane_distance(bounds, light.position);
            const float half_angle = std::clamp(light.outer_cone, 0.001f, 1.5533f);  // < 89 degrees
            map.texel_angle = 2.0f * std::tan(half_angle) / static_cast<float>(size);
            map.view_projection = glm::perspective(2.0f * half_angle, 1.0f, map.far * 1e-4f, map.far) *
                                  glm::lookAt(light.position, light.position + direction, up_for(direction));
            program.set("u_store_distance", 1);
            program.set("u_light_position", light.position);
            program.set("u_far", map.far);
        } else {
            const glm::vec3 center = bounds.center();
            const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-6f);
            map.far = 3.0f * radius;
            map.texel_world = 2.0f * radius / static_cast<float>(size);
            map.view_projection = glm::ortho(-radius, radius, -radius, radius, radius * 0.5f, map.far) *
                                  directional_view(center, direction, 2.0f * radius);
            program.set("u_store_distance", 0);
        }
        render_view(context, program, map.view_projection);
    }
}

bool ShadowMaps::has_map(std::size_t light_index) const {
    return light_index < maps_.size() && maps_[light_index].valid;
}

void ShadowMaps::bind(const gpu::ShaderProgram& program, std::size_t light_index) const {
    BOUNCE_CHECK(has_map(light_index), "light {} has no shadow map", light_index);
    const LightMap& map = maps_[light_index];
    program.set("u_shadows_enabled", 1);
    program.set("u_light_view_proj", map.view_projection);
    program.set("u_shadow_far", map.far);
    program.set("u_shadow_texel_angle", map.texel_angle);
    program.set("u_shadow_texel_world", map.texel_world);
    const GLuint unit = map.type == scene::LightType::point ? BOUNCE_UNIT_SHADOW_CUBE : BOUNCE_UNIT_SHADOW_2D;
    glBindTextureUnit(unit, map.depth.id());
    glBindSampler(unit, 0);
}

std::uint64_t ShadowMaps::bytes_for(const scene::Scene& scene, int size) {
    return light_views_with_power(scene) * static_cast<std::uint64_t>(size) * static_cast<std::uint64_t>(size) * 4;
}

std::size_t ShadowMaps::bytes() const {
    std::size_t total = 0;
    for (const auto& map : maps_) total += map.depth.bytes();
    return total;
}

std::size_t ShadowMaps::map_count() const {
    return static_cast<std::size_t>(std::count_if(maps_.begin(), maps_.end(), [](const LightMap& m) { return m.valid; }));
}

}  // namespace bounce::passes
