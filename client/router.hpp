// Scene affinity across daemons. A Router spreads scenes over several bounced daemons (one per
// GPU) by rendezvous hashing of the scene's name, so a scene stays resident where it was loaded
// and every client, in any language, sends it to the same daemon without talking to the others.
// When a scene's daemon cannot be reached, the scene moves to the next daemon in its order and is
// loaded there again from its source, and the changes this router made to it (transforms, lights,
// camera) are applied again (docs/scaling.md).
#pragma once

#include "client/client.hpp"

#include <map>
#include <memory>
#include <set>
#include <span>
#include <string_view>
#include <variant>

namespace bounce::client {

// The rendezvous weight of a scene on a daemon keyed "ADDRESS:PORT" (Endpoint::to_string):
// splitmix64's finalizer of the 64-bit FNV-1a hash of key, a zero byte and scene. The Python client
// computes the same; docs/scaling.md gives the definition and test vectors.
std::uint64_t rendezvous_weight(std::string_view endpoint_key, std::string_view scene);
// The endpoints in the order a scene tries them: highest weight first, ties to the smaller key.
std::vector<Endpoint> rendezvous_order(std::span<const Endpoint> endpoints, std::string_view scene);

// Where a scene came from, so that the daemon that takes it over can load it again.
struct SceneSource {
    std::optional<std::string> path;  // a scene.load path under the daemons' scene root
    std::vector<std::uint8_t> glb;    // or the bytes of an uploaded .glb
};

class Router {
public:
    // Throws std::invalid_argument for an empty list.
    explicit Router(std::vector<Endpoint> endpoints, std::optional<std::string> token = {});

    const std::vector<Endpoint>& endpoints() const { return endpoints_; }
    // The daemon a scene goes to now: the first endpoint of its order not found down.
    Endpoint owner(std::string_view scene) const;

    // Loads a scene on its daemon, by path under the scene root or as uploaded .glb bytes, and
    // remembers the source.
    protocol::Message load(const std::string& name, const std::string& path);
    protocol::Message upload(const std::string& name, std::vector<std::uint8_t> glb);
    // Remembers a scene's source without loading it (it is resident already, or was loaded by
    // another client).
    void remember(const std::string& scene, SceneSource source);

    // A request about one scene, sent to its daemon. A daemon that cannot be reached (after one
    // fresh connection, when a kept one broke) or that is shutting down is marked down and the
    // next in the scene's order is tried. When the daemon answers that it has no
    // such scene and the source is known, the scene is loaded there, the scene's recorded changes
    // are applied again, and the request is sent once more. Throws ServerError for the daemon's
    // refusal, ConnectionError when none can be reached.
    protocol::Message request(const std::string& scene, protocol::MessageType type,
                              nlohmann::json body = nlohmann::json::object(), std::vector<std::uint8_t> attachment = {},
                              const std::function<void(const nlohmann::json&)>& on_progress = {});

    // A request that is about no one scene (scene.list, stats), sent to every daemon: each answer,
    // or the reason there is none.
    struct Answer {
        Endpoint endpoint;
        std::variant<protocol::Message, std::string> reply;  // the reply, or why there is none
    };
    std::vector<Answer> broadcast(protocol::MessageType type, const nlohmann::json& body = nlohmann::json::object());

private:
    // A change to a scene that a reload must apply again; each sets state absolutely, so applying
    // the recorded ones in order rebuilds the state.
    struct Change {
        protocol::MessageType type;
        std::string key;  // what it changes: "object:NAME", "light:NAME" or "camera"
        nlohmann::json body;
    };
    void record(const std::string& scene, protocol::MessageType type, const nlohmann::json& body);
    Client& connect(const Endpoint& endpoint);
    void mark_down(const Endpoint& endpoint);
    void load_from_source(Client& client, const std::string& scene, const SceneSource& source);

    std::vector<Endpoint> endpoints_;
    std::optional<std::string> token_;
    std::map<std::string, std::unique_ptr<Client>> clients_;  // connected lazily, by endpoint key
    std::set<std::string> down_;
    std::map<std::string, SceneSource> sources_;
    std::map<std::string, std::vector<Change>> changes_;  // by scene
};

}  // namespace bounce::client
