// A bounds-checked shader build, for finding out-of-bounds array accesses that one driver forgives
// and another does not (Mesa's llvmpipe drops out-of-range storage-buffer writes and reads zero;
// a GPU may corrupt memory, stall or lose the context).
//
// With BOUNCE_SHADER_BOUNDS_CHECK=1 in the environment, every program is compiled with each index
// into an array the shader declares (storage-buffer members, uniform, shared and local arrays)
// routed through a check against the array's length. A failed check counts the access, keeps the
// first failure's site, index and length in a storage buffer at BOUNCE_BINDING_BOUNDS_CHECK, and
// reads element 0 instead. The Renderer reads that buffer after each frame and throws an Error
// naming the shader, line and expression. Off by default: the checks cost time in every access.
#pragma once

#include "renderer/gpu/counter_buffer.hpp"

#include <optional>
#include <string>
#include <vector>

namespace bounce::gpu {

struct ExpandedSource;

// Whether BOUNCE_SHADER_BOUNDS_CHECK asks for checked shaders (read once per process).
bool shader_bounds_checks_enabled();
// A program whose defines hold this is checked whatever the environment says.
inline constexpr const char* kBoundsCheckDefine = "BOUNCE_BOUNDS_CHECK";

// `source` with every index into a declared array checked. Each access gets a site number whose
// description (file:line and the expression) bounds_check_site() returns. The storage binding is
// `binding`. Returns the source unchanged where it indexes no array.
ExpandedSource insert_bounds_checks(const ExpandedSource& source, unsigned binding);

// "vct/octree.glsl:34: node_child[node]" for a site number insert_bounds_checks handed out.
std::string bounds_check_site(unsigned site);

// One failed check, as the shaders recorded it.
struct BoundsViolation {
    std::uint32_t count = 0;  // failed accesses since the last read
    std::string site;         // the first one's
    std::uint32_t index = 0;
    std::uint32_t length = 0;

    std::string describe() const;
};

// The storage buffer the checks write to, bound at the binding the checked shaders declare.
class BoundsCheckBuffer {
public:
    explicit BoundsCheckBuffer(unsigned binding);
    void bind() const;
    // The failures recorded since the last call (none: nullopt), and the buffer cleared.
    std::optional<BoundsViolation> take();

private:
    unsigned binding_;
    CounterBuffer counters_;
};

}  // namespace bounce::gpu
