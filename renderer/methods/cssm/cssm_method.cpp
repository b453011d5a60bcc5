#include "renderer/methods/cssm/cssm_method.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/gpu/counter_buffer.hpp"
#include "renderer/methods/cssm/cssm_display.hpp"
#include "renderer/methods/cssm/gather_tree.hpp"
#include "renderer/methods/cssm/radiosity_solve.hpp"
#include "renderer/methods/cssm/resident_bake.hpp"
#include "renderer/methods/cssm/texel_placement.hpp"
#include "renderer/passes/direct_light_pass.hpp"
#include "renderer/passes/gbuffer_pass.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/passes/shadow_maps.hpp"

#include "cssm/cssm_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <optional>
#include <vector>

namespace bounce::methods::cssm {
namespace {

// Direct light as `direct` draws it, then the parts of the method: the resident bake, where its
// texels stand, the radiosity solve on them (redone only when the lighting changes) and the
// display of the indirect light.
class CssmMethod final : public Method {
public:
    std::string_view name() const override { return "cssm"; }

    void render(const FrameContext& frame) override {
        gbuffer_.render(frame);
        shadows_.render(frame, frame.knob_int("shadow_map_size"), frame.knob_int("shadow_cascades"));
        direct_light_.render(frame, gbuffer_, shadows_);
        if (frame.scene.world_bounds().empty()) return;

        ensure_bake(frame);
        if (!bake_ || bake_.bake().texel_count() == 0) return;
        settings_ = GatherSettings::of(frame);
        // What the atlas solution depends on, but the lights' power: a change of any of it solves again.
        Hasher hash;
        hash.add(passes::light_view_fingerprint(frame.scene, frame.knob_int("shadow_map_size"), /*with_power=*/false));
        hash.add(settings_.bounces).add(settings_.per_texel).add(settings_.pcf).add(settings_.threshold);
        hash.add(settings_.spots);
        hash.add(bake_.generation());
        const std::uint64_t lighting = hash.value();
        batches_.update(settings_.pcf, bake_, placement_);
        const GatherTree tree{bake_, placement_, batches_, counters_, settings_.spots};
        // The solution is linear in the lights' power: where every light's changed by one factor and
        // nothing else did, the display scales it instead of solving again, unless a surface emits
        // (its emission is in the solution and does not scale with the lights).
        std::optional<float> power_scale =
            lighting == lighting_ ? passes::common_power_scale(solved_lights_, frame.scene.lights) : std::nullopt;
        if (power_scale && *power_scale != 1.0f && passes::emits_light(frame.scene)) power_scale.reset();
        if (!power_scale) {
            counters_.reset();
            solve_.solve(frame, tree, shadows_, settings_);
            lighting_ = lighting;
            solved_lights_ = frame.scene.lights;
            solution_scale_ = 1.0f;
            ++atlas_solutions_;
            atlas_counts_ = GatherCounts::read(counters_);  // kept: frames that reuse the solution report the one made
        } else if (*power_scale != solution_scale_) {
            solution_scale_ = *power_scale;
            ++solution_rescales_;
        }
        counters_.reset();
        // The solution, not its lighting: a change of colour solves again for the same lights' places.
        Hasher solution;
        solution.add(lighting_).add(atlas_solutions_);
        display_.draw(frame, tree, solve_.indirect(), settings_, solution.value(), solution_scale_);
        pixel_counts_ = GatherCounts::read(counters_);
    }

