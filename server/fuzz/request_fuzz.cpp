// Fuzzes the daemon's request path after the socket, without GL: a byte stream is cut into
// messages by a FrameDecoder with the daemon's default limits, and every message goes where a
// session sends it, through parse_order() (and plan_frame() behind it for render and bake), then
// to what the render thread does with the order, as far as that needs no GL:
//  - every input starts from the scenes "cornell" (the built-in Cornell box) and "crowded" (the
//    same with lights up to the cap of kMaxLights less one);
//  - scene.load adds or replaces a scene: an upload imported under a 64 MiB budget (checked for
//    what the importer promises), or a built-in one, with its `dynamic` objects declared
//    (declare_dynamic); at most 4 scenes, as --max-scenes; scene.unload removes one;
//  - object.set_transform, light.set, light.remove and camera.set mutate their scene through the
//    functions the registry's requests call (server/scene_requests.hpp, apply_*).
// After every load and mutation the scene must still be one a render can draw: scene::validate_finite
// holds, the world bounds are finite, every camera (a render may name any; the framing camera when
// there is none) has a finite positive far plane and finite view and projection matrices at every
// aspect a frame can have, every light a usable direction, a finite radiant intensity and (when
// the scene has anything in it) a finite far plane and finite views, as the shadow and light-view
// maps build them, and there are at most kMaxLights lights.
//
// A request may fail only with what the daemon answers as a client fault: protocol::ProtocolError
// (FieldError included), server::RequestError or bounce::InputError (ResourceExhausted included).
// Any other exception, a scene that breaks the importer's promises or a render's invariants, or a
// sanitizer report is a finding (abort).
//
// The input is the stream itself, so the seed corpus (server/fuzz/corpus, written by
// make_corpus.py) is plain frames; libFuzzer's -max_len bounds the attachment any input carries.
#include "protocol/protocol.hpp"
#include "renderer/base/log.hpp"
#include "renderer/passes/light_view_maps.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "renderer/scene/scene.hpp"
#include "server/orders.hpp"
#include "server/request_error.hpp"
#include "server/scene_requests.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <string>
#include <typeinfo>
#include <variant>

namespace {

using namespace bounce;

constexpr std::uint64_t kMaxPixels = 4096ull * 4096ull;  // the daemon's default --max-pixels
constexpr std::uint64_t kSceneBudget = 64ull << 20;      // --max-scene-bytes for this target
constexpr std::size_t kMaxScenes = 4;                    // --max-scenes for this target

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "request_fuzz: %s\n", what.c_str());
    std::abort();
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

bool finite(const glm::mat4& m) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r])) return false;
        }
    }
    return true;
}

// What the importer promises of every scene it returns (scene.hpp, gltf_import.hpp).
void check_scene(const scene::Scene& loaded) {
    try {
        scene::validate_finite(loaded);
    } catch (const InputError& error) {
        finding(std::string("an imported scene is not finite: ") + error.what());
    }
    const auto texture_ok = [&](const scene::TextureRef& ref) {
        return ref.texture >= -1 && ref.texture < static_cast<int>(loaded.textures.size()) &&
               (ref.uv_set == 0 || ref.uv_set == 1);
    };
    for (const scene::Texture& texture : loaded.textures) {
        if (texture.width < 0 || texture.height < 0 ||
            texture.rgba8.size() != std::size_t(texture.width) * std::size_t(texture.height) * 4) {
            finding("a texture's pixels do not match its size");
        }
    }
    for (const scene::Material& material : loaded.materials) {
        if (!texture_ok(material.base_color_texture) || !texture_ok(material.metallic_roughness_texture) ||
            !texture_ok(material.normal_texture) || !texture_ok(material.emissive_texture)) {
            finding("a material names a texture the scene does not have");
        }
    }
    for (const scene::Mesh& mesh : loaded.meshes) {
        for (const scene::Primitive& primitive : mesh.primitives) {
            const std::size_t vertices = primitive.positions.size();
            if (primitive.indices.size() % 3 != 0) finding("a primitive's index count is not a multiple of 3");
            for (const std::uint32_t index : primitive.indices) {
                if (index >= vertices) finding("an index is past its primitive's vertex count");
            }
            if (primitive.normals.size() != vertices) finding("a primitive's normals do not match its positions");
            for (const glm::vec3& normal : primitive.normals) {
                if (!finite(normal)) finding("a normal is not finite");
            }
            if (primitive.tangents.size() != vertices) finding("a primitive's tangents do not match its positions");
            if (!primitive.uv0.empty() && primitive.uv0.size() != vertices) finding("uv0 does not match the positions");
            if (!primitive.uv1.empty() && primitive.uv1.size() != vertices) finding("uv1 does not match the positions");
            if (primitive.material < -1 || primitive.material >= static_cast<int>(loaded.materials.size())) {
                finding("a primitive names a material the scene does not have");
            }
        }
    }
    for (const scene::Object& object : loaded.objects) {
        if (object.mesh < -1 || object.mesh >= static_cast<int>(loaded.meshes.size())) {
            finding("an object names a mesh the scene does not have");
        }
    }
}

