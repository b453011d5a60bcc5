#include "renderer/passes/light_geometry.hpp"

#include "renderer/base/hash.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace bounce::passes {
namespace {

void add_geometry(Hasher& hash, const scene::Scene& scene) {
    for (const scene::Object& object : scene.objects) {
        hash.add(object.mesh);
        hash.add(object.transform);
    }
    hash.add(scene.objects.size());
}

}  // namespace

bool has_power(const scene::Light& light) {
    const glm::vec3 radiant = light.radiant();
    return radiant.x > 0.0f || radiant.y > 0.0f || radiant.z > 0.0f;
}

std::uint64_t light_views_with_power(const scene::Scene& scene) {
    std::uint64_t views = 0;
    for (const scene::Light& light : scene.lights) {
        if (has_power(light)) views += light.type == scene::LightType::point ? 6 : 1;
    }
    return views;
}

glm::mat4 directional_view(const glm::vec3& center, const glm::vec3& direction, float distance) {
    return glm::lookAt(-direction * distance, glm::vec3(0.0f), up_for(direction)) * glm::translate(glm::mat4(1.0f), -center);
}

glm::vec3 up_for(const glm::vec3& direction) {
    return std::abs(direction.y) > 0.99f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
}

std::uint64_t geometry_fingerprint(const scene::Scene& scene) {
    Hasher hash;
    add_geometry(hash, scene);
    return hash.value();
}

std::uint64_t light_view_fingerprint(const scene::Scene& scene, int size, bool with_power) {
    Hasher hash;
    hash.add(size);
    for (const scene::Light& light : scene.lights) {
        hash.add(light.type);
        hash.add(light.position);
        hash.add(light.direction);
        if (with_power) {
            hash.add(light.radiant());
        } else {
            hash.add(has_power(light));  // power 0 <-> > 0 decides whether a map exists
        }
        hash.add(light.inner_cone);
        hash.add(light.outer_cone);
    }
    hash.add(scene.lights.size());
    add_geometry(hash, scene);
    return hash.value();
}

std::uint64_t shadow_map_fingerprint(const scene::Light& light, std::uint64_t geometry, int size) {
    Hasher hash;
    hash.add(geometry).add(size).add(light.type).add(light.position).add(light.direction);
    hash.add(light.inner_cone).add(light.outer_cone).add(has_power(light));
    return hash.value();
}

std::optional<float> common_power_scale(const std::vector<scene::Light>& before, const std::vector<scene::Light>& now) {
    if (before.size() != now.size()) return std::nullopt;
    std::optional<double> factor;
    for (std::size_t i = 0; i < now.size(); ++i) {
        if (shadow_map_fingerprint(before[i], 0, 0) != shadow_map_fingerprint(now[i], 0, 0)) return std::nullopt;
        const glm::vec3 from = before[i].radiant(), to = now[i].radiant();
        for (int c = 0; c < 3; ++c) {
            if (from[c] == 0.0f) {
                if (to[c] != 0.0f) return std::nullopt;
                continue;
            }
            const double channel = static_cast<double>(to[c]) / static_cast<double>(from[c]);
            if (!factor) factor = channel;
            // Equal to float precision: colours given as numbers may round apart.
            if (std::abs(channel - *factor) > 1e-6 * std::abs(*factor)) return std::nullopt;
        }
    }
    if (!factor) return 1.0f;  // no light with power, before or now
    if (!(*factor > 0.0) || !std::isfinite(*factor)) return std::nullopt;
    return static_cast<float>(*factor);
}

bool emits_light(const scene::Scene& scene) {
    return std::any_of(scene.materials.begin(), scene.materials.end(),
                       [](const scene::Material& material) { return material.emissive != glm::vec3(0.0f); });
}

void set_light_uniforms(const gpu::ShaderProgram& program, const scene::Light& light) {
    program.set("u_light_type", static_cast<int>(light.type));
    program.set("u_light_position", light.position);
    program.set("u_light_direction", glm::normalize(light.direction));
    program.set("u_light_radiant", light.radiant());
    program.set("u_light_cos_inner", std::cos(light.inner_cone));
    program.set("u_light_cos_outer", std::cos(light.outer_cone));
}

}  // namespace bounce::passes
