// The scenes a daemon holds. Lives on the render thread only: every access, mutation or render
// runs there, in arrival order, so a render always sees one consistent scene state.
#pragma once

#include "renderer/planning/comparisons.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <map>
#include <set>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace bounce::server {

struct SceneEntry {
    std::unique_ptr<scene::Scene> scene;  // stable address: SceneResources reads it every frame
    std::unique_ptr<SceneResources> resources;
    std::uint64_t version = 0;  // increases with every mutation
    std::string source;         // "builtin", a path under the scene root, or "upload"
    // Its GPU and reference frames of one view, compared for the planner's error model. Shared: CPU
    // frames add to it from the CPU pool.
    std::shared_ptr<planning::FrameComparisons> comparisons = std::make_shared<planning::FrameComparisons>();
    // What upsampling loses per GPU method and scale (planning/resolution.hpp), for one frame size.
    struct Resampling {
        std::uint64_t key = 0;  // the frame size's
        std::map<std::string, std::map<double, double>> errors;
        std::set<std::string> measured;  // methods measured at this size (some frames are too small to scale)
    };
    std::optional<Resampling> resampling;
};

class SceneRegistry {
public:
    explicit SceneRegistry(Renderer& renderer) : renderer_(renderer) {}
    ~SceneRegistry();

    // Adds or replaces `name`; uploads its geometry to the GPU.
    SceneEntry& put(const std::string& name, scene::Scene scene, std::string source);
    // Throws RequestError not_found naming the scene (and no other).
    SceneEntry& get(const std::string& name);
    bool remove(const std::string& name);
    std::vector<std::string> names() const;
    const std::map<std::string, SceneEntry>& entries() const { return scenes_; }

private:
    Renderer& renderer_;
    std::map<std::string, SceneEntry> scenes_;
};

}  // namespace bounce::server
