#include "renderer/methods/isr/isr_method.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/gpu/counter_buffer.hpp"
#include "renderer/methods/isr/imperfect_shadow_maps.hpp"
#include "renderer/methods/isr/multires_buffer.hpp"
#include "renderer/methods/isr/vpl_tree.hpp"
#include "renderer/passes/direct_light_pass.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/passes/light_view_maps.hpp"

#include "common/shared_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace bounce::methods::isr {
namespace {

// The presets' `ism_open_below`: the maps' dilation (ism_dilation 2) where the scene analysis finds
// at least this share of the indirect light occluded, none below it. The bench's scenes that err
// less without it are the Cornell boxes with no wall inside (0.102 occluded; isr high 0.0148 to
// 0.0030), those that err more the atrium (0.166; low 0.0136 to 0.0174), the street (0.318) and the
// furnished room (0.389); the glossy gallery (0.149) and the foliage (0.079) move by 3% either way
// (docs/benchmarks.md, "The maps' hole filling"). Halfway between the box and the atrium.
constexpr double kIsmOpenBelow = 0.134;

// Imperfect shadow maps are made on the VPL tree's patches: in hierarchical mode, and where they
// have texels.
bool makes_visibility_maps(int ism_size, int mode) { return ism_size > 0 && mode == ISR_MODE_HIERARCHICAL; }

const char* mode_name(int mode) {
    switch (mode) {
        case ISR_MODE_NAIVE: return "naive RSM sampling";
        case ISR_MODE_BASIC: return "basic image-space radiosity";
        default: return "hierarchical image-space radiosity";
    }
}

// The largest power of two not above `texels` (the VPL tree halves each level exactly).
int power_of_two_floor(int texels) {
    int size = 1;
    while (size * 2 <= texels) size *= 2;
    return size;
}

class IsrMethod final : public Method {
public:
    std::string_view name() const override { return "isr"; }

    void render(const FrameContext& frame) override {
        gbuffer_.render(frame);
        shadows_.render(frame, frame.knob_int("shadow_map_size"), frame.knob_int("shadow_cascades"));
        direct_light_.render(frame, gbuffer_, shadows_);
        if (frame.scene.world_bounds().empty()) return;

        mode_ = frame.knob_int("mode");
        const int rsm_size = power_of_two_floor(frame.knob_int("rsm_size"));
        const bool maps_drawn = light_views_.render(frame, rsm_size);
        if (maps_drawn) ++light_view_draws_;
        // The maps hold places, normals and albedo; each VPL takes its flux from its light as the
        // tree is built. So a change of the lights' colour or intensity alone rebuilds the tree over
        // the kept maps, without drawing them again.
        const std::uint64_t lights = passes::light_view_fingerprint(frame.scene, rsm_size);
        const bool tree_built = tree_.build(frame, light_views_, maps_drawn || lights != tree_lights_,
                                            {static_cast<float>(frame.knob("depth_threshold")),
                                             static_cast<float>(frame.knob("normal_threshold"))});
        tree_lights_ = lights;
        finest_level_ = std::max(0, tree_.top_level() - frame.knob_int("max_depth"));
        const IsmSettings ism{frame.knob_int("ism_size"), frame.knob_int("ism_points"), frame.knob_int("ism_levels_below_top"),
                              frame.knob_int("ism_dilation")};
        visibility_ = makes_visibility_maps(ism.size, mode_);
        if (visibility_) {
            ism_.build(frame, tree_, ism, patch_fingerprint(frame, rsm_size), [&frame] { frame.interruption_point(); });
        } else if (ism_.bytes() > 0) {
            ism_.release();
        }
        if (mode_ != ISR_MODE_HIERARCHICAL && (tree_built || mode_ != cache_mode_ || finest_level_ != cache_level_)) {
            tree_.select(frame, mode_, finest_level_);
            cache_mode_ = mode_;
            cache_level_ = finest_level_;
            cached_vpls_ = tree_.cached_vpls();
        }

        if (!counters_) counters_ = gpu::CounterBuffer(ISR_COUNTERS);
        counters_.reset();
        counters_.bind(ISR_BINDING_COUNTERS);

        multires_.refine(frame, gbuffer_,
                         {frame.knob_int("levels"), static_cast<float>(frame.knob("depth_threshold")),
                          static_cast<float>(frame.knob("normal_threshold"))});
        gather(frame);
        multires_.upsample(frame);
        composite(frame);
        read_counters();
    }

