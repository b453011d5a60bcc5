#include "server/scene_requests.hpp"

#include "protocol/protocol.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "renderer/scene/units.hpp"
#include "server/frame_json.hpp"
#include "server/request_error.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/component_wise.hpp>

#include <algorithm>
#include <cmath>

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::ErrorCode;

json vec3_json(const glm::vec3& v) { return json::array({v.x, v.y, v.z}); }

json mutated(SceneEntry& entry) {
    ++entry.version;
    return {{"scene_version", entry.version}};
}

std::size_t object_index(const scene::Scene& scene, const ObjectRef& object) {
    if (const auto* index = std::get_if<std::uint64_t>(&object)) {
        if (*index < scene.objects.size()) return static_cast<std::size_t>(*index);
        if (scene.objects.empty()) {
            throw RequestError(ErrorCode::not_found, fmt::format("scene '{}' has no objects", scene.name), "object");
        }
        throw RequestError(ErrorCode::not_found,
                           fmt::format("object index {} is outside 0..{}", *index, scene.objects.size() - 1), "object");
    }
    const auto& name = std::get<std::string>(object);
    if (const auto index = scene.find_object(name)) return *index;
    throw RequestError(ErrorCode::not_found, fmt::format("scene '{}' has no object '{}'", scene.name, name), "object");
}

json describe_light(const scene::Light& light) {
    static const char* types[] = {"point", "spot", "directional"};
    return {{"name", light.name}, {"type", types[static_cast<int>(light.type)]}, {"position", vec3_json(light.position)},
            {"direction", vec3_json(light.direction)}, {"color", vec3_json(light.color)},
            {"intensity", scene::photometric_from_radiometric(light.intensity)},  // cd or lux, as light.set takes
            {"inner_cone_deg", glm::degrees(light.inner_cone)},
            {"outer_cone_deg", glm::degrees(light.outer_cone)}};
}

}  // namespace

std::filesystem::path resolve_in_root(const std::filesystem::path& root, const std::string& relative) {
    namespace fs = std::filesystem;
    const fs::path requested(relative);
    if (relative.empty() || requested.is_absolute()) {
        throw protocol::FieldError("path", fmt::format("path '{}' must be relative to the scene root", relative));
    }
    for (const auto& part : requested) {
        if (part == "..") throw protocol::FieldError("path", fmt::format("path '{}' may not contain '..'", relative));
    }
    std::error_code error;
    const fs::path canonical_root = fs::canonical(root, error);
    if (error) throw RequestError(ErrorCode::internal, fmt::format("scene root '{}': {}", root.string(), error.message()));
    const fs::path resolved = fs::weakly_canonical(canonical_root / requested, error);
    if (error) throw RequestError(ErrorCode::not_found, fmt::format("path '{}': {}", relative, error.message()), "path");
    // Symlinks are followed by canonicalization: what matters is where the file really is.
    const auto [root_end, unused] = std::mismatch(canonical_root.begin(), canonical_root.end(), resolved.begin(), resolved.end());
    if (root_end != canonical_root.end()) {
        throw protocol::FieldError("path", fmt::format("path '{}' leads outside the scene root", relative));
    }
    if (!fs::is_regular_file(resolved)) {
        throw RequestError(ErrorCode::not_found, fmt::format("no scene file '{}' under the scene root", relative), "path");
    }
    return resolved;
}

json load_scene(SceneRegistry& registry, const SceneRoot& root, const LoadOrder& order,
                std::span<const std::uint8_t> attachment) {
    if (!registry.entries().count(order.name) && registry.entries().size() >= root.max_scenes) {
        throw RequestError(ErrorCode::resource_exhausted,
                           fmt::format("the daemon holds {} scenes, its limit (--max-scenes): unload one first",
                                       registry.entries().size()), "name");
    }
    const scene::ImportLimits limits{root.max_scene_bytes};
    scene::Scene loaded;
    std::string source;
    if (order.path) {
        if (!root.root) {
            throw RequestError(ErrorCode::unsupported, "this daemon has no --scene-root: load by path is off", "path");
        }
        loaded = scene::import_gltf_file(resolve_in_root(*root.root, *order.path), limits);
        source = *order.path;
    } else if (order.upload) {
        loaded = scene::import_glb_memory(attachment, order.name, limits);
        source = "upload";
    } else {
        try {
            loaded = scene::make_builtin_scene(order.builtin.value());
        } catch (const InputError& error) {
            throw protocol::FieldError("builtin", error.what());
        }
        source = "builtin";
    }
    // Objects declared movable: methods with precomputed structures prepare them for motion now.
    declare_dynamic(loaded, order.dynamic);
    const auto warnings = loaded.warnings;
    SceneEntry& entry = registry.put(order.name, std::move(loaded), source);
    return {{"scene", order.name}, {"scene_version", entry.version}, {"warnings", warnings},
            {"objects", entry.scene->objects.size()}, {"triangles", entry.scene->triangle_count()}};
}

