#include "server/scene_requests.hpp"

#include "protocol/protocol.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "server/request_error.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <cmath>

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::ErrorCode;

json vec3_json(const glm::vec3& v) { return json::array({v.x, v.y, v.z}); }

glm::vec3 vec3_from(const std::vector<double>& v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

SceneEntry& scene_of(SceneRegistry& registry, const json& body) {
    return registry.get(protocol::get_string(body, "scene"));
}

json mutated(SceneEntry& entry) {
    ++entry.version;
    return {{"scene_version", entry.version}};
}

std::size_t object_index(const scene::Scene& scene, const json& body) {
    const auto& field = body.contains("object") ? body["object"] : json();
    if (field.is_number_integer()) {
        const auto index = field.get<std::int64_t>();
        if (index >= 0 && static_cast<std::size_t>(index) < scene.objects.size()) return static_cast<std::size_t>(index);
        throw RequestError(ErrorCode::not_found,
                           fmt::format("object index {} is outside 0..{}", index, scene.objects.size() - 1), "object");
    }
    const std::string name = protocol::get_string(body, "object");
    if (const auto index = scene.find_object(name)) return *index;
    throw RequestError(ErrorCode::not_found, fmt::format("scene '{}' has no object '{}'", scene.name, name), "object");
}

json describe_light(const scene::Light& light) {
    static const char* types[] = {"point", "spot", "directional"};
    return {{"name", light.name}, {"type", types[static_cast<int>(light.type)]}, {"position", vec3_json(light.position)},
            {"direction", vec3_json(light.direction)}, {"color", vec3_json(light.color)},
            {"intensity", light.intensity}, {"inner_cone_deg", glm::degrees(light.inner_cone)},
            {"outer_cone_deg", glm::degrees(light.outer_cone)}};
}

scene::LightType parse_light_type(const std::string& name) {
    if (name == "point") return scene::LightType::point;
    if (name == "spot") return scene::LightType::spot;
    if (name == "directional") return scene::LightType::directional;
    throw protocol::FieldError("type", fmt::format("field 'type' is '{}', expected point, spot or directional", name));
}

float finite_float(double value, const char* field) {
    const auto f = static_cast<float>(value);
    if (!std::isfinite(f)) throw protocol::FieldError(field, fmt::format("field '{}' does not fit a float", field));
    return f;
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

json load_scene(SceneRegistry& registry, const SceneRoot& root, const json& body, std::span<const std::uint8_t> attachment) {
    const std::string name = protocol::get_string(body, "name");
    if (name.empty() || name.size() > 128) throw protocol::FieldError("name", "field 'name' must have 1 to 128 characters");
    const auto path = protocol::get_optional_string(body, "path");
    scene::Scene loaded;
    std::string source;
    if (path) {
        if (!root.root) {
            throw RequestError(ErrorCode::unsupported, "this daemon has no --scene-root: load by path is off", "path");
        }
        loaded = scene::import_gltf_file(resolve_in_root(*root.root, *path));
        source = *path;
    } else if (!attachment.empty()) {
        loaded = scene::import_glb_memory(attachment, name);
        source = "upload";
    } else if (const auto builtin = protocol::get_optional_string(body, "builtin")) {
        try {
            loaded = scene::make_builtin_scene(*builtin);
        } catch (const InputError& error) {
            throw protocol::FieldError("builtin", error.what());
        }
        source = "builtin";
    } else {
        throw protocol::FieldError("path", "scene.load needs a 'path', a 'builtin' scene or a .glb attachment");
    }
    // Objects declared movable: methods with precomputed structures prepare them for motion now.
    if (body.contains("dynamic")) {
        const json& dynamic = body["dynamic"];
        if (!dynamic.is_array()) throw protocol::FieldError("dynamic", "field 'dynamic' must be an array of object names");
        for (const json& entry : dynamic) {
            if (!entry.is_string()) throw protocol::FieldError("dynamic", "field 'dynamic' must be an array of object names");
            const auto index = loaded.find_object(entry.get<std::string>());
            if (!index) {
                throw RequestError(ErrorCode::not_found,
                                   fmt::format("scene has no object '{}' to declare dynamic", entry.get<std::string>()), "dynamic");
            }
            loaded.objects[*index].dynamic = true;
        }
    }
    const auto warnings = loaded.warnings;
    SceneEntry& entry = registry.put(name, std::move(loaded), source);
    return {{"scene", name}, {"scene_version", entry.version}, {"warnings", warnings},
            {"objects", entry.scene->objects.size()}, {"triangles", entry.scene->triangle_count()}};
}

json unload_scene(SceneRegistry& registry, const json& body) {
    const std::string name = protocol::get_string(body, "name");
    if (!registry.remove(name)) throw RequestError(ErrorCode::not_found, fmt::format("no scene '{}'", name), "name");
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

json describe_scene(SceneRegistry& registry, const json& body) {
    const std::string name = protocol::get_string(body, "name");
    SceneEntry& entry = registry.get(name);
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
    json resident = json::array();
    for (const auto& structure : entry.resources->resident()) {
        resident.push_back({{"structure", structure.name}, {"bytes", structure.bytes}, {"reason", structure.reason}});
    }
    return {{"scene", name}, {"scene_version", entry.version}, {"objects", objects}, {"lights", lights},
            {"cameras", cameras}, {"materials", scene.materials.size()}, {"triangles", scene.triangle_count()},
            {"warnings", scene.warnings}, {"resident", resident}};
}

json set_object_transform(SceneRegistry& registry, const json& body) {
    SceneEntry& entry = scene_of(registry, body);
    scene::Object& object = entry.scene->objects[object_index(*entry.scene, body)];
    glm::mat4 transform(1.0f);
    if (const auto matrix = protocol::get_optional_numbers(body, "matrix", 16)) {
        for (int i = 0; i < 16; ++i) glm::value_ptr(transform)[i] = finite_float((*matrix)[i], "matrix");
    } else {
        const auto translation = protocol::get_optional_numbers(body, "translation", 3);
        const auto rotation = protocol::get_optional_numbers(body, "rotation_deg", 3);
        const auto scale = protocol::get_optional_number(body, "scale");
        if (!translation && !rotation && !scale) {
            throw protocol::FieldError("matrix", "object.set_transform needs 'matrix' or any of 'translation', "
                                                 "'rotation_deg', 'scale'");
        }
        if (scale && (*scale <= 0.0 || *scale > 1e6)) {
            throw protocol::FieldError("scale", fmt::format("field 'scale' is {}, outside (0, 1e6]", *scale));
        }
        // TRS about the object's origin, relative to how it was loaded.
        glm::mat4 trs(1.0f);
        if (translation) trs = glm::translate(trs, vec3_from(*translation));
        if (rotation) {
            const glm::vec3 r = glm::radians(vec3_from(*rotation));
            trs = glm::rotate(trs, r.z, {0, 0, 1});
            trs = glm::rotate(trs, r.y, {0, 1, 0});
            trs = glm::rotate(trs, r.x, {1, 0, 0});
        }
        if (scale) trs = glm::scale(trs, glm::vec3(static_cast<float>(*scale)));
        const glm::vec3 origin(object.initial_transform[3]);
        const glm::mat4 local = glm::translate(glm::mat4(1.0f), -origin) * object.initial_transform;
        transform = glm::translate(glm::mat4(1.0f), origin) * trs * local;
    }
    object.transform = transform;
    return mutated(entry);
}

json set_light(SceneRegistry& registry, const json& body) {
    SceneEntry& entry = scene_of(registry, body);
    const std::string name = protocol::get_string(body, "light");
    auto& lights = entry.scene->lights;
    const auto existing = entry.scene->find_light(name);
    scene::Light light = existing ? lights[*existing] : scene::Light{};
    light.name = name;
    if (const auto type = protocol::get_optional_string(body, "type")) light.type = parse_light_type(*type);
    if (const auto v = protocol::get_optional_numbers(body, "position", 3)) light.position = vec3_from(*v);
    if (const auto v = protocol::get_optional_numbers(body, "direction", 3)) {
        const glm::vec3 direction = vec3_from(*v);
        if (!(glm::length(direction) > 1e-12f)) throw protocol::FieldError("direction", "field 'direction' is zero");
        light.direction = glm::normalize(direction);
    }
    if (const auto v = protocol::get_optional_numbers(body, "color", 3)) {
        light.color = vec3_from(*v);
        if (glm::any(glm::lessThan(light.color, glm::vec3(0.0f)))) {
            throw protocol::FieldError("color", "field 'color' has a negative component");
        }
    }
    if (const auto v = protocol::get_optional_number(body, "intensity")) {
        if (*v < 0.0 || *v > 1e12) throw protocol::FieldError("intensity", fmt::format("field 'intensity' is {}, outside [0, 1e12]", *v));
        light.intensity = finite_float(*v, "intensity");
    }
    if (const auto v = protocol::get_optional_number(body, "inner_cone_deg")) {
        if (*v < 0.0 || *v > 90.0) throw protocol::FieldError("inner_cone_deg", "field 'inner_cone_deg' is outside [0, 90]");
        light.inner_cone = glm::radians(static_cast<float>(*v));
    }
    if (const auto v = protocol::get_optional_number(body, "outer_cone_deg")) {
        if (*v < 0.0 || *v > 90.0) throw protocol::FieldError("outer_cone_deg", "field 'outer_cone_deg' is outside [0, 90]");
        light.outer_cone = glm::radians(static_cast<float>(*v));
    }
    if (light.inner_cone > light.outer_cone) {
        throw protocol::FieldError("inner_cone_deg", "field 'inner_cone_deg' exceeds 'outer_cone_deg'");
    }
    if (existing) {
        lights[*existing] = light;
    } else {
        if (lights.size() >= 256) throw RequestError(ErrorCode::too_large, "a scene holds at most 256 lights", "light");
        lights.push_back(light);
    }
    return mutated(entry);
}

json remove_light(SceneRegistry& registry, const json& body) {
    SceneEntry& entry = scene_of(registry, body);
    const std::string name = protocol::get_string(body, "light");
    const auto index = entry.scene->find_light(name);
    if (!index) throw RequestError(ErrorCode::not_found, fmt::format("scene has no light '{}'", name), "light");
    entry.scene->lights.erase(entry.scene->lights.begin() + static_cast<std::ptrdiff_t>(*index));
    return mutated(entry);
}

json set_camera(SceneRegistry& registry, const json& body) {
    SceneEntry& entry = scene_of(registry, body);
    auto& cameras = entry.scene->cameras;
    if (const auto name = protocol::get_optional_string(body, "camera")) {
        const auto index = entry.scene->find_camera(*name);
        if (!index) throw RequestError(ErrorCode::not_found, fmt::format("scene has no camera '{}'", *name), "camera");
        std::rotate(cameras.begin(), cameras.begin() + static_cast<std::ptrdiff_t>(*index), cameras.begin() + static_cast<std::ptrdiff_t>(*index) + 1);
        return mutated(entry);
    }
    scene::Camera camera = cameras.empty() ? scene::Camera{} : cameras.front();
    if (const auto v = protocol::get_optional_numbers(body, "position", 3)) camera.position = vec3_from(*v);
    if (const auto v = protocol::get_optional_numbers(body, "look_at", 3)) {
        const glm::vec3 target = vec3_from(*v);
        if (!(glm::length(target - camera.position) > 1e-12f)) {
            throw protocol::FieldError("look_at", "field 'look_at' equals the camera position");
        }
        const glm::vec3 forward = glm::normalize(target - camera.position);
        const glm::vec3 up = std::abs(forward.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
        camera = scene::Camera::look_at(camera.position, target, up, camera.vertical_fov);
    } else if (const auto q = protocol::get_optional_numbers(body, "orientation", 4)) {
        const glm::quat orientation(static_cast<float>((*q)[3]), static_cast<float>((*q)[0]), static_cast<float>((*q)[1]),
                                    static_cast<float>((*q)[2]));
        if (!(glm::length(orientation) > 1e-6f)) throw protocol::FieldError("orientation", "field 'orientation' is zero");
        camera.orientation = glm::normalize(orientation);
    }
    if (const auto fov = protocol::get_optional_number(body, "fov_deg")) {
        if (*fov <= 0.1 || *fov >= 179.0) throw protocol::FieldError("fov_deg", "field 'fov_deg' is outside (0.1, 179)");
        camera.vertical_fov = glm::radians(static_cast<float>(*fov));
    }
    camera.name = cameras.empty() ? "default" : cameras.front().name;
    if (cameras.empty()) {
        cameras.push_back(camera);
    } else {
        cameras.front() = camera;
    }
    return mutated(entry);
}

RenderOrder parse_render(const json& body, std::uint64_t max_pixels) {
    RenderOrder order;
    order.scene = protocol::get_string(body, "scene");
    order.camera = protocol::get_optional_string(body, "camera");
    RenderRequest& request = order.request;
    request.method = protocol::get_optional_string(body, "method").value_or("direct");
    request.preset = protocol::get_optional_string(body, "preset").value_or("medium");
    request.width = static_cast<int>(protocol::get_optional_integer(body, "width", 1, Renderer::kMaxDimension).value_or(512));
    request.height = static_cast<int>(protocol::get_optional_integer(body, "height", 1, Renderer::kMaxDimension).value_or(512));
    const std::uint64_t pixels = static_cast<std::uint64_t>(request.width) * static_cast<std::uint64_t>(request.height);
    if (pixels > max_pixels) {
        throw RequestError(ErrorCode::too_large,
                           fmt::format("{}x{} is {} pixels, above this daemon's limit of {}", request.width,
                                       request.height, pixels, max_pixels), "width");
    }
    if (body.contains("knobs")) {
        const json& knobs = body["knobs"];
        if (!knobs.is_object()) throw protocol::FieldError("knobs", "field 'knobs' must be an object of numbers");
        for (const auto& [name, value] : knobs.items()) {
            if (!value.is_number()) throw protocol::FieldError("knobs", fmt::format("knob '{}' must be a number", name));
            request.knobs[name] = value.get<double>();
        }
    }
    order.format = protocol::get_optional_string(body, "format").value_or("png");
    const auto format = image::parse_image_format(order.format);
    request.make_display_image = format != image::ImageFormat::exr;
    if (const auto exposure = protocol::get_optional_number(body, "exposure")) {
        if (std::abs(*exposure) > 64.0) throw protocol::FieldError("exposure", "field 'exposure' is outside [-64, 64] stops");
        request.display.exposure = static_cast<float>(*exposure);
    }
    if (const auto tone = protocol::get_optional_string(body, "tone")) request.display.curve = image::parse_tone_curve(*tone);
    order.jpeg_quality = static_cast<int>(protocol::get_optional_integer(body, "jpeg_quality", 1, 100).value_or(90));
    order.exr_half = protocol::get_optional_bool(body, "exr_half").value_or(false);
    if (const auto version = protocol::get_optional_integer(body, "min_scene_version", 0, INT64_MAX)) {
        order.min_scene_version = static_cast<std::uint64_t>(*version);
    }
    return order;
}

}  // namespace bounce::server