// The view of `camera` as Renderer::with_frame and the reference path tracer build it, at the
// aspects of a square frame and of the widest and tallest (1 x 16384) ones.
void check_camera(const scene::Camera& camera, const scene::Aabb& bounds, const std::string& what) {
    const float far = camera.far_plane_for(bounds);
    if (!(std::isfinite(far) && far > 0.0f)) finding(what + ": the far plane " + std::to_string(far) + " is not finite and positive");
    const glm::mat4 view = camera.view();
    if (!finite(view)) finding(what + ": the view matrix is not finite");
    constexpr float extreme = static_cast<float>(Renderer::kMaxDimension);
    for (const float aspect : {1.0f, extreme, 1.0f / extreme}) {
        const glm::mat4 projection = camera.projection(aspect, far);
        if (!finite(projection)) finding(what + ": the projection is not finite at aspect " + std::to_string(aspect));
        if (!finite(projection * view)) finding(what + ": the view-projection is not finite");
    }
}

// What a render relies on in the scene it draws (see the top of this file). `after` names what
// was just done to it.
void check_renderable(const scene::Scene& scene, const std::string& after) {
    try {
        scene::validate_finite(scene);
    } catch (const InputError& error) {
        finding(after + ": " + error.what());
    }
    const scene::Aabb bounds = scene.world_bounds();
    if (!bounds.empty() && !(finite(bounds.min) && finite(bounds.max) && finite(bounds.extent()))) {
        finding(after + ": the world bounds are not finite");
    }
    if (scene.lights.size() > server::kMaxLights) finding(after + ": more lights than the cap");
    for (const scene::Camera& camera : scene.cameras) check_camera(camera, bounds, after + ": camera '" + camera.name + "'");
    if (scene.cameras.empty()) check_camera(scene::framing_camera(bounds), bounds, after + ": the framing camera");
    // Shadow and light-view maps (renderer/passes): views from each light that hold the scene; a
    // scene with nothing in it has none.
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        const scene::Light& light = scene.lights[i];
        const std::string what = after + ": light '" + light.name + "'";
        if (!finite(glm::normalize(light.direction))) finding(what + ": its direction cannot be normalized");
        if (!finite(light.radiant())) finding(what + ": its radiant intensity is not finite");
        if (bounds.empty()) continue;
        const float far = scene::far_plane_distance(bounds, light.position);
        if (!(std::isfinite(far) && far > 0.0f)) finding(what + ": its far plane is not finite and positive");
        for (const auto& view : passes::light_views(light, i, bounds, 1024)) {
            if (!finite(view.view_projection)) finding(what + ": a light view is not finite");
        }
    }
}

// The scenes one input works on, by name, as the registry holds them.
using Scenes = std::map<std::string, scene::Scene>;

Scenes initial_scenes() {
    static const Scenes initial = [] {
        Scenes scenes;
        scenes["cornell"] = scene::make_cornell_box();
        scene::Scene crowded = scene::make_cornell_box();
        crowded.name = "crowded";
        while (crowded.lights.size() + 1 < server::kMaxLights) {
            scene::Light light;
            light.name = "extra_" + std::to_string(crowded.lights.size());
            light.position = glm::vec3(0.1f * static_cast<float>(crowded.lights.size() % 10), 1.5f, 0.0f);
            crowded.lights.push_back(light);
        }
        scenes["crowded"] = std::move(crowded);
        for (const auto& [name, scene] : scenes) check_renderable(scene, "the initial scene " + name);
        return scenes;
    }();
    return initial;
}

