#include "server/orders.hpp"

#include "renderer/image/codec.hpp"
#include "renderer/methods/registry.hpp"
#include "server/request_error.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <cmath>

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::ErrorCode;
using protocol::FieldError;
using protocol::MessageType;

// The documented ranges of client numbers (docs/protocol.md, "Numbers"): wide enough for any scene
// the stability tests cover (1e-3 to 1e4 m), narrow enough that products of them stay finite in float.
constexpr double kMaxCoordinate = 1e7;   // positions, translations, look_at, matrix entries
constexpr double kMaxAngleDeg = 1e6;     // rotations
constexpr double kMaxColor = 1e6;        // light colour components

float finite_float(double value, const char* field) {
    const auto f = static_cast<float>(value);
    if (!std::isfinite(f)) throw FieldError(field, fmt::format("field '{}' does not fit a finite float", field));
    return f;
}

float bounded_float(double value, const char* field, double max_abs) {
    if (!(std::abs(value) <= max_abs)) {
        throw FieldError(field, fmt::format("field '{}' has {}, outside [-{:g}, {:g}]", field, value, max_abs, max_abs));
    }
    return finite_float(value, field);
}

std::optional<glm::vec3> optional_vec3(const json& body, const char* field, double max_abs) {
    const auto v = protocol::get_optional_numbers(body, field, 3);
    if (!v) return std::nullopt;
    return glm::vec3(bounded_float((*v)[0], field, max_abs), bounded_float((*v)[1], field, max_abs),
                     bounded_float((*v)[2], field, max_abs));
}

std::optional<float> optional_in_range(const json& body, const char* field, double min, double max) {
    const auto v = protocol::get_optional_number(body, field);
    if (!v) return std::nullopt;
    if (!(*v >= min && *v <= max)) throw FieldError(field, fmt::format("field '{}' is {}, outside [{}, {}]", field, *v, min, max));
    return finite_float(*v, field);
}

scene::LightType parse_light_type(const std::string& name) {
    if (name == "point") return scene::LightType::point;
    if (name == "spot") return scene::LightType::spot;
    if (name == "directional") return scene::LightType::directional;
    throw FieldError("type", fmt::format("field 'type' is '{}', expected point, spot or directional", name));
}

LoadOrder parse_load(const json& body, bool has_attachment) {
    LoadOrder order;
    order.name = protocol::get_string(body, "name");
    if (order.name.empty() || order.name.size() > 128) throw FieldError("name", "field 'name' must have 1 to 128 characters");
    order.path = protocol::get_optional_string(body, "path");
    if (!order.path) {
        order.upload = has_attachment;
        if (!order.upload) order.builtin = protocol::get_optional_string(body, "builtin");
        if (!order.upload && !order.builtin) {
            throw FieldError("path", "scene.load needs a 'path', a 'builtin' scene or a .glb attachment");
        }
    }
    if (body.contains("dynamic")) {
        const json& dynamic = body["dynamic"];
        if (!dynamic.is_array()) throw FieldError("dynamic", "field 'dynamic' must be an array of object names");
        for (const json& entry : dynamic) {
            if (!entry.is_string()) throw FieldError("dynamic", "field 'dynamic' must be an array of object names");
            order.dynamic.push_back(entry.get<std::string>());
        }
    }
    return order;
}

ObjectRef parse_object(const json& body) {
    if (body.contains("object") && body["object"].is_number_integer()) {
        const auto index = body["object"].get<std::int64_t>();
        if (index < 0) throw RequestError(ErrorCode::not_found, fmt::format("object index {} is negative", index), "object");
        return static_cast<std::uint64_t>(index);
    }
    return protocol::get_string(body, "object");
}

TransformOrder parse_transform(const json& body) {
    TransformOrder order;
    order.scene = protocol::get_string(body, "scene");
    order.object = parse_object(body);
    if (const auto matrix = protocol::get_optional_numbers(body, "matrix", 16)) {
        glm::mat4 m(1.0f);
        for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = bounded_float((*matrix)[i], "matrix", kMaxCoordinate);
        order.matrix = m;
        return order;
    }
    order.translation = optional_vec3(body, "translation", kMaxCoordinate);
    order.rotation_deg = optional_vec3(body, "rotation_deg", kMaxAngleDeg);
    if (const auto scale = protocol::get_optional_number(body, "scale")) {
        // A scale that rounds to float 0 (1e-300) would collapse the object: the floor is 1e-6.
        if (!(*scale >= 1e-6 && *scale <= 1e6)) {
            throw FieldError("scale", fmt::format("field 'scale' is {}, outside [1e-6, 1e6]", *scale));
        }
        order.scale = finite_float(*scale, "scale");
    }
    if (!order.translation && !order.rotation_deg && !order.scale) {
        throw FieldError("matrix", "object.set_transform needs 'matrix' or any of 'translation', 'rotation_deg', 'scale'");
    }
    return order;
}

