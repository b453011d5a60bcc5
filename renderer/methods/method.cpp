#include "renderer/methods/method.hpp"

#include "renderer/base/error.hpp"

namespace bounce::methods {

double FrameContext::knob(std::string_view name) const {
    const auto it = knobs.find(std::string(name));
    BOUNCE_CHECK(it != knobs.end(), "knob '{}' was not resolved for this frame", name);
    return it->second;
}

}  // namespace bounce::methods
