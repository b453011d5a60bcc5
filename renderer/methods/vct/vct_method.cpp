#include "renderer/methods/vct/vct_method.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/methods/vct/sparse_voxel_octree.hpp"
#include "renderer/passes/direct_light_pass.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/passes/light_view_maps.hpp"
#include "renderer/scene/shading.hpp"
#include "vct/vct_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace bounce::methods::vct {

std::vector<DiffuseCone> diffuse_cones(int count) {
    count = std::clamp(count, 1, VCT_MAX_CONES);
    std::vector<DiffuseCone> cones(static_cast<std::size_t>(count));
    if (count == 1) {
        cones[0].weight = std::numbers::pi_v<float>;
        return cones;
    }
    // Uniform in z is uniform in solid angle; the golden angle spreads the azimuths.
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (i + 0.5) / count;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden_angle * i;
        cones[static_cast<std::size_t>(i)].axis = glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
    }
    // Voronoi-cell integrals of cos by midpoint quadrature, uniform in solid angle; normalized so
    // the sum is pi exactly.
    constexpr int kRings = 256, kSectors = 512;
    std::vector<double> weights(cones.size(), 0.0);
    for (int ring = 0; ring < kRings; ++ring) {
        const double z = (ring + 0.5) / kRings;
        const double r = std::sqrt(1.0 - z * z);
        for (int sector = 0; sector < kSectors; ++sector) {
            const double phi = 2.0 * std::numbers::pi * (sector + 0.5) / kSectors;
            const glm::vec3 direction(r * std::cos(phi), r * std::sin(phi), z);
            std::size_t nearest = 0;
            for (std::size_t c = 1; c < cones.size(); ++c) {
                if (glm::dot(direction, cones[c].axis) > glm::dot(direction, cones[nearest].axis)) nearest = c;
            }
            weights[nearest] += z;
        }
    }
    double total = 0.0;
    for (double w : weights) total += w;
    for (std::size_t c = 0; c < cones.size(); ++c) {
        cones[c].weight = static_cast<float>(weights[c] / total * std::numbers::pi);
    }
    return cones;
}

float default_cone_aperture(int count) {
    return static_cast<float>(std::acos(1.0 - 1.0 / std::max(count, 1)));
}

namespace {

class VctMethod final : public Method {
public:
    std::string_view name() const override { return "vct"; }

    void render(const FrameContext& frame) override {
        const bool ambient_occlusion = frame.knob_int("ao") != 0;
        gbuffer_.render(frame);
        if (!ambient_occlusion) {
            shadows_.render(frame, frame.knob_int("shadow_map_size"), frame.knob_int("shadow_cascades"));
            direct_light_.render(frame, gbuffer_, shadows_);
        }
        const bool has_geometry = !frame.scene.world_bounds().empty();
        if (!has_geometry) return;

        if (update_octree(frame)) lit_ = false;
        const bool maps_drawn = light_views_.render(frame, frame.knob_int("light_view_size"));
        const SparseVoxelOctree::Filtering filtering{frame.knob_int("anisotropic") != 0,
                                                     frame.knob_int("one_sided_leaves") != 0};
        const int bounces = frame.knob_int("bounces");
        // 1 where every light is as it was injected, its power included (the light-view maps are not
        // drawn again for a change of power alone: they hold none); nullopt where one moved.
        const std::optional<float> power_scale = passes::common_power_scale(injected_lights_, frame.scene.lights);
        if (!lit_ || maps_drawn || power_scale != 1.0f || filtering != octree_.filtering() ||
            bounces != octree_.bounces()) {
            // A factor of 1 here: the lights' power did not change, so something else did (the views' size).
            const bool scalable = lit_ && !maps_drawn && filtering == octree_.filtering() &&
                                  bounces == octree_.bounces() && !passes::emits_light(frame.scene);
            if (scalable && power_scale && *power_scale != 1.0f && octree_.scale_light(*power_scale)) {
                ++light_rescales_;
            } else {
                const ConeSettings cones = cone_settings(frame);
                octree_.inject(frame, light_views_, filtering, bounces >= 2 ? &cones : nullptr);
                ++injections_;
            }
            injected_lights_ = frame.scene.lights;
            lit_ = true;
        }
        trace(frame, ambient_occlusion);
    }

