#include "client/router.hpp"

#include <algorithm>
#include <utility>

namespace bounce::client {

std::uint64_t rendezvous_weight(std::string_view endpoint_key, std::string_view scene) {
    std::uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a, 64-bit
    const auto mix = [&](unsigned char byte) {
        hash ^= byte;
        hash *= 0x100000001b3ull;
    };
    for (const char c : endpoint_key) mix(static_cast<unsigned char>(c));
    mix(0);  // so that ("ab", "c") and ("a", "bc") differ
    for (const char c : scene) mix(static_cast<unsigned char>(c));
    // FNV's low bits avalanche poorly; splitmix64's finalizer spreads every input bit.
    std::uint64_t z = hash;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

std::vector<Endpoint> rendezvous_order(std::span<const Endpoint> endpoints, std::string_view scene) {
    std::vector<std::pair<std::uint64_t, Endpoint>> weighted;
    for (const Endpoint& endpoint : endpoints) weighted.emplace_back(rendezvous_weight(endpoint.to_string(), scene), endpoint);
    std::sort(weighted.begin(), weighted.end(), [](const auto& a, const auto& b) {
        if (a.first != b.first) return a.first > b.first;
        return a.second.to_string() < b.second.to_string();
    });
    std::vector<Endpoint> order;
    for (auto& [weight, endpoint] : weighted) order.push_back(std::move(endpoint));
    return order;
}

Router::Router(std::vector<Endpoint> endpoints, std::optional<std::string> token)
    : endpoints_(std::move(endpoints)), token_(std::move(token)) {
    if (endpoints_.empty()) throw std::invalid_argument("a router needs at least one endpoint");
}

Endpoint Router::owner(std::string_view scene) const {
    const auto order = rendezvous_order(endpoints_, scene);
    for (const Endpoint& endpoint : order) {
        if (!down_.count(endpoint.to_string())) return endpoint;
    }
    return order.front();
}

Client& Router::connect(const Endpoint& endpoint) {
    auto& client = clients_[endpoint.to_string()];
    if (!client || !client->connected()) client = std::make_unique<Client>(endpoint, token_);
    return *client;
}

void Router::mark_down(const Endpoint& endpoint) {
    down_.insert(endpoint.to_string());
    clients_.erase(endpoint.to_string());
}

void Router::remember(const std::string& scene, SceneSource source) { sources_[scene] = std::move(source); }


void Router::load_from_source(Client& client, const std::string& scene, const SceneSource& source) {
    nlohmann::json body = {{"name", scene}};
    if (source.path) body["path"] = *source.path;
    client.request(protocol::MessageType::scene_load, body, source.path ? std::vector<std::uint8_t>{} : source.glb);
    for (const Change& change : changes_[scene]) client.request(change.type, change.body);
}

void Router::record(const std::string& scene, protocol::MessageType type, const nlohmann::json& body) {
    using protocol::MessageType;
    auto& changes = changes_[scene];
    const auto drop = [&](const std::string& key) {
        std::erase_if(changes, [&](const Change& change) { return change.key == key; });
    };
    switch (type) {
        case MessageType::scene_load: changes_.erase(scene); return;  // a fresh scene
        case MessageType::scene_unload:  // gone on purpose: not to be brought back
            changes_.erase(scene);
            sources_.erase(scene);
            return;
        case MessageType::object_set_transform: {
            // A transform replaces the last one whole.
            const std::string key = "object:" + body.value("object", nlohmann::json()).dump();
            drop(key);
            changes.push_back({type, key, body});
            return;
        }
        case MessageType::camera_set:
            drop("camera");
            changes.push_back({type, "camera", body});
            return;
        case MessageType::light_set:
            // light.set keeps the fields it leaves out: every one since the light's last removal counts.
            changes.push_back({type, "light:" + body.value("light", nlohmann::json()).dump(), body});
            return;
        case MessageType::light_remove: {
            const std::string key = "light:" + body.value("light", nlohmann::json()).dump();
            drop(key);
            changes.push_back({type, key, body});
            return;
        }
        default: return;
    }
}

protocol::Message Router::load(const std::string& name, const std::string& path) {
    auto reply = request(name, protocol::MessageType::scene_load, {{"name", name}, {"path", path}});
    remember(name, {path, {}});
    return reply;
}

protocol::Message Router::upload(const std::string& name, std::vector<std::uint8_t> glb) {
    auto reply = request(name, protocol::MessageType::scene_load, {{"name", name}}, glb);
    remember(name, {std::nullopt, std::move(glb)});
    return reply;
}

protocol::Message Router::request(const std::string& scene, protocol::MessageType type, nlohmann::json body,
                                  std::vector<std::uint8_t> attachment,
                                  const std::function<void(const nlohmann::json&)>& on_progress) {
    std::string tried;
    for (const Endpoint& endpoint : rendezvous_order(endpoints_, scene)) {
        if (down_.count(endpoint.to_string())) continue;
        // A connection kept from an earlier request may have been closed by the daemon since (its
        // idle timeout): one fresh connection is tried before the daemon counts as down.
        bool reused = clients_.count(endpoint.to_string()) != 0;
        for (;;) try {
            Client& client = connect(endpoint);
            try {
                auto reply = client.request(type, body, attachment, on_progress);
                record(scene, type, body);
                return reply;
            } catch (const ServerError& error) {
                // The daemon lacks the scene itself (restarted, or the scene moved here): load it
                // from its source and ask once more. A missing object or camera is an answer.
                const auto source = sources_.find(scene);
                const bool scene_missing = error.code() == protocol::ErrorCode::not_found &&
                                           (error.field() == "scene" || error.field() == "name");
                if (!scene_missing || source == sources_.end() || type == protocol::MessageType::scene_load) throw;
                load_from_source(client, scene, source->second);
                auto reply = client.request(type, body, attachment, on_progress);
                record(scene, type, body);
                return reply;
            }
        } catch (const ConnectionError& error) {
            if (std::exchange(reused, false)) {
                clients_.erase(endpoint.to_string());
                continue;
            }
            mark_down(endpoint);
            tried += (tried.empty() ? "" : "; ") + endpoint.to_string() + ": " + error.what();
            break;
        } catch (const ServerError& error) {
            if (error.code() != protocol::ErrorCode::shutting_down) throw;
            // Draining before it exits: its scenes go where they will live next.
            mark_down(endpoint);
            tried += (tried.empty() ? "" : "; ") + endpoint.to_string() + ": shutting down";
            break;
        }
    }
    throw ConnectionError("no daemon reachable for scene '" + scene + "' (" + tried + ")");
}

std::vector<Router::Answer> Router::broadcast(protocol::MessageType type, const nlohmann::json& body) {
    std::vector<Answer> answers;
    for (const Endpoint& endpoint : endpoints_) {
        try {
            answers.push_back({endpoint, connect(endpoint).request(type, body)});
        } catch (const ConnectionError& error) {
            mark_down(endpoint);
            answers.push_back({endpoint, std::string(error.what())});
        } catch (const ServerError& error) {
            answers.push_back({endpoint, std::string(protocol::error_code_name(error.code())) + ": " + error.what()});
        }
    }
    return answers;
}

}  // namespace bounce::client
