#include "renderer/methods/direct/direct_method.hpp"

#include "renderer/passes/direct_light_pass.hpp"

#include <fmt/format.h>

namespace bounce::methods::direct {
namespace {

class DirectMethod final : public Method {
public:
    std::string_view name() const override { return "direct"; }

    void render(const FrameContext& frame) override {
        gbuffer_.render(frame);
        shadows_.render(frame, frame.knob_int("shadow_map_size"), frame.knob_int("shadow_cascades"));
        direct_light_.render(frame, gbuffer_, shadows_);
    }

    std::vector<ResidentStructure> resident() const override {
        return {{"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
                {"shadow_maps", shadows_.bytes(),
                 fmt::format("{} lights with power, one map each and a sun's view cascades; drawn for {} frames, "
                             "reused for {} (nothing they depend on changed)",
                             shadows_.map_count(), shadows_.frames_drawn(), shadows_.frames_reused())}};
    }

private:
    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::DirectLightPass direct_light_;
};

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "direct";
    info.description = "emission and direct light with shadow maps; no indirect light";
    info.knobs = {{"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (cube face)"},
                  shadow_cascades_knob()};
    const auto preset = [](double size) {
        return KnobValues{{"shadow_map_size", size}, {"shadow_cascades", kPresetShadowCascades}};
    };
    info.presets = {{"draft", preset(256)}, {"low", preset(512)}, {"medium", preset(1024)}, {"high", preset(2048)},
                    {"ultra", preset(4096)}};
    info.create = [] { return std::make_unique<DirectMethod>(); };
    info.estimate = direct_light_estimate;
    return info;
}

}  // namespace bounce::methods::direct