    std::vector<ResidentStructure> resident() const override {
        return {
            {"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
            {"shadow_maps", shadows_.bytes(), fmt::format("direct light: {} lights with power", shadows_.map_count())},
            {"reflective_shadow_maps", light_views_.bytes(),
             fmt::format("VPLs: {} light views of {}^2 texels ({} views that cannot see the scene not drawn)",
                         light_views_.views().size(), light_views_.size(), light_views_.views_culled())},
            {"vpl_tree", tree_.bytes(),
             fmt::format("{}: {} patches from each texel up to {}^2 per view, and the VPL cache", mode_name(mode_),
                         tree_.nodes(), ISR_TOP_PATCHES)},
            {"multires_atlas", multires_.bytes(),
             fmt::format("{} eye-space levels: irradiance, min-max depth and normals, stencil", multires_.levels())},
            {"imperfect_shadow_maps", ism_.bytes(),
             visibility_ ? fmt::format("indirect visibility: {} maps on the VPL patches of level {}", ism_.maps(), ism_.level())
                         : std::string("none: the gather has no indirect visibility")}};
    }

    std::map<std::string, double> statistics() const override {
        std::map<std::string, double> stats = {
            {"mode", static_cast<double>(mode_)},
            {"rsm_views", static_cast<double>(light_views_.views().size())},
            {"rsm_views_culled", static_cast<double>(light_views_.views_culled())},
            {"rsm_size", static_cast<double>(light_views_.size())},
            {"rsm_draws", static_cast<double>(light_views_.frames_drawn())},
            {"vpl_tree_builds", static_cast<double>(tree_.builds())},
            {"vpl_tree_nodes", static_cast<double>(tree_.nodes())},
            {"vpl_finest_patch_texels", static_cast<double>(1 << finest_level_)},
            {"multires_levels", static_cast<double>(multires_.levels())},
            {"multires_fragments", static_cast<double>(fragments_)},
            {"gathered_texels", static_cast<double>(gathered_texels_)},
            {"vpls_per_fragment_mean", fragments_ > 0 ? static_cast<double>(vpls_gathered_) / fragments_ : 0.0},
            {"vpls_per_fragment_max", static_cast<double>(vpls_max_)},
            {"indirect_visibility", visibility_ ? 1.0 : 0.0},
            {"ism_maps", visibility_ ? static_cast<double>(ism_.maps()) : 0.0},
            {"ism_builds", static_cast<double>(ism_.builds())},
            {"resident_bytes", static_cast<double>(gbuffer_.bytes() + shadows_.bytes() + light_views_.bytes() +
                                                   tree_.bytes() + multires_.bytes() + ism_.bytes())}};
        if (mode_ != ISR_MODE_HIERARCHICAL) stats["vpl_cache"] = static_cast<double>(cached_vpls_);
        for (int level = 0; level < multires_.levels(); ++level) {
            stats[fmt::format("multires_fragments_level_{}", level)] = static_cast<double>(level_fragments_[level]);
        }
        return stats;
    }

private:
    // What the tree's patch centres and poles, which the imperfect shadow maps are made at, depend on.
    // They are flux-weighted means over each light's own view, so a change of a light's intensity
    // alone scales every weight of its view alike and moves none of them (beyond float rounding): the
    // maps are kept, as the light-view maps are. A change of colour reweighs texels of different
    // albedo, and a light turned on or off changes which views there are: both make the maps again,
    // as does anything that draws the light-view maps (lights or objects moved) or splits patches
    // differently (the thresholds).
    std::uint64_t patch_fingerprint(const FrameContext& frame, int rsm_size) const {
        Hasher hash;
        hash.add(passes::light_view_fingerprint(frame.scene, rsm_size, /*with_power=*/false));
        hash.add(light_view_draws_);
        for (const scene::Light& light : frame.scene.lights) hash.add(light.color);
        hash.add(frame.knob("depth_threshold")).add(frame.knob("normal_threshold"));
        return hash.value();
    }

    // The gather, in draws of bounded work per fragment (GPU watchdogs, and software rasterizers'
    // loop limits, cut long draws short): VPL-cache ranges, or ranges of top patches whose whole
    // subtrees fit the same budget.
    void gather(const FrameContext& frame) {
        gpu::GpuTimers::Scope timing(frame.timers, "isr_gather");
        constexpr std::size_t kVplsPerDraw = 16384;
        const bool hierarchical = mode_ == ISR_MODE_HIERARCHICAL;
        std::vector<std::string> defines;
        if (!hierarchical) defines.push_back("VPL_CACHE");
        if (visibility_) defines.push_back("INDIRECT_VISIBILITY");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "isr/gather.frag", defines});
        program.use();
        multires_.set_layout(program);
        tree_.bind(program);
        if (visibility_) ism_.bind(program);
        program.set("u_finest_level", finest_level_);
        program.set("u_tau", static_cast<float>(frame.knob("tau")));
        program.set("u_scene_radius", std::max(0.5f * glm::length(frame.scene.world_bounds().extent()), 1e-30f));
        gbuffer_.bind_textures();
        multires_.begin_gather(frame);
        std::size_t items = cached_vpls_, per_draw = kVplsPerDraw;
        if (hierarchical) {
            const std::size_t top_side = static_cast<std::size_t>(tree_.size() >> tree_.top_level());
            items = top_side * top_side * static_cast<std::size_t>(tree_.views());
            std::size_t subtree = 0;  // nodes under one top patch, down to the finest level
            for (int level = finest_level_; level <= tree_.top_level(); ++level) subtree += std::size_t{1} << (2 * (tree_.top_level() - level));
            per_draw = std::max<std::size_t>(1, kVplsPerDraw / subtree);
        }
        for (std::size_t first = 0; first == 0 || first < items; first += per_draw) {
            program.set("u_batch_first", static_cast<unsigned>(first));
            program.set("u_batch_count", static_cast<unsigned>(std::min(per_draw, items - std::min(items, first))));
            program.set("u_first_batch", first == 0 ? 1 : 0);
            triangle_.draw();
        }
        multires_.count_gathered(frame);
    }

