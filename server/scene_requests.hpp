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
#include <string>
#include <vector>

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
// The scene-state orders. Each takes the scene named by the order from the registry (not_found
// naming it otherwise), mutates it as the apply_* function below does, and returns
// {"scene_version": N}, the scene's version increased by one.
nlohmann::json set_object_transform(SceneRegistry& registry, const TransformOrder& order);
nlohmann::json set_light(SceneRegistry& registry, const LightOrder& order);
nlohmann::json remove_light(SceneRegistry& registry, const RemoveLightOrder& order);
nlohmann::json set_camera(SceneRegistry& registry, const CameraOrder& order);

// What those orders and scene.load's `dynamic` do to a scene::Scene, with no registry and no GL
// (bounce_request_fuzz applies them alone). Faults throw RequestError (not_found naming the
// object, light or camera; too_large past kMaxLights) or protocol::FieldError (among them a
// transform that would take its object past scene::max_world_coordinate), and leave the scene as
// it was.
inline constexpr std::size_t kMaxLights = 256;
void declare_dynamic(scene::Scene& loaded, const std::vector<std::string>& names);
void apply_transform(scene::Scene& scene, const TransformOrder& order);
void apply_light(scene::Scene& scene, const LightOrder& order);
void apply_remove_light(scene::Scene& scene, const RemoveLightOrder& order);
void apply_camera(scene::Scene& scene, const CameraOrder& order);
// The camera an order describes, from the scene's default camera, the scene left as it is: a
// named camera of the scene, or the default one with the order's fields replacing its own (a
// render's or a stream's inline view).
scene::Camera camera_from(const scene::Scene& scene, const CameraOrder& order);

}  // namespace bounce::server
