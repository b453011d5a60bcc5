#include "renderer/scene/scene.hpp"

#include "renderer/base/error.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/string_cast.hpp>

#include <algorithm>
#include <cmath>

namespace bounce::scene {

Aabb Aabb::transformed(const glm::mat4& transform) const {
    Aabb out;
    if (empty()) return out;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p{(corner & 1) ? max.x : min.x, (corner & 2) ? max.y : min.y,
                          (corner & 4) ? max.z : min.z};
        out.extend(glm::vec3(transform * glm::vec4(p, 1.0f)));
    }
    return out;
}

glm::vec3 Material::dielectric_f0() const {
    const float r = (ior - 1.0f) / (ior + 1.0f);
    return glm::min(r * r * specular_color, glm::vec3(1.0f));
}

float Material::coverage(float alpha) const {
    switch (alpha_mode) {
    case AlphaMode::mask: return alpha < alpha_cutoff ? 0.0f : 1.0f;
    case AlphaMode::blend: return std::isnan(alpha) ? 0.0f : std::clamp(alpha, 0.0f, 1.0f);
    case AlphaMode::opaque: break;
    }
    return 1.0f;
}

bool Material::glossy() const {
    // A dielectric with specular 0 is pure Lambertian; otherwise the GGX lobe carries energy.
    return metallic > 0.0f || specular > 0.0f;
}

glm::mat4 Camera::view() const {
    return glm::lookAt(position, position + forward(), up());
}

glm::mat4 Camera::projection(float aspect, float far) const {
    const float f = z_far > 0.0f ? z_far : far;
    const float n = z_near > 0.0f ? z_near : f * 1e-4f;
    return glm::perspective(vertical_fov, aspect, n, std::max(f, n * 2.0f));
}

float Camera::far_plane_for(const Aabb& bounds) const {
    return bounds.empty() ? 1.0f : far_plane_distance(bounds, position);
}

float far_plane_distance(const Aabb& bounds, const glm::vec3& from) {
    return std::max(bounds.farthest_distance(from) * 1.05f, 1e-6f);
}

Camera Camera::look_at(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                       float vertical_fov) {
    Camera camera;
    camera.position = eye;
    // glm::lookAt builds world-to-view; its inverse rotation is the camera's orientation.
    const glm::mat4 view = glm::lookAt(eye, target, up);
    camera.orientation = glm::quat_cast(glm::inverse(glm::mat3(view)));
    camera.vertical_fov = vertical_fov;
    return camera;
}

// At radius / sin(fov / 2) from the centre the bounding sphere touches the top and bottom of the
// view cone (and fits across frames at least as wide as tall); 10% farther keeps what lies on the
// sphere off the frame's edge. An empty or flat-to-a-point box is framed as a unit sphere.
Camera framing_camera(const Aabb& bounds) {
    constexpr float fov = 0.8f;
    constexpr float margin = 1.1f;
    const glm::vec3 center = bounds.empty() ? glm::vec3(0.0f) : bounds.center();
    float radius = 0.5f * glm::length(bounds.extent());
    if (!(radius > 0.0f) || !std::isfinite(radius)) radius = 1.0f;
    const float distance = margin * radius / std::sin(0.5f * fov);
    return Camera::look_at(center + glm::vec3(0.0f, 0.0f, distance), center, glm::vec3(0.0f, 1.0f, 0.0f), fov);
}

Aabb Scene::world_bounds() const {
    Aabb bounds;
    for (const Object& object : objects) {
        if (object.mesh >= 0) bounds.extend(object.world_bounds(meshes[object.mesh]));
    }
    return bounds;
}

void Scene::fit_bounds(std::size_t index) {
    Object& object = objects.at(index);
    object.fitted_bounds = Aabb();
    object.fitted_transform = object.transform;
    if (object.mesh < 0 || static_cast<std::size_t>(object.mesh) >= meshes.size()) return;
    for (const Primitive& primitive : meshes[static_cast<std::size_t>(object.mesh)].primitives) {
        for (const glm::vec3& p : primitive.positions) object.fitted_bounds.extend(glm::vec3(object.transform * glm::vec4(p, 1.0f)));
    }
}

void Scene::fit_bounds() {
    for (std::size_t i = 0; i < objects.size(); ++i) fit_bounds(i);
}

const Material& Scene::default_material() {
    static const Material material = [] {
        Material m;
        m.name = "default";
        m.base_color = glm::vec4(0.8f, 0.8f, 0.8f, 1.0f);
        m.metallic = 0.0f;
        m.roughness = 1.0f;
        m.specular = 0.0f;
        return m;
    }();
    return material;
}

const Material& Scene::material(int index) const {
    if (index < 0 || index >= static_cast<int>(materials.size())) return default_material();
    return materials[index];
}

namespace {
template <typename T>
std::optional<std::size_t> find_by_name(const std::vector<T>& items, const std::string& name) {
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (items[i].name == name) return i;
    }
    return std::nullopt;
}
}  // namespace

std::optional<std::size_t> Scene::find_object(const std::string& wanted) const { return find_by_name(objects, wanted); }
std::optional<std::size_t> Scene::find_light(const std::string& wanted) const { return find_by_name(lights, wanted); }
std::optional<std::size_t> Scene::find_camera(const std::string& wanted) const { return find_by_name(cameras, wanted); }

std::size_t Scene::triangle_count() const {
    std::size_t count = 0;
    for (const Object& object : objects) {
        if (object.mesh < 0) continue;
        for (const Primitive& primitive : meshes[object.mesh].primitives) count += primitive.triangle_count();
    }
    return count;
}

bool Scene::has_glossy_material() const {
    for (const Object& object : objects) {
        if (object.mesh < 0) continue;
        for (const Primitive& primitive : meshes[object.mesh].primitives) {
            if (material(primitive.material).glossy()) return true;
        }
    }
    return false;
}

namespace {
bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::mat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}
}  // namespace

void validate_finite(const Scene& scene) {
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const Primitive& primitive = mesh.primitives[p];
            for (std::size_t v = 0; v < primitive.positions.size(); ++v) {
                if (!finite(primitive.positions[v])) {
                    throw InputError(fmt::format("mesh {} ('{}') primitive {}: vertex {} has a non-finite position {}",
                                                 m, mesh.name, p, v, glm::to_string(primitive.positions[v])));
                }
            }
            for (std::size_t v = 0; v < primitive.normals.size(); ++v) {
                if (!finite(primitive.normals[v])) {
                    throw InputError(fmt::format("mesh {} ('{}') primitive {}: vertex {} has a non-finite normal",
                                                 m, mesh.name, p, v));
                }
            }
        }
    }
    for (const Object& object : scene.objects) {
        if (!finite(object.transform)) {
            throw InputError(fmt::format("object '{}' has a non-finite transform", object.name));
        }
    }
    for (const Light& light : scene.lights) {
        if (!finite(light.position) || !finite(light.direction) || !finite(light.color) ||
            !std::isfinite(light.intensity)) {
            throw InputError(fmt::format("light '{}' has a non-finite parameter", light.name));
        }
    }
}

}  // namespace bounce::scene