json unload_scene(SceneRegistry& registry, const SceneNameOrder& order) {
    if (!registry.remove(order.name)) {
        throw RequestError(ErrorCode::not_found, fmt::format("no scene '{}'", order.name), "name");
    }
    return json::object();
}

json list_scenes(SceneRegistry& registry) {
    json scenes = json::array();
    for (const auto& [name, entry] : registry.entries()) {
        std::size_t bytes = 0;
        for (const auto& structure : entry.resources->resident()) bytes += structure.bytes;
        scenes.push_back({{"name", name}, {"objects", entry.scene->objects.size()},
                          {"triangles", entry.scene->triangle_count()}, {"resident_bytes", bytes},
                          {"scene_version", entry.version}, {"source", entry.source}});
    }
    return {{"scenes", scenes}};
}

json describe_scene(SceneRegistry& registry, const SceneNameOrder& order) {
    SceneEntry& entry = registry.get(order.name);
    const scene::Scene& scene = *entry.scene;
    json objects = json::array();
    for (const auto& object : scene.objects) {
        const scene::Aabb bounds = object.mesh >= 0 ? object.world_bounds(scene.meshes[object.mesh]) : scene::Aabb();
        const float* m = glm::value_ptr(object.transform);
        objects.push_back({{"name", object.name}, {"bounds_min", vec3_json(bounds.min)},
                           {"bounds_max", vec3_json(bounds.max)}, {"transform", std::vector<float>(m, m + 16)}});
    }
    json lights = json::array();
    for (const auto& light : scene.lights) lights.push_back(describe_light(light));
    json cameras = json::array();
    for (const auto& camera : scene.cameras) {
        cameras.push_back({{"name", camera.name}, {"position", vec3_json(camera.position)},
                           {"forward", vec3_json(camera.forward())}, {"fov_deg", glm::degrees(camera.vertical_fov)}});
    }
    return {{"scene", order.name}, {"scene_version", entry.version}, {"objects", objects}, {"lights", lights},
            {"cameras", cameras}, {"materials", scene.materials.size()}, {"triangles", scene.triangle_count()},
            {"warnings", scene.warnings}, {"resident", resident_json(entry.resources->resident())}};
}

// ------------------------------------------------------------------------------------------------
// The scene-state orders on a scene alone.

void declare_dynamic(scene::Scene& loaded, const std::vector<std::string>& names) {
    for (const std::string& name : names) {
        const auto index = loaded.find_object(name);
        if (!index) {
            throw RequestError(ErrorCode::not_found, fmt::format("scene has no object '{}' to declare dynamic", name),
                               "dynamic");
        }
        loaded.objects[*index].dynamic = true;
    }
}

namespace {

// Refuses a transform that would take `object` past max_world_coordinate on any axis (or to
// infinity): past it, what a render derives from the scene would not stay finite.
void check_reach(const scene::Scene& scene, const scene::Object& object, const glm::mat4& transform,
                 const TransformOrder& order) {
    if (object.mesh < 0 || static_cast<std::size_t>(object.mesh) >= scene.meshes.size()) return;
    const scene::Aabb bounds = scene.meshes[static_cast<std::size_t>(object.mesh)].bounds.transformed(transform);
    if (bounds.empty()) return;
    const float reach = glm::compMax(glm::max(glm::abs(bounds.min), glm::abs(bounds.max)));
    if (reach <= scene::max_world_coordinate) return;  // false for NaN too
    const char* field = order.matrix ? "matrix" : order.scale ? "scale" : order.translation ? "translation" : "rotation_deg";
    throw protocol::FieldError(field, fmt::format("the transform takes object '{}' to {:g} m from the origin, past the "
                                                  "limit of {:g} m", object.name, reach, scene::max_world_coordinate));
}

}  // namespace

void apply_transform(scene::Scene& scene, const TransformOrder& order) {
    const std::size_t index = object_index(scene, order.object);
    scene::Object& object = scene.objects[index];
    if (order.matrix) {
        check_reach(scene, object, *order.matrix, order);
        object.transform = *order.matrix;
        scene.fit_bounds(index);
        return;
    }
    // TRS about the object's origin, relative to how it was loaded.
    glm::mat4 trs(1.0f);
    if (order.translation) trs = glm::translate(trs, *order.translation);
    if (order.rotation_deg) {
        const glm::vec3 r = glm::radians(*order.rotation_deg);
        trs = glm::rotate(trs, r.z, {0, 0, 1});
        trs = glm::rotate(trs, r.y, {0, 1, 0});
        trs = glm::rotate(trs, r.x, {1, 0, 0});
    }
    if (order.scale) trs = glm::scale(trs, glm::vec3(*order.scale));
    const glm::vec3 origin(object.initial_transform[3]);
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), -origin) * object.initial_transform;
    const glm::mat4 transform = glm::translate(glm::mat4(1.0f), origin) * trs * local;
    check_reach(scene, object, transform, order);
    object.transform = transform;
    scene.fit_bounds(index);
}

