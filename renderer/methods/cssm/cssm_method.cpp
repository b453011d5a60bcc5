#include "renderer/methods/cssm/cssm_method.hpp"

#include "renderer/base/log.hpp"
#include "renderer/methods/cssm/bake_cache.hpp"
#include "renderer/passes/direct_light_pass.hpp"
#include "renderer/passes/gbuffer_pass.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/passes/shadow_maps.hpp"

#include "cssm/cssm_layout.h"
#include "common/shared_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace bounce::methods::cssm {
namespace {

// Work one gather draw or dispatch may do per receiver, in node visits times the visibility
// query's loop steps: GPU watchdogs (and software rasterizers' loop limits) cut long draws short,
// so traversals run over batches of subtrees whose node counts fit this budget.
constexpr double kStepsPerBatch = 40000.0;

struct GpuNode {
    glm::vec4 centre_radius;
    glm::vec4 normal_cone;
    glm::vec4 area;
    glm::uvec4 links;
};
struct GpuTexel {
    glm::vec4 position_area;
    glm::vec4 normal_map;
    glm::vec4 albedo;
    glm::vec4 emission;
};

void dispatch_1d(std::size_t items) {
    const auto groups = static_cast<GLuint>(std::max<std::size_t>(1, (items + 63) / 64));
    glDispatchCompute(groups, 1, 1);
}

template <typename T>
gpu::Buffer storage(const std::vector<T>& data, GLbitfield flags = 0) {
    return gpu::Buffer(std::max<std::size_t>(sizeof(T), data.size() * sizeof(T)), data.empty() ? nullptr : data.data(), flags);
}

class CssmMethod final : public Method {
public:
    std::string_view name() const override { return "cssm"; }

    void render(const FrameContext& frame) override {
        gbuffer_.render(frame);
        shadows_.render(frame, frame.knob_int("shadow_map_size"));
        direct_light_.render(frame, gbuffer_, shadows_);
        if (frame.scene.world_bounds().empty()) return;

        ensure_bake(frame);
        if (!bake_ || bake_->atlas.texels.empty()) return;
        const int bounces = frame.knob_int("bounces");
        const float threshold = static_cast<float>(frame.knob("threshold"));
        const int pcf = frame.knob_int("pcf");
        const std::uint64_t lighting = passes::light_view_fingerprint(frame.scene, frame.knob_int("shadow_map_size")) ^
                                       (static_cast<std::uint64_t>(bounces) << 56) ^
                                       (static_cast<std::uint64_t>(pcf) << 48) ^
                                       std::hash<float>{}(threshold) ^ bake_generation_;
        set_batches(pcf);
        reset_counters();
        if (lighting != lighting_) {
            light_atlas(frame, bounces, threshold, pcf);
            lighting_ = lighting;
            ++atlas_solutions_;
        }
        read_counters(atlas_counters_);
        reset_counters();
        final_gather(frame, static_cast<float>(frame.knob("final_threshold")), pcf);
        read_counters(pixel_counters_);
    }

