// Fixed-function state goes through one owner: every pass states the whole state it needs, and
// StateCache applies only what differs. No pass can leave state behind for the next.
#pragma once

#include "renderer/gpu/gl.hpp"

#include <optional>

namespace bounce::gpu {

enum class Blend { none, additive };
enum class Cull { none, back, front };
// Stencil use, always with reference value 1: `mark` writes 1 where fragments pass, `marked` keeps
// only fragments where 1 was written (and writes nothing).
enum class Stencil { none, mark, marked };

struct PipelineState {
    bool depth_test = false;
    bool depth_write = false;
    GLenum depth_func = GL_LESS;
    Cull cull = Cull::none;
    Blend blend = Blend::none;
    Stencil stencil = Stencil::none;
    // Depth offset for shadow-map rendering (glPolygonOffset); 0,0 disables it.
    float polygon_offset_factor = 0.0f;
    float polygon_offset_units = 0.0f;

    bool operator==(const PipelineState&) const = default;
};

class StateCache {
public:
    void apply(const PipelineState& state);
    // Forget what is cached (after code outside this owner touched state).
    void invalidate() { current_.reset(); }

private:
    std::optional<PipelineState> current_;
};

}  // namespace bounce::gpu
