#include "renderer/passes/light_view_maps.hpp"

#include "common/shared_layout.h"
#include "renderer/passes/light_geometry.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace bounce::passes {

std::vector<LightViewMaps::View> light_views(const scene::Light& light, std::size_t index, const scene::Aabb& bounds,
                                             int size) {
    std::vector<LightViewMaps::View> views;
    const float texels = static_cast<float>(size);
    if (light.type == scene::LightType::point) {
        const float far = scene::far_plane_distance(bounds, light.position);
        const glm::mat4 projection = glm::perspective(glm::radians(90.0f), 1.0f, far * 1e-4f, far);
        static const glm::vec3 forward[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        static const glm::vec3 up[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
        for (int face = 0; face < 6; ++face) {
            const float texel = 2.0f / texels;  // tan(45 degrees) = 1
            views.push_back({index, projection * glm::lookAt(light.position, light.position + forward[face], up[face]),
                             forward[face], light.position, false, texel * texel});
        }
        return views;
    }
    const glm::vec3 direction = glm::normalize(light.direction);
    if (light.type == scene::LightType::spot) {
        const float far = scene::far_plane_distance(bounds, light.position);
        const float half_angle = std::clamp(light.outer_cone, 0.001f, 1.5533f);  // < 89 degrees
        const float texel = 2.0f * std::tan(half_angle) / texels;
        views.push_back({index,
                         glm::perspective(2.0f * half_angle, 1.0f, far * 1e-4f, far) *
                             glm::lookAt(light.position, light.position + direction, up_for(direction)),
                         direction, light.position, false, texel * texel});
        return views;
    }
    const glm::vec3 center = bounds.center();
    const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-6f);
    const float texel = 2.0f * radius / texels;
    views.push_back({index,
                     glm::ortho(-radius, radius, -radius, radius, radius * 0.5f, 3.0f * radius) *
                         directional_view(center, direction, 2.0f * radius),
                     direction, center - direction * (2.0f * radius), true, texel * texel});
    return views;
}

namespace {
// Whether every corner of the box lies outside one and the same clip plane of the view (then no
// surface inside the box can reach the view). Exact in homogeneous clip space, corners behind the
// eye included.
bool frustum_misses(const glm::mat4& view_projection, const scene::Aabb& bounds) {
    int outside[6] = {0, 0, 0, 0, 0, 0};
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec4 c = view_projection * glm::vec4(bounds.corner(corner), 1.0f);
        outside[0] += c.x > c.w;
        outside[1] += c.x < -c.w;
        outside[2] += c.y > c.w;
        outside[3] += c.y < -c.w;
        outside[4] += c.z > c.w;
        outside[5] += c.z < -c.w;
    }
    return std::any_of(std::begin(outside), std::end(outside), [](int count) { return count == 8; });
}
}  // namespace

std::uint64_t LightViewMaps::bytes_for(const scene::Scene& scene, int size) {
    return std::max<std::uint64_t>(light_views_with_power(scene), 1) * static_cast<std::uint64_t>(size) * static_cast<std::uint64_t>(size) *
           (16 + 8 + 4 + 4);
}

bool LightViewMaps::render(const PassContext& context, int size) {
    const std::uint64_t fingerprint = light_view_fingerprint(context.scene, size, /*with_power=*/false);
    if (fingerprint == fingerprint_ && size == size_) return false;
    gpu::GpuTimers::Scope timing(context.timers, "light_view_maps");
    fingerprint_ = fingerprint;
    ++frames_drawn_;
    views_.clear();
    views_culled_ = 0;
    const scene::Aabb bounds = context.scene.world_bounds();
    if (!bounds.empty()) {
        for (std::size_t i = 0; i < context.scene.lights.size(); ++i) {
            if (!has_power(context.scene.lights[i])) continue;  // no power: no photons
            for (const View& view : light_views(context.scene.lights[i], i, bounds, size)) {
                if (frustum_misses(view.view_projection, bounds)) {
                    ++views_culled_;
                } else {
                    views_.push_back(view);
                }
            }
        }
    }
    const int layers = std::max<int>(1, static_cast<int>(views_.size()));
    if (size != size_ || position_.desc().depth != layers) {
        size_ = size;
        position_ = gpu::Texture({GL_TEXTURE_2D_ARRAY, GL_RGBA32F, size, size, layers});
        normal_ = gpu::Texture({GL_TEXTURE_2D_ARRAY, GL_RGBA16F, size, size, layers});
        albedo_ = gpu::Texture({GL_TEXTURE_2D_ARRAY, GL_RGBA8, size, size, layers});
        depth_ = gpu::Texture({GL_TEXTURE_2D_ARRAY, GL_DEPTH_COMPONENT32F, size, size, layers});
        for (gpu::Texture* texture : {&position_, &normal_, &albedo_}) texture->set_filter(GL_NEAREST, GL_NEAREST);
    }
    const gpu::ShaderProgram& program = context.shaders.get({"passes/gbuffer.vert", "passes/light_view.frag", {}});
    program.use();
    framebuffer_.set_draw_buffers(3);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, size, size);
    // Both faces: the back of an open wall occludes as much as its front (it reflects nothing:
    // light_view.frag).
    context.state.apply({.depth_test = true, .depth_write = true, .depth_func = GL_LESS, .cull = gpu::Cull::none});
    const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    const float far_depth = 1.0f;
    for (std::size_t v = 0; v < views_.size(); ++v) {
        const int layer = static_cast<int>(v);
        framebuffer_.attach_color_layer(0, position_, layer);
        framebuffer_.attach_color_layer(1, normal_, layer);
        framebuffer_.attach_color_layer(2, albedo_, layer);
        framebuffer_.attach_depth_layer(depth_, layer);
        framebuffer_.check_complete("a light-view map");
        for (int target = 0; target < 3; ++target) glClearNamedFramebufferfv(framebuffer_.id(), GL_COLOR, target, zero);
        glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
        program.set("u_view_proj", views_[v].view_projection);
        program.set("u_light_position", context.scene.lights[views_[v].light].position);
        context.gpu_scene.for_each_primitive([&](const scene::Object& object, const gpu::GpuPrimitive& primitive) {
            gpu::set_object_transform(program, object.transform);
            context.gpu_scene.bind_material(program, primitive.material);
            gpu::GpuScene::draw(primitive);
        });
    }
    return true;
}

std::size_t LightViewMaps::bytes() const {
    return position_.bytes() + normal_.bytes() + albedo_.bytes() + depth_.bytes();
}

}  // namespace bounce::passes