    std::vector<ResidentStructure> resident() const override {
        std::vector<ResidentStructure> structures = {
            {"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
            {"shadow_maps", shadows_.bytes(), fmt::format("direct light: {} lights with power", shadows_.map_count())}};
        if (!bake_) return structures;
        const auto& maps = bake_->maps;
        structures.push_back({"surface_atlas", atlas_bytes_,
                              fmt::format("{} texels ({}x{}, {} charts) over {} objects: senders, receivers and cube-map "
                                          "origins; radiance of each bounce",
                                          bake_->atlas.texels.size(), bake_->atlas.width, bake_->atlas.height,
                                          bake_->atlas.charts.size(), bake_->atlas.objects.size())});
        structures.push_back({"coherent_surface_shadow_maps", cssm_bytes_,
                              fmt::format("{} depth cube maps of 6x{}^2 in {} order: {} bytes raw, {} compressed ({:.1f}:1)",
                                          maps.depth.maps, maps.settings.face_size, traversal_name(bake_->parameters.traversal),
                                          maps.depth.uncompressed_bytes(), maps.depth.compressed_bytes(), compression_ratio())});
        structures.push_back({"radiosity_tree", tree_bytes_,
                              fmt::format("median-cut hierarchy of {} nodes, depth {}", bake_->tree.nodes.size(), bake_->tree.depth)});
        return structures;
    }

    std::map<std::string, double> statistics() const override {
        std::map<std::string, double> stats = {{"bakes", static_cast<double>(bakes_)},
                                               {"bakes_loaded", static_cast<double>(bakes_loaded_)},
                                               {"atlas_solutions", static_cast<double>(atlas_solutions_)}};
        if (!bake_) return stats;
        const auto& maps = bake_->maps;
        auto mean = [](const std::array<std::uint64_t, 3>& c, int which) {
            return c[0] > 0 ? static_cast<double>(c[which]) / static_cast<double>(c[0]) : 0.0;
        };
        stats.insert({{"atlas_texels", static_cast<double>(bake_->atlas.texels.size())},
                      {"atlas_width", static_cast<double>(bake_->atlas.width)},
                      {"atlas_height", static_cast<double>(bake_->atlas.height)},
                      {"atlas_charts", static_cast<double>(bake_->atlas.charts.size())},
                      {"cube_maps", static_cast<double>(maps.depth.maps)},
                      {"cube_face_size", static_cast<double>(maps.settings.face_size)},
                      {"depth_runs", static_cast<double>(maps.depth.runs())},
                      {"uncompressed_bytes", static_cast<double>(maps.depth.uncompressed_bytes())},
                      {"compressed_bytes", static_cast<double>(maps.depth.compressed_bytes())},
                      {"compression_ratio", compression_ratio()},
                      {"bake_seconds", maps.bake_seconds},
                      {"tree_nodes", static_cast<double>(bake_->tree.nodes.size())},
                      {"gather_batches", static_cast<double>(batches_.size())},
                      {"texel_receivers", static_cast<double>(atlas_counters_[0])},
                      {"nodes_per_texel_mean", mean(atlas_counters_, 1)},
                      {"nodes_per_pixel_mean", mean(pixel_counters_, 1)},
                      {"nodes_visited_per_pixel_mean", mean(pixel_counters_, 2)},
                      {"pixel_receivers", static_cast<double>(pixel_counters_[0])},
                      {"resident_bytes", static_cast<double>(gbuffer_.bytes() + shadows_.bytes() + atlas_bytes_ +
                                                             cssm_bytes_ + tree_bytes_)}});
        return stats;
    }

private:
    double compression_ratio() const {
        const auto& depth = bake_->maps.depth;
        return depth.compressed_bytes() > 0 ? static_cast<double>(depth.uncompressed_bytes()) / depth.compressed_bytes() : 0.0;
    }

    void prepare(const FrameContext& frame) override { ensure_bake(frame); }

    // The bake these knobs need: kept, loaded from the cache directory, or baked (and stored there).
    void ensure_bake(const FrameContext& frame) {
        const BakeParameters parameters{static_cast<float>(frame.knob("atlas_resolution")), frame.knob_int("face_size"),
                                        static_cast<Traversal>(frame.knob_int("traversal"))};
        const std::uint64_t geometry = passes::geometry_fingerprint(frame.scene);
        if (bake_ && bake_->parameters == parameters && bake_->geometry == geometry) return;
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_bake");
        const Precompute& precompute = frame.precompute;
        const std::string key = bake_key(frame.scene, parameters);
        if (precompute.cache_dir) {
            if (auto cached = load_cached_bake(*precompute.cache_dir, key, frame.scene)) {
                bake_ = std::make_unique<CssmBake>(std::move(*cached));
                ++bakes_loaded_;
                ++bake_generation_;
                log::info("cssm", "loaded bake {} ({} cube maps, {} bytes)", key, bake_->maps.depth.maps,
                          bake_->maps.depth.compressed_bytes());
                if (precompute.progress) precompute.progress(1.0, "loaded from cache");
                upload();
                return;
            }
        }
        BakeProgress progress;
        if (precompute.progress) {
            progress = [&](std::uint32_t done, std::uint32_t total) {
                return precompute.progress(total > 0 ? static_cast<double>(done) / total : 1.0, "depth cube maps");
            };
        }
        // Replaces the resident bake only once complete: a cancelled bake loses nothing.
        bake_ = std::make_unique<CssmBake>(bake_scene(frame.scene, parameters, progress));
        ++bakes_;
        ++bake_generation_;
        log::info("cssm", "baked {} cube maps of 6x{}^2 over {} atlas texels in {:.2f} s ({} -> {} bytes, {:.1f}:1)",
                  bake_->maps.depth.maps, parameters.face_size, bake_->atlas.texels.size(), bake_->maps.bake_seconds,
                  bake_->maps.depth.uncompressed_bytes(), bake_->maps.depth.compressed_bytes(), compression_ratio());
        if (precompute.cache_dir) {
            try {
                store_cached_bake(*precompute.cache_dir, key, *bake_);
            } catch (const std::exception& error) {
                log::warn("cssm", "bake not cached: {}", error.what());
            }
        }
        upload();
    }

    void upload() {
        const CssmBake& bake = *bake_;
        const std::size_t texel_count = bake.atlas.texels.size();
        std::vector<GpuTexel> texels(texel_count);
        for (std::size_t t = 0; t < texel_count; ++t) {
            texels[t] = {glm::vec4(bake.maps.origins[t], bake.atlas.texels[t].area),
                         glm::vec4(bake.normals[t], static_cast<float>(bake.maps.map_of_texel[t])), glm::vec4(bake.albedo[t], 0.0f),
                         glm::vec4(bake.emission[t], 0.0f)};
        }
        std::vector<GpuNode> nodes(bake.tree.nodes.size());
        for (std::size_t n = 0; n < nodes.size(); ++n) {
            const RadiosityNode& node = bake.tree.nodes[n];
            nodes[n] = {glm::vec4(node.centre, node.radius), glm::vec4(node.normal, node.cone_cos), glm::vec4(node.area, 0, 0, 0),
                        glm::uvec4(node.child, node.skip, node.representative, node.texel)};
        }
        const CompressedDepthMaps& depth = bake.maps.depth;
        std::vector<std::uint32_t> packed_depth((depth.run_depth.size() + 1) / 2, 0);
        for (std::size_t r = 0; r < depth.run_depth.size(); ++r)
            packed_depth[r / 2] |= static_cast<std::uint32_t>(depth.run_depth[r]) << (16 * (r % 2));

        texels_ = storage(texels);
        nodes_ = storage(nodes);
        node_radiance_ = gpu::Buffer(nodes.size() * sizeof(glm::vec4), nullptr, 0);
        pixel_runs_ = storage(depth.pixel_runs);
        run_start_ = storage(depth.run_start);
        run_depth_ = storage(packed_depth);
        level_nodes_ = storage(bake.tree.level_nodes);
        for (gpu::Buffer* buffer : {&direct_, &bounce_, &total_, &irradiance_})
            *buffer = gpu::Buffer(texel_count * sizeof(glm::vec4), nullptr, 0);
        atlas_bytes_ = texels_.bytes() + 4 * direct_.bytes();
        cssm_bytes_ = pixel_runs_.bytes() + run_start_.bytes() + run_depth_.bytes();
        tree_bytes_ = nodes_.bytes() + node_radiance_.bytes() + level_nodes_.bytes();
        batch_pcf_ = -1;
    }

    // Roots of subtrees, grouped into batches whose node counts fit the per-draw budget.
    void set_batches(int pcf) {
        if (pcf == batch_pcf_) return;
        batch_pcf_ = pcf;
        const double search_steps = std::log2(std::max<double>(2.0, bake_->maps.depth.maps)) + 2.0;
        const double steps_per_node = static_cast<double>(pcf * pcf) * search_steps + 8.0;
        const auto budget = static_cast<std::uint32_t>(std::max(1.0, kStepsPerBatch / steps_per_node));
        const std::vector<std::uint32_t> roots = bake_->tree.cut((budget + 1) / 2);
        batches_.clear();
        std::uint32_t first = 0, nodes = 0;
        for (std::uint32_t r = 0; r < roots.size(); ++r) {
            const std::uint32_t subtree = 2 * bake_->tree.nodes[roots[r]].leaves - 1;
            if (r > first && nodes + subtree > budget) {
                batches_.push_back({first, r - first});
                first = r;
                nodes = 0;
            }
            nodes += subtree;
        }
        batches_.push_back({first, static_cast<std::uint32_t>(roots.size()) - first});
        roots_ = storage(roots);
    }

    void bind_tree(const gpu::ShaderProgram& program, int pcf, float threshold) const {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_NODES, nodes_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_NODE_RADIANCE, node_radiance_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXELS, texels_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_PIXEL_RUNS, pixel_runs_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_RUN_START, run_start_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_RUN_DEPTH, run_depth_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_ROOTS, roots_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_LEVEL_NODES, level_nodes_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_COUNTERS, counters_.id());
        const CubeMapSettings& cube = bake_->maps.settings;
        program.set("u_face_size", cube.face_size);
        program.set("u_far_plane", cube.far_plane);
        program.set("u_near_plane", cube.near_plane);
        program.set("u_pcf", pcf);
        program.set("u_threshold", threshold);
    }

