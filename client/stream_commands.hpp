// The CLI's stream commands (docs/protocol.md, "stream.start, stream.update, stream.stop"):
// `bounce watch`, which saves a stream's frames, and `bounce load-test --stream`, which measures
// how soon many viewers see a scene change. main.cpp parses their command lines.
#pragma once

#include "client/client.hpp"

#include <optional>
#include <string>
#include <vector>

namespace bounce::cli {

struct WatchOptions {
    std::string directory;     // created if missing; frames go to DIR/frame-NNNNNN.EXT
    int frames = 0;            // stop after this many frames; 0: no limit
    bool until_final = false;  // stop after the first frame of the ladder's last rung
};

// Starts a stream (`start` is the stream.start body) on the scene's daemon, saves each frame and
// prints one JSON line per frame, then stops the stream. Returns false when the stream ended with
// an `error` event (printed on stderr as the CLI prints errors). Throws ServerError when
// stream.start is refused, ConnectionError when the daemon cannot be reached.
bool watch(const std::vector<client::Endpoint>& endpoints, const std::optional<std::string>& token,
           const nlohmann::json& start, const WatchOptions& options);

struct StreamLoadTestOptions {
    int viewers = 1;     // stream connections, each with a view of its own
    int frames = 1;      // frames each viewer receives before the run ends
    int move_every = 1;  // the mover moves an object each time viewer 0 received this many frames
};

// Opens the viewers' streams (`start` holds the frame fields; each viewer adds its own camera) and
// a mover connection, and prints one JSON line: frames per viewer, moves, dropped_stale and the
// motion-to-photon percentiles. Returns true when the run saw no errors.
bool stream_load_test(const std::vector<client::Endpoint>& endpoints, const std::optional<std::string>& token,
                      const nlohmann::json& start, const StreamLoadTestOptions& options);

}  // namespace bounce::cli