void apply_light(scene::Scene& scene, const LightOrder& order) {
    auto& lights = scene.lights;
    const auto existing = scene.find_light(order.light);
    scene::Light light = existing ? lights[*existing] : scene::Light{};
    // A new light has glTF's default intensity, 1 cd (or 1 lx): a light set over the protocol means
    // what the same numbers in a file mean.
    if (!existing) light.intensity = static_cast<float>(scene::radiometric_from_photometric(1.0));
    light.name = order.light;
    if (order.type) light.type = *order.type;
    if (order.position) light.position = *order.position;
    if (order.direction) light.direction = *order.direction;
    if (order.color) light.color = *order.color;
    if (order.intensity) light.intensity = static_cast<float>(scene::radiometric_from_photometric(*order.intensity));
    if (order.inner_cone) light.inner_cone = *order.inner_cone;
    if (order.outer_cone) light.outer_cone = *order.outer_cone;
    if (light.inner_cone > light.outer_cone) {
        throw protocol::FieldError("inner_cone_deg", "field 'inner_cone_deg' exceeds 'outer_cone_deg'");
    }
    if (existing) {
        lights[*existing] = light;
    } else {
        if (lights.size() >= kMaxLights) {
            throw RequestError(ErrorCode::too_large, fmt::format("a scene holds at most {} lights", kMaxLights), "light");
        }
        lights.push_back(light);
    }
}

void apply_remove_light(scene::Scene& scene, const RemoveLightOrder& order) {
    const auto index = scene.find_light(order.light);
    if (!index) throw RequestError(ErrorCode::not_found, fmt::format("scene has no light '{}'", order.light), "light");
    scene.lights.erase(scene.lights.begin() + static_cast<std::ptrdiff_t>(*index));
}

scene::Camera camera_from(const scene::Scene& scene, const CameraOrder& order) {
    const auto& cameras = scene.cameras;
    if (order.camera) {
        const auto index = scene.find_camera(*order.camera);
        if (!index) throw RequestError(ErrorCode::not_found, fmt::format("scene has no camera '{}'", *order.camera), "camera");
        return cameras[*index];
    }
    scene::Camera camera = cameras.empty() ? scene::Camera{} : cameras.front();
    if (order.position) camera.position = *order.position;
    if (order.look_at) {
        const glm::vec3 target = *order.look_at;
        if (!(glm::length(target - camera.position) > 1e-12f)) {
            throw protocol::FieldError("look_at", "field 'look_at' equals the camera position");
        }
        const glm::vec3 forward = glm::normalize(target - camera.position);
        const glm::vec3 up = std::abs(forward.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
        camera = scene::Camera::look_at(camera.position, target, up, camera.vertical_fov);
    } else if (order.orientation) {
        camera.orientation = *order.orientation;
    }
    if (order.fov) camera.vertical_fov = *order.fov;
    camera.name = cameras.empty() ? "default" : cameras.front().name;
    return camera;
}

void apply_camera(scene::Scene& scene, const CameraOrder& order) {
    auto& cameras = scene.cameras;
    if (order.camera) {
        const auto index = scene.find_camera(*order.camera);
        if (!index) throw RequestError(ErrorCode::not_found, fmt::format("scene has no camera '{}'", *order.camera), "camera");
        const auto at = cameras.begin() + static_cast<std::ptrdiff_t>(*index);
        std::rotate(cameras.begin(), at, at + 1);
        return;
    }
    scene::Camera camera = camera_from(scene, order);
    if (cameras.empty()) {
        cameras.push_back(camera);
    } else {
        cameras.front() = camera;
    }
}

// ------------------------------------------------------------------------------------------------
// The same on the registry's scenes: each mutation bumps the scene's version.

namespace {
template <typename Order, typename Apply>
json mutate(SceneRegistry& registry, const Order& order, Apply&& apply) {
    SceneEntry& entry = registry.get(order.scene);
    apply(*entry.scene, order);
    return mutated(entry);
}
}  // namespace

json set_object_transform(SceneRegistry& registry, const TransformOrder& order) {
    return mutate(registry, order, apply_transform);
}

json set_light(SceneRegistry& registry, const LightOrder& order) { return mutate(registry, order, apply_light); }

json remove_light(SceneRegistry& registry, const RemoveLightOrder& order) {
    return mutate(registry, order, apply_remove_light);
}

json set_camera(SceneRegistry& registry, const CameraOrder& order) { return mutate(registry, order, apply_camera); }

}  // namespace bounce::server