LightOrder parse_light(const json& body) {
    LightOrder order;
    order.scene = protocol::get_string(body, "scene");
    order.light = protocol::get_string(body, "light");
    if (const auto type = protocol::get_optional_string(body, "type")) order.type = parse_light_type(*type);
    order.position = optional_vec3(body, "position", kMaxCoordinate);
    if (const auto direction = optional_vec3(body, "direction", kMaxCoordinate)) {
        if (!(glm::length(*direction) > 1e-12f)) throw FieldError("direction", "field 'direction' is zero");
        order.direction = glm::normalize(*direction);
    }
    order.color = optional_vec3(body, "color", kMaxColor);
    if (order.color && glm::any(glm::lessThan(*order.color, glm::vec3(0.0f)))) {
        throw FieldError("color", "field 'color' has a negative component");
    }
    order.intensity = optional_in_range(body, "intensity", 0.0, 1e12);
    if (const auto inner = optional_in_range(body, "inner_cone_deg", 0.0, 90.0)) order.inner_cone = glm::radians(*inner);
    if (const auto outer = optional_in_range(body, "outer_cone_deg", 0.0, 90.0)) order.outer_cone = glm::radians(*outer);
    return order;
}

// The view fields of camera.set, and of an inline camera object.
void parse_view_fields(const json& body, CameraOrder& order) {
    order.position = optional_vec3(body, "position", kMaxCoordinate);
    order.look_at = optional_vec3(body, "look_at", kMaxCoordinate);
    if (!order.look_at) {
        if (const auto q = protocol::get_optional_numbers(body, "orientation", 4)) {
            const glm::quat orientation(bounded_float((*q)[3], "orientation", kMaxCoordinate), bounded_float((*q)[0], "orientation", kMaxCoordinate),
                                        bounded_float((*q)[1], "orientation", kMaxCoordinate), bounded_float((*q)[2], "orientation", kMaxCoordinate));
            if (!(glm::length(orientation) > 1e-6f)) throw FieldError("orientation", "field 'orientation' is zero");
            order.orientation = glm::normalize(orientation);
        }
    }
    if (const auto fov = protocol::get_optional_number(body, "fov_deg")) {
        if (!(*fov > 0.1 && *fov < 179.0)) throw FieldError("fov_deg", "field 'fov_deg' is outside (0.1, 179)");
        order.fov = glm::radians(static_cast<float>(*fov));
    }
}

CameraOrder parse_camera(const json& body) {
    CameraOrder order;
    order.scene = protocol::get_string(body, "scene");
    order.camera = protocol::get_optional_string(body, "camera");
    if (!order.camera) parse_view_fields(body, order);
    return order;
}

// A render's `camera`: a name, or an object of inline view fields.
std::optional<CameraOrder> parse_render_view(const json& body, const std::string& scene) {
    const auto it = body.find("camera");
    if (it == body.end() || it->is_null()) return std::nullopt;
    CameraOrder view;
    view.scene = scene;
    if (it->is_string()) {
        view.camera = it->get<std::string>();
    } else if (it->is_object()) {
        try {
            parse_view_fields(*it, view);
        } catch (const FieldError& error) {
            throw FieldError(fmt::format("camera.{}", error.field), error.what());
        }
    } else {
        throw FieldError("camera", "field 'camera' must be a camera's name or an object of view fields");
    }
    return view;
}

// `budget`: {"max_ms": T} and/or {"max_error": E}, nothing else.
planning::Budget parse_budget(const json& body) {
    const json& field = body["budget"];
    if (!field.is_object()) throw FieldError("budget", "field 'budget' must be an object with max_ms and/or max_error");
    for (const auto& [key, value] : field.items()) {
        if (key != "max_ms" && key != "max_error") {
            throw FieldError("budget." + key, fmt::format("budget has no field '{}': it takes max_ms and max_error", key));
        }
    }
    planning::Budget budget;
    try {
        if (const auto ms = protocol::get_optional_number(field, "max_ms")) {
            if (!(*ms > 0.0 && *ms <= 24.0 * 3600 * 1000)) {
                throw FieldError("max_ms", fmt::format("field 'max_ms' is {}, outside (0, 86400000]", *ms));
            }
            budget.max_ms = *ms;
        }
        if (const auto error = protocol::get_optional_number(field, "max_error")) {
            if (!(*error > 0.0 && *error <= 100.0)) {
                throw FieldError("max_error", fmt::format("field 'max_error' is {}, outside (0, 100]", *error));
            }
            budget.max_error = *error;
        }
    } catch (const FieldError& error) {
        throw FieldError("budget." + error.field, error.what());
    }
    if (!budget.max_ms && !budget.max_error) throw FieldError("budget", "field 'budget' needs max_ms or max_error");
    return budget;
}

}  // namespace

