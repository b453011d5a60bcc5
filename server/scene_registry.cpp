#include "server/scene_registry.hpp"

#include "server/request_error.hpp"

namespace bounce::server {

SceneRegistry::~SceneRegistry() {
    // GPU resources go first, while the scenes they read still exist.
    for (auto& [name, entry] : scenes_) entry.resources.reset();
}

SceneEntry& SceneRegistry::put(const std::string& name, scene::Scene scene, std::string source) {
    auto owned = std::make_unique<scene::Scene>(std::move(scene));
    owned->name = name;
    auto resources = renderer_.upload(*owned);
    const auto previous = scenes_.find(name);
    const std::uint64_t version = previous == scenes_.end() ? 0 : previous->second.version + 1;
    if (previous != scenes_.end()) {
        previous->second.resources.reset();
        scenes_.erase(previous);
    }
    SceneEntry& entry = scenes_[name];
    entry.scene = std::move(owned);
    entry.resources = std::move(resources);
    entry.version = version;
    entry.source = std::move(source);
    return entry;
}

SceneEntry& SceneRegistry::get(const std::string& name) {
    const auto it = scenes_.find(name);
    if (it == scenes_.end()) {
        // Other clients' scene names are not for this one to read in an error.
        throw RequestError(protocol::ErrorCode::not_found, fmt::format("no scene '{}'", name), "scene");
    }
    return it->second;
}

bool SceneRegistry::remove(const std::string& name) {
    const auto it = scenes_.find(name);
    if (it == scenes_.end()) return false;
    it->second.resources.reset();
    scenes_.erase(it);
    return true;
}

std::vector<std::string> SceneRegistry::names() const {
    std::vector<std::string> names;
    for (const auto& [name, entry] : scenes_) names.push_back(name);
    return names;
}

}  // namespace bounce::server