    // Direct light on the atlas, then bounces 1 .. n-1 by hierarchical radiosity; the texels'
    // total exitance is pulled up the tree for the final gather (which makes bounce n).
    void light_atlas(const FrameContext& frame, int bounces, float threshold, int pcf) {
        const auto texel_count = static_cast<unsigned>(bake_->atlas.texels.size());
        {
            gpu::GpuTimers::Scope timing(frame.timers, "cssm_atlas_direct");
            const gpu::ShaderProgram& program = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/atlas_direct.comp"));
            program.use();
            bind_tree(program, pcf, threshold);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_OUT, direct_.id());
            program.set("u_texel_count", texel_count);
            program.set("u_emission_only", 1);
            dispatch_1d(texel_count);
            program.set("u_emission_only", 0);
            for (std::size_t l = 0; l < frame.scene.lights.size(); ++l) {
                if (!shadows_.has_map(l)) continue;
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                passes::set_light_uniforms(program, frame.scene.lights[l]);
                shadows_.bind(program, l);
                dispatch_1d(texel_count);
            }
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        glCopyNamedBufferSubData(direct_.id(), total_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
        glCopyNamedBufferSubData(direct_.id(), bounce_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
        for (int bounce = 1; bounce < bounces; ++bounce) {
            pull(frame, bounce_);
            gpu::GpuTimers::Scope timing(frame.timers, "cssm_atlas_gather");
            const gpu::ShaderProgram& gather = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/gather.comp"));
            gather.use();
            bind_tree(gather, pcf, threshold);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_OUT, irradiance_.id());
            gather.set("u_texel_count", texel_count);
            for (std::size_t b = 0; b < batches_.size(); ++b) {
                gather.set("u_first_root", batches_[b].first);
                gather.set("u_root_count", batches_[b].count);
                gather.set("u_first_batch", b == 0 ? 1 : 0);
                dispatch_1d(texel_count);
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            }
            const gpu::ShaderProgram& finish = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/bounce.comp"));
            finish.use();
            bind_tree(finish, pcf, threshold);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_IN, irradiance_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_OUT, total_.id());
            finish.set("u_texel_count", texel_count);
            dispatch_1d(texel_count);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            std::swap(bounce_, irradiance_);  // this bounce's exitance is the next one's source
        }
        pull(frame, total_);
    }

