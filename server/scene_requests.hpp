// The scene requests of the protocol (docs/protocol.md), applied to the registry on the render
// thread. Their orders were parsed and checked on the network thread (orders.hpp); what is checked
// here depends on scene state. Faults throw RequestError or protocol::FieldError.
#pragma once

#include "server/orders.hpp"
#include "server/scene_registry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <span>

namespace bounce::server {

// Where scene.load may read and how much a scene may take.
struct SceneRoot {
    std::optional<std::filesystem::path> root;  // scene.load by path is refused without one
    std::uint64_t max_scene_bytes = std::uint64_t{2} << 30;
    std::size_t max_scenes = 64;
};

// Resolves `relative` inside `root`; refuses absolute paths, '..' and symlinks leading outside.
std::filesystem::path resolve_in_root(const std::filesystem::path& root, const std::string& relative);

nlohmann::json load_scene(SceneRegistry& registry, const SceneRoot& root, const LoadOrder& order,
                          std::span<const std::uint8_t> attachment);
nlohmann::json unload_scene(SceneRegistry& registry, const SceneNameOrder& order);
nlohmann::json list_scenes(SceneRegistry& registry);
nlohmann::json describe_scene(SceneRegistry& registry, const SceneNameOrder& order);
nlohmann::json set_object_transform(SceneRegistry& registry, const TransformOrder& order);
nlohmann::json set_light(SceneRegistry& registry, const LightOrder& order);
nlohmann::json remove_light(SceneRegistry& registry, const RemoveLightOrder& order);
nlohmann::json set_camera(SceneRegistry& registry, const CameraOrder& order);

}  // namespace bounce::server
