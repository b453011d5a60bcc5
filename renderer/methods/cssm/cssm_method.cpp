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
        shadows_.render(frame, frame.knob_int("shadow_map_size"));
        direct_light_.render(frame, gbuffer_, shadows_);
        if (frame.scene.world_bounds().empty()) return;

        ensure_bake(frame);
        if (!bake_ || bake_.bake().texel_count() == 0) return;
        settings_ = GatherSettings::of(frame);
        // What the atlas solution depends on: a change of any of it solves again.
        Hasher hash;
        hash.add(passes::light_view_fingerprint(frame.scene, frame.knob_int("shadow_map_size")));
        hash.add(settings_.bounces).add(settings_.per_texel).add(settings_.pcf).add(settings_.threshold);
        hash.add(bake_.generation());
        const std::uint64_t lighting = hash.value();
        batches_.update(settings_.pcf, bake_, placement_);
        const GatherTree tree{bake_, placement_, batches_, counters_};
        if (lighting != lighting_) {
            counters_.reset();
            solve_.solve(frame, tree, shadows_, settings_);
            lighting_ = lighting;
            ++atlas_solutions_;
            atlas_counts_ = GatherCounts::read(counters_);  // kept: frames that reuse the solution report the one made
        }
        counters_.reset();
        display_.draw(frame, tree, solve_.indirect(), settings_, lighting);
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
                                               {"atlas_solutions", static_cast<double>(atlas_solutions_)}};
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

private:
    void prepare(const FrameContext& frame) override { ensure_bake(frame); }

    // The bake these knobs need: kept (its moving objects placed anew when they moved), or made
    // resident anew with its texels where they stand.
    void ensure_bake(const FrameContext& frame) {
        scene_ = &frame.scene;
        if (bake_.serves(frame)) {
            placement_.follow(frame.scene, bake_);
            return;
        }
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_bake");
        bake_.make(frame);
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
    const scene::Scene* scene_ = nullptr;  // the last frame's: names the objects it holds
    GatherSettings settings_;
    std::uint64_t lighting_ = 0;
    std::size_t atlas_solutions_ = 0;
    GatherCounts atlas_counts_, pixel_counts_;
};

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
        {"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (direct light)"}};
    auto preset = [](double atlas, double face, double threshold, double pcf) {
        return KnobValues{{"atlas_resolution", atlas}, {"face_size", face},      {"traversal", 2}, {"csm_directions", 256}, {"per_texel", 0}, {"jitter_frames", 0},
                          {"bounces", 1},              {"threshold", threshold}, {"final_threshold", threshold},
                          {"pcf", pcf},                {"shadow_map_size", 2048}};
    };
    info.presets = {{"draft", preset(12, 16, 0.3, 1)},
                    {"low", preset(20, 16, 0.2, 1)},
                    {"medium", preset(32, 24, 0.1, 3)},
                    {"high", preset(48, 32, 0.05, 3)},
                    {"ultra", preset(64, 32, 0.02, 3)}};
    info.create = [] { return std::make_unique<CssmMethod>(); };
    return info;
}

}  // namespace bounce::methods::cssm