    std::vector<ResidentStructure> resident() const override {
        std::vector<ResidentStructure> structures = {
            {"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
            {"shadow_maps", shadows_.bytes(), fmt::format("direct light: {} lights with power", shadows_.map_count())}};
        if (!bake_) return structures;
        structures.push_back(placement_.atlas_structure(bake_.bake(), solve_.bytes()));
        structures.push_back(bake_.structure(*scene_));
        structures.push_back(placement_.tree_structure(bake_.bake()));
        return structures;
    }

    std::map<std::string, double> statistics() const override {
        std::map<std::string, double> stats = {{"per_texel", settings_.per_texel ? 1.0 : 0.0},
                                               {"jittered_frames", static_cast<double>(display_.jittered_frames())},
                                               {"atlas_solutions", static_cast<double>(atlas_solutions_)},
                                               {"solution_rescales", static_cast<double>(solution_rescales_)},
                                               {"light_updates", static_cast<double>(atlas_solutions_ + solution_rescales_)}};
        bake_.add_statistics(stats);
        if (!bake_) return stats;
        placement_.add_statistics(stats, bake_.bake());
        stats.insert({{"gather_batches", static_cast<double>(batches_.batches().size())},
                      {"texel_receivers", static_cast<double>(atlas_counts_.receivers)},
                      {"nodes_per_texel_mean", atlas_counts_.per_receiver(atlas_counts_.gathered)},
                      {"nodes_per_pixel_mean", pixel_counts_.per_receiver(pixel_counts_.gathered)},
                      {"nodes_visited_per_pixel_mean", pixel_counts_.per_receiver(pixel_counts_.visited)},
                      {"pixel_receivers", static_cast<double>(pixel_counts_.receivers)},
                      {"resident_bytes", static_cast<double>(gbuffer_.bytes() + shadows_.bytes() + placement_.bytes() +
                                                             solve_.bytes() + bake_.bytes())}});
        return stats;
    }

    std::optional<PendingWork> pending_work(const FrameContext& frame) override {
        if (finished_) {
            scene_ = &frame.scene;
            const auto finished = std::move(finished_);
            if (bake_.adopt(*finished, frame)) after_new_bake(frame);
        }
        if (frame.scene.world_bounds().empty() || bake_.serves(frame)) return std::nullopt;
        return bake_.work(frame);
    }

    void install(std::shared_ptr<PrecomputeResult> result) override { finished_ = std::move(result); }

private:
    bool prepare(const FrameContext& frame) override {
        ensure_bake(frame);
        return true;
    }

    // The bake these knobs need: kept (its moving objects placed anew when they moved), taken from
    // finished work, or made resident anew with its texels where they stand.
    void ensure_bake(const FrameContext& frame) {
        scene_ = &frame.scene;
        if (finished_) {
            const auto finished = std::move(finished_);
            if (bake_.adopt(*finished, frame)) {
                after_new_bake(frame);
                return;
            }
        }
        if (bake_.serves(frame)) {
            placement_.follow(frame.scene, bake_);
            return;
        }
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_bake");
        bake_.make(frame);
        after_new_bake(frame);
    }

    void after_new_bake(const FrameContext& frame) {
        solve_.allocate(bake_.bake().texel_count());
        placement_.upload(frame.scene, bake_);
    }

    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::DirectLightPass direct_light_;
    ResidentBake bake_;
    TexelPlacement placement_;
    GatherBatches batches_;
    RadiositySolve solve_;
    CssmDisplay display_{gbuffer_};
    gpu::CounterBuffer counters_{CSSM_COUNTERS};
    std::shared_ptr<PrecomputeResult> finished_;  // a bake made off the render thread, not adopted yet
    const scene::Scene* scene_ = nullptr;  // the last frame's: names the objects it holds
    GatherSettings settings_;
    std::uint64_t lighting_ = 0;
    std::vector<scene::Light> solved_lights_;  // the lights the atlas solution was solved for
    float solution_scale_ = 1.0f;              // the lights' power now over theirs
    std::size_t atlas_solutions_ = 0;
    std::size_t solution_rescales_ = 0;  // frames that scaled the solution instead of solving again
    GatherCounts atlas_counts_, pixel_counts_;
};

// The atlas holds about atlas_resolution^2 texels (texel edge = sqrt(area) / atlas_resolution; chart
// padding adds some), more by the share of the area that is double-sided (both sides have texels).
// Each texel costs on the GPU its CssmTexel and its direct light's sample points, about two
// radiosity-tree nodes with their radiance, five vec4 solve buffers and two vec4 of its spot sums; on
// the host its atlas entry
// and the bake's arrays. The compressed depth runs depend on the scene: at least one run per cube-map
// pixel per group (the static objects, and each moving one), and the bake's chunk of 32 uncompressed
// maps on the host.
MemoryEstimate estimate(const EstimateInput& input) {
    MemoryEstimate estimate = direct_light_estimate(input);
    double both_sides = 1.0;
    if (std::any_of(input.scene.materials.begin(), input.scene.materials.end(),
                    [](const scene::Material& material) { return material.double_sided; })) {
        std::vector<std::uint32_t> objects(input.scene.objects.size());
        std::iota(objects.begin(), objects.end(), 0u);
        const double area = surface_area(input.scene, objects);
        if (area > 0.0) both_sides += double_sided_area(input.scene, objects) / area;
    }
    const auto texels = static_cast<std::uint64_t>(input.knob("atlas_resolution") * input.knob("atlas_resolution") * both_sides);
    constexpr std::uint64_t kGpuPerTexel = sizeof(glsl::CssmTexel) + kTexelSamples * 16 +
                                           2 * (sizeof(glsl::CssmNode) + sizeof(glsl::CssmNodeLight)) + (5 + 2) * 16;
    constexpr std::uint64_t kHostPerTexel =
        sizeof(AtlasTexel) + (6 + kTexelSamples) * sizeof(glm::vec3) + 3 * sizeof(std::uint32_t);
    estimate.push_back({"atlas_texels", texels * (kGpuPerTexel + kHostPerTexel), "atlas_resolution"});
    std::uint64_t groups = 1;
    for (const scene::Object& object : input.scene.objects) groups += object.mesh >= 0 && object.dynamic ? 1 : 0;
    const auto face = static_cast<std::uint64_t>(input.knob_int("face_size"));
    const std::uint64_t pixels = 6 * face * face;
    estimate.push_back({"depth_cube_maps", groups * pixels * (2 * sizeof(std::uint32_t) + sizeof(std::uint16_t)) +
                                               32 * pixels * sizeof(DepthInterval),
                        "face_size"});
    if (input.knob_int("jitter_frames") > 1) {
        estimate.push_back({"jitter_accumulation",
                            2 * static_cast<std::uint64_t>(input.width) * static_cast<std::uint64_t>(input.height) * 16,
                            "frame size"});
    }
    return estimate;
}

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "cssm";
    info.description = "coherent surface shadow maps: n diffuse bounces by GPU hierarchical radiosity on a surface atlas "
                       "with visibility from baked, compressed depth cube maps, and a per-pixel final gather";
    info.knobs = {
        {"atlas_resolution", 4, 1024, false,
         "atlas texels along the square root of the surface area (texel edge = sqrt(area) / this)"},
        {"face_size", 4, 256, true, "pixels per side of each depth cube-map face"},
        {"traversal", 0, 2, true, "order the cube maps are baked and compressed in: 0 greedy, 1 zig-zag, 2 spiral"},
        {"bounces", 1, 8, true, "indirect diffuse bounces (the last one is the per-pixel final gather)"},
        {"bounce_tolerance", 0, 1, false,
         "above 0: bounces as many as the scene needs for its frame to lack at most this share of the light (the "
         "scene analysis; a request's own `bounces` wins); 0: `bounces` as set"},
        {"threshold", 0, 100, false,
         "radiosity: refine a sender while its tone-mapped radiance bound at the receiver texel exceeds this (0: every texel)"},
        {"final_threshold", 0, 100, false, "final gather: the same threshold for pixels"},
        {"pcf", 1, 7, true, "percentage-closer filter width over cube-map pixels"},
        {"csm_directions", 16, 4096, true, "directions of each moving object's coherent shadow maps"},
        {"jitter_frames", 0, 4096, true,
         "final gather: above 1, senders move to random points of their area each frame and the frames' mean is "
         "shown while nothing changes, for up to this many frames (§4.5)"},
        {"per_texel", 0, 1, true,
         "0: the last bounce gathered per pixel (final gathering); 1: all n bounces on the atlas, pixels read the "
         "texels around them (view-dependent lightmap)"},
        {"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (direct light)"},
        shadow_cascades_knob(),
        {"texel_spots", 0, 1, true,
         "1: a texel sends the lights' light from the part of it the light falls on (its spot); 0: from all of it. "
         "Off at draft and low: with texels that coarse, what a texel's cube map sees from its point does not hold "
         "from its spot in one bench scene in five"}};
    // The presets bounce once (bounce_tolerance 0); `bounce_tolerance` asks the scene analysis instead.
    auto preset = [](double atlas, double face, double threshold, double pcf, double spots) {
        return KnobValues{{"atlas_resolution", atlas}, {"face_size", face},      {"traversal", 2}, {"csm_directions", 256}, {"per_texel", 0}, {"jitter_frames", 0},
                          {"bounces", 1},              {"threshold", threshold}, {"final_threshold", threshold},
                          {"pcf", pcf},                {"shadow_map_size", 2048}, {"shadow_cascades", kPresetShadowCascades}, {"bounce_tolerance", 0},
                          {"texel_spots", spots}};
    };
    info.presets = {{"draft", preset(12, 16, 0.3, 1, 0)},
                    {"low", preset(20, 16, 0.2, 1, 0)},
                    {"medium", preset(32, 24, 0.1, 3, 1)},
                    {"high", preset(48, 32, 0.05, 3, 1)},
                    {"ultra", preset(64, 32, 0.02, 3, 1)}};
    info.create = [] { return std::make_unique<CssmMethod>(); };
    info.estimate = estimate;
    return info;
}

}  // namespace bounce::methods::cssm
