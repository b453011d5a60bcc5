// The scene requests of the protocol (docs/protocol.md): each reads its JSON body, acts on the
// registry and returns the reply body. They run on the render thread. Bad input throws
// protocol::FieldError, RequestError or InputError, which the session turns into `error` replies.
#pragma once

#include "server/scene_registry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <span>

namespace bounce::server {

struct SceneRoot {
    std::optional<std::filesystem::path> root;  // scene.load by path is refused without one
};

// Resolves `relative` inside `root`; refuses absolute paths, '..' and symlinks leading outside.
std::filesystem::path resolve_in_root(const std::filesystem::path& root, const std::string& relative);

nlohmann::json load_scene(SceneRegistry& registry, const SceneRoot& root, const nlohmann::json& body,
                          std::span<const std::uint8_t> attachment);
nlohmann::json unload_scene(SceneRegistry& registry, const nlohmann::json& body);
nlohmann::json list_scenes(SceneRegistry& registry);
nlohmann::json describe_scene(SceneRegistry& registry, const nlohmann::json& body);
nlohmann::json set_object_transform(SceneRegistry& registry, const nlohmann::json& body);
nlohmann::json set_light(SceneRegistry& registry, const nlohmann::json& body);
nlohmann::json remove_light(SceneRegistry& registry, const nlohmann::json& body);
nlohmann::json set_camera(SceneRegistry& registry, const nlohmann::json& body);

// The render request's fields, validated (the pixel cap comes from the daemon's --max-pixels).
struct RenderOrder {
    std::string scene;
    RenderRequest request;
    std::string format = "png";
    int jpeg_quality = 90;
    bool exr_half = false;
    std::optional<std::uint64_t> min_scene_version;
    std::optional<std::string> camera;  // a camera of the scene, for this render only
};
RenderOrder parse_render(const nlohmann::json& body, std::uint64_t max_pixels);

}  // namespace bounce::server