    // The octree for these knobs (resolution, dense) and this geometry, without the light: the
    // next frame injects it (what a change of the lights redoes) instead of voxelizing too.
    bool prepare(const FrameContext& frame) override {
        if (frame.scene.world_bounds().empty()) return false;
        if (update_octree(frame)) lit_ = false;
        return true;
    }

    std::vector<ResidentStructure> resident() const override {
        const auto& counts = octree_.counts();
        std::vector<ResidentStructure> structures = {
            {"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
            {"shadow_maps", shadows_.bytes(), fmt::format("direct light: {} lights with power", shadows_.map_count())},
            {"light_view_maps", light_views_.bytes(),
             fmt::format("photons for injection: {} views", light_views_.views().size())},
            {"octree_nodes", octree_.node_bytes(),
             fmt::format("{} nodes ({} leaves) over {} levels where the scene has surfaces; voxel {:.4g} m",
                         counts.nodes, counts.leaves, octree_.grid().leaf_level + 1, octree_.grid().spacing)},
            {"octree_leaf_data", octree_.leaf_bytes(),
             "per leaf voxel: surface area, albedo, normal, emission, radiance (for re-injection)"},
            {"brick_pool", octree_.pool_bytes(),
             octree_.dense()
                 ? fmt::format("dense: every level's full lattice of RGBA16F voxels ({}^3 at the leaves){}",
                               octree_.grid().lattice_max() + 1, octree_.anisotropic() ? ", inner levels six times" : "")
                 : fmt::format("{} bricks of 3x3x3 RGBA16F voxels, one per node{}", counts.nodes,
                               octree_.anisotropic() ? ", and six directional bricks per inner node" : "")}};
        return structures;
    }

    std::map<std::string, double> statistics() const override {
        const auto& counts = octree_.counts();
        return {{"octree_builds", static_cast<double>(static_builds_)},
                {"dynamic_revoxelizations", static_cast<double>(dynamic_updates_)},
                {"dynamic_objects", static_cast<double>(std::count(dynamic_.begin(), dynamic_.end(), true))},
                {"octree_dynamic_nodes", static_cast<double>(counts.dynamic_nodes)},
                {"light_injections", static_cast<double>(injections_)},
                {"light_rescales", static_cast<double>(light_rescales_)},
                {"light_updates", static_cast<double>(injections_ + light_rescales_)},
                {"octree_levels", static_cast<double>(octree_.grid().leaf_level + 1)},
                {"dense", octree_.dense() ? 1.0 : 0.0},
                {"octree_nodes", static_cast<double>(counts.nodes)},
                {"octree_leaves", static_cast<double>(counts.leaves)},
                {"octree_bricks", static_cast<double>(counts.nodes)},
                {"octree_bytes", static_cast<double>(octree_.node_bytes() + octree_.leaf_bytes() + octree_.pool_bytes())},
                {"voxel_size_m", static_cast<double>(octree_.grid().spacing)},
                {"voxel_fragments", static_cast<double>(counts.fragments)},
                {"photons_injected", static_cast<double>(counts.injected_photons)},
                {"photons_dropped", static_cast<double>(counts.dropped_photons)},
                {"stray_flux_voxels", static_cast<double>(counts.stray_slots)}};
    }

private:
    // Static part: built once per geometry and resolution, from every object that has not moved.
    // An object that moves for the first time becomes dynamic: the static part is rebuilt once
    // without it, and from then on only the dynamic part is revoxelized when dynamic objects move.
    // Returns whether the octree changed (the light must be injected again).
    bool update_octree(const FrameContext& frame) {
        const scene::Scene& scene = frame.scene;
        const int resolution = frame.knob_int("resolution");
        const bool dense = frame.knob_int("dense") != 0;
        const bool fresh = !octree_.built() || resolution != resolution_ || dense != octree_.dense() ||
                           scene.objects.size() != build_transforms_.size();
        if (fresh) dynamic_.assign(scene.objects.size(), false);
        bool newly_dynamic = false;
        if (!fresh) {
            for (std::size_t i = 0; i < scene.objects.size(); ++i) {
                if (!dynamic_[i] && scene.objects[i].transform != build_transforms_[i]) {
                    dynamic_[i] = true;
                    newly_dynamic = true;
                }
            }
        }
        auto is_static = [this](std::size_t object) { return !dynamic_[object]; };
        auto is_dynamic = [this](std::size_t object) { return static_cast<bool>(dynamic_[object]); };
        bool changed = false;
        if (fresh || newly_dynamic) {
            octree_.build(frame, resolution, is_static, dense);
            resolution_ = resolution;
            build_transforms_.clear();
            for (const scene::Object& object : scene.objects) build_transforms_.push_back(object.transform);
            ++static_builds_;
            dynamic_fingerprint_ = 0;
            changed = true;
        }
        if (std::find(dynamic_.begin(), dynamic_.end(), true) != dynamic_.end()) {
            Hasher hash;
            for (std::size_t i = 0; i < scene.objects.size(); ++i) {
                if (dynamic_[i]) hash.add(i).add(scene.objects[i].transform);
            }
            const std::uint64_t fingerprint = hash.value();
            if (changed || fingerprint != dynamic_fingerprint_) {
                octree_.update_dynamic(frame, is_dynamic);
                dynamic_fingerprint_ = fingerprint;
                ++dynamic_updates_;
                changed = true;
            }
        }
        return changed;
    }

    static ConeSettings cone_settings(const FrameContext& frame) {
        const int count = frame.knob_int("diffuse_cones");
        const double aperture_degrees = frame.knob("aperture");
        const float aperture = aperture_degrees > 0.0 ? static_cast<float>(aperture_degrees * std::numbers::pi / 180.0)
                                                      : default_cone_aperture(count);
        ConeSettings settings;
        for (const DiffuseCone& cone : diffuse_cones(count)) settings.cones.emplace_back(cone.axis, cone.weight);
        settings.tan_half_aperture = std::tan(aperture);
        settings.step = static_cast<float>(frame.knob("step"));
        settings.max_distance = glm::length(frame.scene.world_bounds().extent());
        settings.ao_lambda = static_cast<float>(frame.knob("ao_lambda"));
        return settings;
    }

    void trace(const FrameContext& frame, bool ambient_occlusion) {
        gpu::GpuTimers::Scope timing(frame.timers, "vct_cone_trace");
        std::vector<std::string> defines = octree_.program_defines();
        // No specular cone where no material has a specular lobe.
        const bool specular = frame.knob_int("specular") != 0 && frame.scene.has_glossy_material();
        if (specular) {
            defines.push_back("SPECULAR_CONE");  // weighted by the BRDF's own albedo table (brdf.glsl)
        }
        const gpu::ShaderProgram& program =
            frame.shaders.get({"common/fullscreen.vert", "vct/cone_trace.frag", defines});
        program.use();
        octree_.bind_for_tracing(program);
        set_cone_uniforms(program, cone_settings(frame));
        program.set("u_ambient_occlusion", ambient_occlusion ? 1 : 0);
        program.set("u_camera_position", frame.camera.position);

        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        if (ambient_occlusion) {
            const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            glClearNamedFramebufferfv(frame.output.id(), GL_COLOR, 0, zero);
        }
        gbuffer_.bind_textures();
        frame.state.apply({.blend = ambient_occlusion ? gpu::Blend::none : gpu::Blend::additive});
        triangle_.draw();
    }

    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::DirectLightPass direct_light_;
    passes::LightViewMaps light_views_;  // a change of power is seen by same_lights()
    SparseVoxelOctree octree_;
    passes::FullscreenTriangle triangle_;
    int resolution_ = 0;
    std::vector<glm::mat4> build_transforms_;  // every object's transform at the last static build
    std::vector<bool> dynamic_;                // objects that have moved since
    std::uint64_t dynamic_fingerprint_ = 0;
    std::size_t static_builds_ = 0;
    std::size_t dynamic_updates_ = 0;
    std::size_t injections_ = 0;
    std::size_t light_rescales_ = 0;       // frames that scaled the injected light instead (scale_light)
    bool lit_ = false;                     // the octree holds the light of injected_lights_
    std::vector<scene::Light> injected_lights_;
};

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "vct";
    info.description = "voxel cone tracing on a GPU-built sparse voxel octree: direct light plus one or two diffuse "
                       "bounces, or ambient occlusion";
    info.knobs = {
        {"resolution", 4, 500, true, "leaf voxels across the scene's largest extent (voxel size = extent / this)"},
        {"diffuse_cones", 1, VCT_MAX_CONES, true, "cones gathering diffuse indirect light per pixel"},
        {"aperture", 0, 89, false, "cone half aperture in degrees; 0: the cones' share of the hemisphere"},
        {"step", 0.05, 4, false, "cone march step in cone diameters"},
        {"specular", 0, 1, true, "1: a specular cone for glossy materials (none where no material is glossy)"},
        {"bounces", 1, 2, true, "indirect bounces: 1, or 2 (the leaves gather the first bounce before the pixels do)"},
        {"dense", 0, 1, true, "1: the same pipeline over a dense 3D texture of every level instead of the sparse octree"},
        {"anisotropic", 0, 1, true, "1: six directional voxels per inner voxel (paper §9); 0: one isotropic"},
        {"one_sided_leaves", 0, 1, true,
         "1 (with anisotropic): a leaf's light seen only from the side its surface faces, by its projection"},
        {"light_view_size", 16, 4096, true, "texels per side of each light-view map (photons per light view)"},
        {"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (direct light)"},
        shadow_cascades_knob(),
        {"ao", 0, 1, true, "1: ambient occlusion (paper §6) instead of radiance"},
        {"ao_lambda", 0, 1e6, false, "ambient occlusion falloff 1 / (1 + lambda r), per metre"}};
    auto preset = [](double resolution, double cones, double step, double light_view, double shadow) {
        return KnobValues{{"resolution", resolution}, {"diffuse_cones", cones}, {"aperture", 0},
                          {"step", step}, {"specular", 1}, {"bounces", 1}, {"dense", 0}, {"anisotropic", 1},
                          {"one_sided_leaves", 0}, {"light_view_size", light_view}, {"shadow_map_size", shadow},
                          {"shadow_cascades", kPresetShadowCascades},
                          {"ao", 0}, {"ao_lambda", 1}};
    };
    info.presets = {{"draft", preset(24, 6, 1.0, 128, 512)},
                    {"low", preset(32, 9, 0.75, 256, 1024)},
                    {"medium", preset(48, 12, 0.5, 256, 2048)},
                    {"high", preset(64, 16, 0.5, 512, 2048)},
                    {"ultra", preset(96, 32, 0.35, 512, 2048)}};
    info.create = [] { return std::make_unique<VctMethod>(); };
    info.voxel_size = [](const KnobValues& knobs, double extent) { return extent / knobs.at("resolution"); };
    info.estimate = [](const EstimateInput& input) {
        MemoryEstimate estimate = direct_light_estimate(input);
        if (input.knob_int("ao") != 0) estimate[1].bytes = 0;  // ambient occlusion draws no direct light
        estimate.push_back({"light_view_maps", passes::LightViewMaps::bytes_for(input.scene, input.knob_int("light_view_size")),
                            "light_view_size"});
        estimate.push_back({"octree", SparseVoxelOctree::estimate_bytes(input.scene, input.knob_int("resolution"),
                                                                        input.knob_int("dense") != 0,
                                                                        input.knob_int("anisotropic") != 0),
                            "resolution"});
        return estimate;
    };
    return info;
}

}  // namespace bounce::methods::vct
