// A preview stream's fields and its refinement ladder (docs/protocol.md, "stream.start"): what a
// stream renders for one state of its view, from the cheapest frame to the converged reference.
// Parsed and checked on the network thread, like every order; no GL, no scene state.
#pragma once

#include "server/orders.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace bounce::server {

// One rung: the frame it renders and what it is called in the stream's events.
struct Rung {
    std::string stage;  // "interactive", "still" or "reference"
    RenderOrder frame;
};

struct StreamOrder {
    RenderOrder view;  // the stream's own render fields: scene, method, preset, knobs, size, camera
    bool refine = true;
    int reference_spp = 256;
    double interactive_scale = 0.5;
    int interactive_quality = 50;
    std::vector<Rung> ladder;  // at least one rung; rung 0 after every change
};

inline constexpr int kFirstReferenceSpp = 16;
inline constexpr int kReferenceSppStep = 4;

// Parses a stream's fields (stream.start's body, or it with stream.update's patches merged in) and
// builds its ladder, each rung planned with plan_frame(). Throws protocol::FieldError or
// RequestError naming the field at fault.
StreamOrder parse_stream(const nlohmann::json& fields, std::uint64_t max_pixels);

// The rungs of a stream's ladder, from its fields (parse_stream calls it):
//   0 `interactive`: the method at preset draft, at interactive_scale of the size and quality;
//     with a budget, the plan for it at that size;
//   1 `still`: the stream's method, preset and knobs at full size (left out when it is rung 0);
//     with a budget, the plan for it at full size;
//   2… `reference`: the path tracer at 16, 64, … samples, ×4 a rung up to reference_spp, each but
//      the last denoised; none without `refine`.
std::vector<Rung> build_ladder(const StreamOrder& order);

}  // namespace bounce::server
