// Fuzzes the daemon's request path after the socket, without GL: a byte stream is cut into
// messages by a FrameDecoder with the daemon's default limits, and every message goes where a
// session sends it, through parse_order() (and plan_frame() behind it for render and bake). A
// scene.load with an attachment is imported as the render thread would, under a 64 MiB budget, and
// the scene that comes back is checked.
//
// A request may fail only with what the daemon answers as a client fault: protocol::ProtocolError
// (FieldError included), server::RequestError or bounce::InputError (ResourceExhausted included).
// Any other exception, a scene that breaks the importer's promises, or a sanitizer report is a
// finding. Applying the scene-state orders is left out: set_object_transform(), set_light() and
// set_camera() work on a SceneRegistry, and a registry needs a GL Renderer.
//
// The input is the stream itself, so the seed corpus (server/fuzz/corpus, written by
// make_corpus.py) is plain frames; libFuzzer's -max_len bounds the attachment any input carries.
#include "protocol/protocol.hpp"
#include "renderer/base/log.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "renderer/scene/scene.hpp"
#include "server/orders.hpp"
#include "server/request_error.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>
#include <variant>

namespace {

using namespace bounce;

constexpr std::uint64_t kMaxPixels = 4096ull * 4096ull;  // the daemon's default --max-pixels
constexpr std::uint64_t kSceneBudget = 64ull << 20;      // --max-scene-bytes for this target

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "request_fuzz: %s\n", what.c_str());
    std::abort();
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

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

// One message, as a session and the render thread would take it.
void serve(const protocol::Message& message) {
    // RequestHandlers::admit() reads the deadline before the order.
    protocol::get_optional_integer(message.body, "timeout_ms", 1, 24ll * 3600 * 1000);
    const server::Order order = server::parse_order(message, kMaxPixels);
    if (const auto* load = std::get_if<server::LoadOrder>(&order); load && load->upload) {
        check_scene(scene::import_glb_memory(message.attachment, "fuzz", scene::ImportLimits{kSceneBudget}));
    }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    log::set_level(log::Level::error);  // the importer's warnings would drown libFuzzer's output
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    protocol::FrameDecoder decoder;  // the daemon's default limits
    decoder.feed(std::span<const std::uint8_t>(data, size));
    while (true) {
        std::optional<protocol::Message> message;
        try {
            message = decoder.next();
        } catch (const protocol::ProtocolError&) {
            return 0;  // the stream lost its framing: the daemon answers and closes the connection
        }
        if (!message) return 0;
        try {
            serve(*message);
        } catch (const protocol::ProtocolError&) {  // these three: the client's fault, answered as errors
        } catch (const server::RequestError&) {
        } catch (const InputError&) {
        } catch (const std::exception& error) {
            finding(std::string("a request escaped with ") + typeid(error).name() + ": " + error.what());
        }
    }
}