RenderOrder parse_render(const json& body, std::uint64_t max_pixels) {
    RenderOrder order;
    order.scene = protocol::get_string(body, "scene");
    order.view = parse_render_view(body, order.scene);
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
        if (!knobs.is_object()) throw FieldError("knobs", "field 'knobs' must be an object of numbers");
        for (const auto& [name, value] : knobs.items()) {
            if (!value.is_number()) throw FieldError("knobs", fmt::format("knob '{}' must be a number", name));
            request.knobs[name] = value.get<double>();
        }
    }
    order.format = protocol::get_optional_string(body, "format").value_or("png");
    const auto format = image::parse_image_format(order.format);
    request.make_display_image = format != image::ImageFormat::exr;
    if (const auto exposure = protocol::get_optional_number(body, "exposure")) {
        if (std::abs(*exposure) > 64.0) throw FieldError("exposure", "field 'exposure' is outside [-64, 64] stops");
        request.display.exposure = static_cast<float>(*exposure);
    }
    if (const auto tone = protocol::get_optional_string(body, "tone")) request.display.curve = image::parse_tone_curve(*tone);
    order.jpeg_quality = static_cast<int>(protocol::get_optional_integer(body, "jpeg_quality", 1, 100).value_or(90));
    order.exr_half = protocol::get_optional_bool(body, "exr_half").value_or(false);
    if (const auto version = protocol::get_optional_integer(body, "min_scene_version", 0, INT64_MAX)) {
        order.min_scene_version = static_cast<std::uint64_t>(*version);
    }
    if (body.contains("budget") && !body["budget"].is_null()) order.budget = parse_budget(body);
    if (request.method == "auto" && !order.budget) {
        throw FieldError("budget", "method 'auto' needs a budget: {\"max_ms\": T} or {\"max_error\": E}");
    }
    if (order.budget) {
        // The planner chooses these on the render thread, from the scene.
        for (const char* field : {"preset", "knobs"}) {
            if (body.contains(field)) throw FieldError(field, fmt::format("a budget plans the {0}: leave out '{0}'", field));
        }
        const auto methods = methods::MethodRegistry::builtin().names();
        if (request.method != "auto" && std::find(methods.begin(), methods.end(), request.method) == methods.end()) {
            throw FieldError("method", fmt::format("unknown method '{}'", request.method));
        }
        return order;
    }
    // Method, preset, knobs and size, refused here rather than queued, naming the field at fault.
    try {
        order.plan = plan_frame(request);
    } catch (const ResourceExhausted&) {
        throw;
    } catch (const InputError& error) {
        const auto& registry = methods::MethodRegistry::builtin();
        const auto methods = registry.names();
        const auto& presets = methods::preset_names();
        const char* field = std::find(methods.begin(), methods.end(), request.method) == methods.end()   ? "method"
                            : std::find(presets.begin(), presets.end(), request.preset) == presets.end() ? "preset"
                                                                                                         : "knobs";
        throw FieldError(field, error.what());
    }
    return order;
}

Order parse_order(const protocol::Message& message, std::uint64_t max_pixels) {
    const json& body = message.body;
    switch (static_cast<MessageType>(message.type)) {
        case MessageType::scene_load: return parse_load(body, !message.attachment.empty());
        case MessageType::scene_unload:
        case MessageType::scene_describe:
            return SceneNameOrder{protocol::get_string(body, "name"), protocol::get_optional_bool(body, "analyze").value_or(false)};
        case MessageType::scene_list: return ListOrder{};
        case MessageType::stats: return StatsOrder{};
        case MessageType::object_set_transform: return parse_transform(body);
        case MessageType::light_set: return parse_light(body);
        case MessageType::light_remove: return RemoveLightOrder{protocol::get_string(body, "scene"),
                                                                protocol::get_string(body, "light")};
        case MessageType::camera_set: return parse_camera(body);
        case MessageType::render: return parse_render(body, max_pixels);
        case MessageType::bake: {
            BakeOrder order{parse_render(body, max_pixels)};
            if (order.frame.budget) throw FieldError("budget", "bake takes a method and a preset, not a budget");
            if (order.frame.plan.site != FrameSite::gpu) {
                throw FieldError("method", fmt::format("method '{}' has nothing to bake: it runs on CPU threads",
                                                       order.frame.request.method));
            }
            return order;
        }
        default:
            throw RequestError(ErrorCode::unsupported,
                               fmt::format("'{}' is not a request the render thread runs",
                                           protocol::message_type_name(message.type)));
    }
}

}  // namespace bounce::server