    void pull(const FrameContext& frame, const gpu::Buffer& source) const {
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_pull");
        const gpu::ShaderProgram& program = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/pull.comp"));
        program.use();
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_NODES, nodes_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_NODE_RADIANCE, node_radiance_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_LEVEL_NODES, level_nodes_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_IN, source.id());
        const auto node_count = static_cast<unsigned>(bake_->tree.nodes.size());
        program.set("u_leaves", 1);
        program.set("u_first", 0u);
        program.set("u_count", node_count);
        dispatch_1d(node_count);
        program.set("u_leaves", 0);
        const auto& first = bake_->tree.level_first;
        for (std::size_t level = 0; level + 1 < first.size(); ++level) {
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            program.set("u_first", first[level]);
            program.set("u_count", first[level + 1] - first[level]);
            dispatch_1d(first[level + 1] - first[level]);
        }
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    void final_gather(const FrameContext& frame, float threshold, int pcf) {
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_final_gather");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "cssm/final_gather.frag", {}});
        program.use();
        bind_tree(program, pcf, threshold);
        program.set("u_camera_position", frame.camera.position);
        gbuffer_.bind_textures();
        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        frame.state.apply({.blend = gpu::Blend::additive});
        for (const Batch& batch : batches_) {
            program.set("u_first_root", batch.first);
            program.set("u_root_count", batch.count);
            triangle_.draw();
        }
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    }

    void reset_counters() {
        if (!counters_) counters_ = gpu::Buffer(CSSM_COUNTERS * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
        const std::array<std::uint32_t, CSSM_COUNTERS> zero{};
        counters_.upload(0, sizeof(zero), zero.data());
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    }

    // receivers, nodes gathered, nodes visited
    void read_counters(std::array<std::uint64_t, 3>& out) const {
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        std::array<std::uint32_t, CSSM_COUNTERS> c{};
        glGetNamedBufferSubData(counters_.id(), 0, sizeof(c), c.data());
        out = {c[CSSM_COUNTER_RECEIVERS],
               (static_cast<std::uint64_t>(c[CSSM_COUNTER_NODES_HIGH]) << 32) | c[CSSM_COUNTER_NODES_LOW],
               (static_cast<std::uint64_t>(c[CSSM_COUNTER_VISITED_HIGH]) << 32) | c[CSSM_COUNTER_VISITED_LOW]};
    }

    struct Batch {
        std::uint32_t first = 0, count = 0;
    };

    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::DirectLightPass direct_light_;
    passes::FullscreenTriangle triangle_;
    std::unique_ptr<CssmBake> bake_;
    std::uint64_t bake_generation_ = 0;
    std::uint64_t lighting_ = 0;
    std::size_t bakes_ = 0, bakes_loaded_ = 0, atlas_solutions_ = 0;
    gpu::Buffer texels_, nodes_, node_radiance_, pixel_runs_, run_start_, run_depth_, level_nodes_, roots_, counters_;
    gpu::Buffer direct_, bounce_, total_, irradiance_;
    std::size_t atlas_bytes_ = 0, cssm_bytes_ = 0, tree_bytes_ = 0;
    std::vector<Batch> batches_;
    int batch_pcf_ = -1;
    std::array<std::uint64_t, 3> atlas_counters_{}, pixel_counters_{};
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
        {"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (direct light)"}};
    auto preset = [](double atlas, double face, double threshold, double pcf) {
        return KnobValues{{"atlas_resolution", atlas}, {"face_size", face},      {"traversal", 2},
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
