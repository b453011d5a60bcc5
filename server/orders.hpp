// Requests as typed orders. A session parses every request body into its order on the network
// thread, before anything is queued, so a malformed or out-of-range field is refused without
// touching the render thread. What depends on scene state (does the object exist, does look_at
// equal the current camera position) is checked when the order is applied.
#pragma once

#include "protocol/protocol.hpp"
#include "renderer/planning/planner.hpp"
#include "renderer/renderer.hpp"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace bounce::server {

// scene.load: exactly one of a path under the scene root, a built-in scene or an uploaded .glb.
struct LoadOrder {
    std::string name;
    std::optional<std::string> path;
    std::optional<std::string> builtin;
    bool upload = false;                // the scene is the message's attachment
    std::vector<std::string> dynamic;   // objects declared movable
};

// scene.unload, scene.describe.
struct SceneNameOrder {
    std::string name;
    bool analyze = false;  // scene.describe: add the scene analysis (renderer/scene_analysis.hpp)
};

struct ListOrder {};
struct StatsOrder {};

// An object by index or by name.
using ObjectRef = std::variant<std::uint64_t, std::string>;

// object.set_transform: a matrix, or any of translation, rotation and scale about the object's
// origin, relative to how it was loaded.
struct TransformOrder {
    std::string scene;
    ObjectRef object;
    std::optional<glm::mat4> matrix;
    std::optional<glm::vec3> translation;
    std::optional<glm::vec3> rotation_deg;
    std::optional<float> scale;
};

// light.set: the fields given replace the light's (a new light starts from the defaults).
struct LightOrder {
    std::string scene;
    std::string light;
    std::optional<scene::LightType> type;
    std::optional<glm::vec3> position, direction, color;
    std::optional<float> intensity;
    std::optional<float> inner_cone, outer_cone;  // radians
};

struct RemoveLightOrder {
    std::string scene;
    std::string light;
};

// camera.set: make a named camera the default, or move the default one.
struct CameraOrder {
    std::string scene;
    std::optional<std::string> camera;
    std::optional<glm::vec3> position, look_at;
    std::optional<glm::quat> orientation;
    std::optional<float> fov;  // radians
};

// render and bake: the frame's fields, and where and with which knobs it runs.
struct RenderOrder {
    std::string scene;
    RenderRequest request;
    FramePlan plan;
    std::string format = "png";
    int jpeg_quality = 90;
    bool exr_half = false;
    std::optional<std::uint64_t> min_scene_version;
    // A view for this render only: a camera of the scene by name (CameraOrder::camera), or inline
    // fields over the scene's default camera. The scene's own cameras are untouched.
    std::optional<CameraOrder> view;
    // With a budget the planner (renderer/planning/planner.hpp) chooses the preset and knobs, and the
    // method when it is `auto`, on the render thread: `plan` is unset until then, and `planned` then
    // holds what the reply's `plan` says.
    std::optional<planning::Budget> budget;
    std::optional<nlohmann::json> planned;
    // GPU frames the planner asks for beside a reference plan, to measure their error on this scene
    // (planning::probes): rendered on the render thread while the reference traces, never sent.
    std::vector<RenderRequest> probes;
    // Reference frames the planner asks for beside those, of a probe's own bounce count (the
    // probes' companions): traced on the reference's CPU slot after its frame is sent, never sent.
    std::vector<RenderRequest> reference_probes;
    // GPU frames to try before a reference plan for a target error (planning::spot_checks), with the
    // check that judges them: its reference is traced on a CPU slot, then each is rendered and the
    // first within `checks_target` is sent in the reference's place.
    std::vector<RenderRequest> checks;
    std::optional<planning::SpotCheck> spot_check;
    double checks_target = 0.0;
    // Set when the plan renders smaller than asked (planning/resolution.hpp): the size the frame is
    // upsampled to before it is encoded. `request` then holds the size it renders at.
    std::optional<std::pair<int, int>> output_size;
};
struct BakeOrder {
    RenderOrder frame;
};

using Order = std::variant<LoadOrder, SceneNameOrder, ListOrder, StatsOrder, TransformOrder, LightOrder,
                           RemoveLightOrder, CameraOrder, RenderOrder, BakeOrder>;

// Parses the body of a request the render thread runs. Throws protocol::FieldError, RequestError
// or InputError naming the fault; `max_pixels` is the daemon's --max-pixels.
Order parse_order(const protocol::Message& message, std::uint64_t max_pixels);

// The render fields alone (render and bake share them), planned with plan_frame().
RenderOrder parse_render(const nlohmann::json& body, std::uint64_t max_pixels);

}  // namespace bounce::server