scene::Scene& named(Scenes& scenes, const std::string& name) {
    const auto it = scenes.find(name);
    if (it == scenes.end()) {
        throw server::RequestError(protocol::ErrorCode::not_found, "no scene '" + name + "'", "scene");
    }
    return it->second;
}

void load(Scenes& scenes, const server::LoadOrder& order, const protocol::Message& message) {
    if (!scenes.contains(order.name) && scenes.size() >= kMaxScenes) {
        throw server::RequestError(protocol::ErrorCode::resource_exhausted, "too many scenes", "name");
    }
    scene::Scene loaded;
    if (order.path) {
        throw server::RequestError(protocol::ErrorCode::unsupported, "no --scene-root here", "path");
    } else if (order.upload) {
        loaded = scene::import_glb_memory(message.attachment, "fuzz", scene::ImportLimits{kSceneBudget});
        check_scene(loaded);
    } else {
        try {
            loaded = scene::make_builtin_scene(order.builtin.value());
        } catch (const InputError& error) {
            throw protocol::FieldError("builtin", error.what());
        }
    }
    server::declare_dynamic(loaded, order.dynamic);
    check_renderable(loaded, "scene.load of '" + order.name + "'");
    scenes[order.name] = std::move(loaded);
}

// One message, as a session and the render thread would take it.
void serve(const protocol::Message& message, Scenes& scenes) {
    // RequestHandlers::admit() reads the deadline before the order.
    protocol::get_optional_integer(message.body, "timeout_ms", 1, 24ll * 3600 * 1000);
    const server::Order order = server::parse_order(message, kMaxPixels);
    if (const auto* load_order = std::get_if<server::LoadOrder>(&order)) {
        load(scenes, *load_order, message);
    } else if (const auto* name = std::get_if<server::SceneNameOrder>(&order)) {
        if (message.type == static_cast<std::uint16_t>(protocol::MessageType::scene_unload)) {
            named(scenes, name->name);
            scenes.erase(name->name);
        }
    } else if (const auto* transform = std::get_if<server::TransformOrder>(&order)) {
        server::apply_transform(named(scenes, transform->scene), *transform);
        check_renderable(named(scenes, transform->scene), "object.set_transform on '" + transform->scene + "'");
    } else if (const auto* light = std::get_if<server::LightOrder>(&order)) {
        server::apply_light(named(scenes, light->scene), *light);
        check_renderable(named(scenes, light->scene), "light.set on '" + light->scene + "'");
    } else if (const auto* removal = std::get_if<server::RemoveLightOrder>(&order)) {
        server::apply_remove_light(named(scenes, removal->scene), *removal);
        check_renderable(named(scenes, removal->scene), "light.remove on '" + removal->scene + "'");
    } else if (const auto* camera = std::get_if<server::CameraOrder>(&order)) {
        server::apply_camera(named(scenes, camera->scene), *camera);
        check_renderable(named(scenes, camera->scene), "camera.set on '" + camera->scene + "'");
    }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    log::set_level(log::Level::error);  // the importer's warnings would drown libFuzzer's output
    initial_scenes();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    protocol::FrameDecoder decoder;  // the daemon's default limits
    decoder.feed(std::span<const std::uint8_t>(data, size));
    Scenes scenes = initial_scenes();
    while (true) {
        std::optional<protocol::Message> message;
        try {
            message = decoder.next();
        } catch (const protocol::ProtocolError&) {
            return 0;  // the stream lost its framing: the daemon answers and closes the connection
        }
        if (!message) return 0;
        try {
            serve(*message, scenes);
        } catch (const protocol::ProtocolError&) {  // these three: the client's fault, answered as errors
        } catch (const server::RequestError&) {
        } catch (const InputError&) {
        } catch (const std::exception& error) {
            finding(std::string("a request escaped with ") + typeid(error).name() + ": " + error.what());
        }
    }
}