    void composite(const FrameContext& frame) {
        gpu::GpuTimers::Scope timing(frame.timers, "isr_composite");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "isr/composite.frag", {}});
        program.use();
        program.set("u_camera_position", frame.camera.position);
        gbuffer_.bind_textures();
        glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, multires_.irradiance().id());
        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        frame.state.apply({.blend = gpu::Blend::additive});
        triangle_.draw();
    }

    void read_counters() {
        const gpu::CounterValues counters = counters_.read();
        fragments_ = 0;
        for (int level = 0; level < ISR_MAX_LEVELS; ++level) {
            level_fragments_[level] = counters[ISR_COUNTER_LEVEL_FRAGMENTS + level];
            fragments_ += counters[ISR_COUNTER_LEVEL_FRAGMENTS + level];
        }
        vpls_gathered_ = counters.wide(ISR_COUNTER_VPLS_LOW, ISR_COUNTER_VPLS_HIGH);
        vpls_max_ = counters[ISR_COUNTER_VPLS_MAX];
        gathered_texels_ = counters[ISR_COUNTER_GATHERED];
    }

    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::DirectLightPass direct_light_;
    passes::LightViewMaps light_views_;
    VplTree tree_;
    std::uint64_t tree_lights_ = 0;  // light_view_fingerprint() with power, as the tree was last built
    std::uint64_t light_view_draws_ = 0;  // how many times the light-view maps were drawn
    MultiresolutionBuffer multires_;
    ImperfectShadowMaps ism_;
    bool visibility_ = false;
    passes::FullscreenTriangle triangle_;
    gpu::CounterBuffer counters_;
    int mode_ = ISR_MODE_HIERARCHICAL;
    int finest_level_ = 0;
    int cache_mode_ = -1, cache_level_ = -1;
    std::uint32_t cached_vpls_ = 0;
    std::array<std::uint64_t, ISR_MAX_LEVELS> level_fragments_{};
    std::uint64_t fragments_ = 0, vpls_gathered_ = 0, vpls_max_ = 0, gathered_texels_ = 0;
};

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "isr";
    info.description = "hierarchical image-space radiosity: direct light plus one diffuse bounce gathered from "
                       "reflective-shadow-map VPLs at multiresolution eye-space patches (indirect visibility from imperfect "
                       "shadow maps where ism_size is set)";
    info.indirect_bounces = 1;
    info.knobs = {
        {"rsm_size", 16, 2048, true, "texels per side of each reflective shadow map (rounded down to a power of two)"},
        {"levels", 1, ISR_MAX_LEVELS, true, "eye-space multiresolution levels (1: gather at every pixel)"},
        {"depth_threshold", 0, 10, false,
         "relative depth span that splits a patch, in eye and light space (0: full resolution)"},
        {"normal_threshold", 0, 2, false, "normal-component span that splits a patch, in eye and light space"},
        {"mode", 0, 2, true, "0: naive RSM sampling, 1: basic (per-frame light patches), 2: hierarchical (VPL tree)"},
        {"tau", 0, 1e6, false,
         "hierarchical: open a light patch while the bound on its irradiance exceeds tau times the irradiance all "
         "reflected flux gives from the scene's radius (0: every VPL of the finest level)"},
        {"max_depth", 0, ISR_MAX_TREE_LEVELS - 1, true,
         "light-patch levels below the 16^2 top patches that traversal (or basic clustering, or naive sampling) may "
         "reach"},
        {"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (direct light)"},
        shadow_cascades_knob(),
        {"ism_size", 0, 64, true,
         "indirect visibility (hierarchical mode): texels per side of each VPL patch's imperfect shadow map; 0: none, "
         "as in the paper"},
        {"ism_points", 16, 16384, true, "indirect visibility: points of the scene's point cloud splatted into each map"},
        {"ism_levels_below_top", 0, 3, true,
         "indirect visibility: maps on the VPL patches this many levels below the 16^2 top patches per view (each "
         "level 4x the maps)"},
        {"ism_dilation", 0, 2, true,
         "indirect visibility: pyramid levels (2x2, 4x4 texels) from which a map's hole filling lets a nearer "
         "surface replace a sample behind it; 0: empty texels alone (less light taken in open rooms, more leaked "
         "through thin walls)"},
        {"ism_open_below", 0, 1, false,
         "indirect visibility: above 0, ism_dilation is 0 where the scene analysis finds less than this share of the "
         "indirect light occluded (an open room) unless the request sets it"}};
    auto preset = [](double rsm, double levels, double depth, double normal, double tau, double max_depth, double ism,
                     double ism_points) {
        return KnobValues{{"rsm_size", rsm},     {"levels", levels}, {"depth_threshold", depth},
                          {"normal_threshold", normal}, {"mode", ISR_MODE_HIERARCHICAL}, {"tau", tau},
                          {"max_depth", max_depth}, {"shadow_map_size", 2048}, {"shadow_cascades", kPresetShadowCascades},
                          {"ism_size", ism}, {"ism_points", ism_points}, {"ism_levels_below_top", 1},
                          {"ism_dilation", 2}, {"ism_open_below", ism > 0 ? kIsmOpenBelow : 0.0}};
    };
    // A normal span of 0.2 at every preset to high: where a patch that gathers once spans normals
    // more apart (0.3 to 0.5 before), the furnished room's draft to medium erred 0.14 to 0.30 against
    // the one-bounce reference and 0.11 to 0.27 against the one without visibility, which isr
    // computes; at 0.2 they err 0.029 to 0.035 and 0.008 to 0.009, at the same time there and at
    // 1.0 to 1.25 times it elsewhere (bench/quality --corpus --method isr --unoccluded). The VPL
    // tree's use of the threshold changes none of that: the eye-space patches carry it.
    // Draft is the paper's method, without indirect visibility; from low up, imperfect shadow maps
    // of 64^2 texels and 4096 points. Nearly all of isr's error is the visibility it leaves out
    // (its presets erred alike, draft to ultra): with the maps, low's one-bounce relMSE fell 1.04
    // to 1.6 times on the corpus (the street 0.0166 to 0.0103, the furnished room 0.033 to 0.023;
    // the glossy gallery's rose 4%) and 2.4 to 25 times on the Cornell variants (the doorway 0.78
    // to 0.031, the box 0.117 to 0.023), at 1.75 to 2.1 times the time; 32^2 maps of 1024 points
    // did better on the three boxes with no wall inside (0.018 on the plain one) and worse on the
    // other seven scenes (docs/benchmarks.md, "isr's presets with visibility").
    // At 4096 points the finer presets' clustering moved isr's error by under 10% on every bench
    // scene; what moves it most is how densely the maps sample occluders. So from medium up the maps splat more of the point
    // cloud: 8192 points at medium, 16384 at high and ultra. Behind walls that takes up to half the
    // error away (the doorway's ultra 0.0208 to 0.0107, the furnished room's high 0.0234 to 0.0166,
    // the street's 0.0097 to 0.0072); it adds up to 9% in the open glossy box and 7% in the atrium,
    // where a denser cloud occludes more than is there. The maps are kept across warm frames, so a
    // warm frame costs the same (within 5%, 11% once); a frame that redraws them costs more on
    // llvmpipe: after a light change 1.1 to 2.1 times as long, a cold one up to 2.5 times
    // (docs/benchmarks.md, "Denser point clouds from medium up").
    info.presets = {{"draft", preset(64, 5, 0.1, 0.2, 0.05, 2, 0, 1024)},
                    {"low", preset(128, 5, 0.05, 0.2, 0.02, 3, 64, 4096)},
                    {"medium", preset(128, 4, 0.03, 0.2, 0.01, 3, 64, 8192)},
                    {"high", preset(256, 4, 0.02, 0.2, 0.005, 4, 64, 16384)},
                    {"ultra", preset(256, 3, 0.01, 0.1, 0.002, 4, 64, 16384)}};
    info.create = [] { return std::make_unique<IsrMethod>(); };
    info.estimate = [](const EstimateInput& input) {
        MemoryEstimate estimate = direct_light_estimate(input);
        const int rsm_size = power_of_two_floor(input.knob_int("rsm_size"));
        estimate.push_back({"reflective_shadow_maps", passes::LightViewMaps::bytes_for(input.scene, rsm_size), "rsm_size"});
        estimate.push_back({"vpl_tree", VplTree::bytes_for(passes::light_views_with_power(input.scene), rsm_size), "rsm_size"});
        estimate.push_back({"multires_atlas", MultiresolutionBuffer::bytes_for(input.width, input.height), "frame size"});
        const IsmSettings ism{input.knob_int("ism_size"), input.knob_int("ism_points"), input.knob_int("ism_levels_below_top"),
                              input.knob_int("ism_dilation")};
        if (makes_visibility_maps(ism.size, input.knob_int("mode"))) {
            estimate.push_back({"imperfect_shadow_maps",
                                ImperfectShadowMaps::bytes_for(passes::light_views_with_power(input.scene), rsm_size, ism,
                                                               input.scene.objects.size()),
                                "ism_size"});
        }
        return estimate;
    };
    info.unmodelled_indirect_visibility = [](const KnobValues& knobs) -> std::string {
        const int ism_size = static_cast<int>(knobs.at("ism_size")), mode = static_cast<int>(knobs.at("mode"));
        if (makes_visibility_maps(ism_size, mode)) return {};
        if (ism_size == 0) return "no imperfect shadow maps: ism_size 0";
        return fmt::format("no imperfect shadow maps: mode {}, and they are made in mode {} alone", mode,
                           ISR_MODE_HIERARCHICAL);
    };
    return info;
}

}  // namespace bounce::methods::isr
