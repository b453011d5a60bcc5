#include "renderer/image/tone.hpp"

#include "renderer/base/error.hpp"

namespace bounce::image {

ToneCurve parse_tone_curve(std::string_view name) {
    if (name == "none") return ToneCurve::none;
    if (name == "reinhard") return ToneCurve::reinhard;
    if (name == "aces") return ToneCurve::aces;
    throw InputError(fmt::format("unknown tone curve '{}' (expected none, reinhard or aces)", name));
}

std::string_view tone_curve_name(ToneCurve curve) {
    switch (curve) {
        case ToneCurve::none: return "none";
        case ToneCurve::reinhard: return "reinhard";
        case ToneCurve::aces: return "aces";
    }
    return "none";
}

}  // namespace bounce::image
