#include "renderer/methods/cssm/cssm_method.hpp"

#include "renderer/base/log.hpp"
#include "renderer/gpu/counter_buffer.hpp"
#include "renderer/methods/cssm/bake_cache.hpp"
#include "renderer/methods/cssm/hull_overlap.hpp"
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
        if (!bake_ || bake_->texel_count() == 0) return;
        const int bounces = frame.knob_int("bounces");
        const float threshold = static_cast<float>(frame.knob("threshold"));
        const int pcf = frame.knob_int("pcf");
        per_texel_ = frame.knob_int("per_texel") != 0;
        const std::uint64_t lighting = passes::light_view_fingerprint(frame.scene, frame.knob_int("shadow_map_size")) ^
                                       (static_cast<std::uint64_t>(bounces) << 56) ^ (per_texel_ ? 1ull << 40 : 0ull) ^
                                       (static_cast<std::uint64_t>(pcf) << 48) ^
                                       std::hash<float>{}(threshold) ^ bake_generation_;
        set_batches(pcf);
        if (lighting != lighting_) {
            reset_counters();
            light_atlas(frame, bounces, threshold, pcf);
            lighting_ = lighting;
            ++atlas_solutions_;
            read_counters(atlas_counters_);  // kept: frames that reuse the solution report the one made
        }
        reset_counters();
        if (per_texel_) {
            texel_display(frame, pcf);
        } else if (frame.knob_int("jitter_frames") > 1) {
            jittered_final_gather(frame, lighting, pcf);
        } else {
            final_gather(frame, frame.output, static_cast<float>(frame.knob("final_threshold")), pcf, 0);
        }
        read_counters(pixel_counters_);
    }

    std::vector<ResidentStructure> resident() const override {
        std::vector<ResidentStructure> structures = {
            {"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
            {"shadow_maps", shadows_.bytes(), fmt::format("direct light: {} lights with power", shadows_.map_count())}};
        if (!bake_) return structures;
        std::string objects;
        for (const BakeGroup& group : bake_->groups) {
            objects += fmt::format(
                "{}{} ({}: {} texels, {} cube maps, {} bytes compressed{})", objects.empty() ? "" : "; ",
                group.moving ? "moving object '" + frame_scene_->objects[group.objects.front()].name + "'"
                             : fmt::format("{} static objects", group.objects.size()),
                group.loaded ? "from the cache" : "baked", group.atlas.texels.size(), group.maps.depth.maps,
                group.maps.depth.compressed_bytes(),
                group.csm ? fmt::format("; its CSM: {} directions, {} bytes compressed", group.csm->directions.size(),
                                        group.csm->depth.compressed_bytes())
                          : "");
        }
        structures.push_back({"surface_atlas", atlas_bytes_,
                              fmt::format("{} texels over {} groups: senders, receivers and cube-map origins; radiance of "
                                          "each bounce",
                                          bake_->texel_count(), bake_->groups.size())});
        structures.push_back({"coherent_surface_shadow_maps", cssm_bytes_,
                              fmt::format("{} depth cube maps of 6x{}^2 in {} order, CSMs for moving objects: {} bytes raw, "
                                          "{} compressed ({:.1f}:1). {}",
                                          bake_->cube_maps(), bake_->parameters.face_size,
                                          traversal_name(bake_->parameters.traversal), bake_->uncompressed_bytes(),
                                          bake_->compressed_bytes(), compression_ratio(), objects)});
        structures.push_back({"radiosity_tree", tree_bytes_,
                              fmt::format("median-cut hierarchy of {} nodes, depth {}", bake_->tree.nodes.size(), bake_->tree.depth)});
        return structures;
    }

    std::map<std::string, double> statistics() const override {
        std::map<std::string, double> stats = {{"bakes", static_cast<double>(bakes_)},
                                               {"per_texel", per_texel_ ? 1.0 : 0.0},
                                               {"jittered_frames", static_cast<double>(jittered_frames_)},
                                               {"bakes_loaded", static_cast<double>(bakes_loaded_)},
                                               {"atlas_solutions", static_cast<double>(atlas_solutions_)}};
        if (!bake_) return stats;
        auto mean = [](const std::array<std::uint64_t, 3>& c, int which) {
            return c[0] > 0 ? static_cast<double>(c[which]) / static_cast<double>(c[0]) : 0.0;
        };
        double bake_seconds = 0.0;
        std::size_t charts = 0, loaded = 0, csm_maps = 0;
        for (const BakeGroup& group : bake_->groups) {
            bake_seconds += group.maps.bake_seconds + (group.csm ? group.csm->bake_seconds : 0.0);
            charts += group.atlas.charts.size();
            loaded += group.loaded ? 1 : 0;
            csm_maps += group.csm ? group.csm->directions.size() : 0;
        }
        stats.insert({{"atlas_texels", static_cast<double>(bake_->texel_count())},
                      {"atlas_charts", static_cast<double>(charts)},
                      {"bake_groups", static_cast<double>(bake_->groups.size())},
                      {"bake_groups_loaded", static_cast<double>(loaded)},
                      {"moving_objects", static_cast<double>(bake_->moving.size())},
                      {"csm_maps", static_cast<double>(csm_maps)},
                      {"hull_overlaps", static_cast<double>(overlaps_.size())},
                      {"placements", static_cast<double>(placements_)},
                      {"cube_maps", static_cast<double>(bake_->cube_maps())},
                      {"cube_face_size", static_cast<double>(bake_->parameters.face_size)},
                      {"uncompressed_bytes", static_cast<double>(bake_->uncompressed_bytes())},
                      {"compressed_bytes", static_cast<double>(bake_->compressed_bytes())},
                      {"compression_ratio", compression_ratio()},
                      {"bake_seconds", bake_seconds},
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
        return bake_->compressed_bytes() > 0 ? static_cast<double>(bake_->uncompressed_bytes()) / bake_->compressed_bytes() : 0.0;
    }

    void prepare(const FrameContext& frame) override { ensure_bake(frame); }

    // The objects to bake as moving: those declared so, and those moved since the static group was
    // baked (moving one of those costs a rebake of the static group without it, once).
    std::vector<std::uint32_t> moving_objects(const scene::Scene& scene) const {
        std::vector<std::uint32_t> moving;
        for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
            if (scene.objects[o].mesh < 0) continue;
            const bool was_moving = bake_ && std::binary_search(bake_->moving.begin(), bake_->moving.end(), o);
            const bool moved = bake_ && o < bake_->baked_transforms.size() && bake_->baked_transforms[o] != scene.objects[o].transform;
            if (scene.objects[o].dynamic || was_moving || moved) moving.push_back(o);
        }
        return moving;
    }

    // The bake these knobs need: kept (its moving objects placed anew), or baked group by group,
    // each loaded from the cache directory when there, else baked and stored there.
    void ensure_bake(const FrameContext& frame) {
        frame_scene_ = &frame.scene;
        const BakeParameters parameters{static_cast<float>(frame.knob("atlas_resolution")), frame.knob_int("face_size"),
                                        static_cast<Traversal>(frame.knob_int("traversal")), frame.knob_int("csm_directions")};
        const std::vector<std::uint32_t> moving = moving_objects(frame.scene);
        const std::uint64_t geometry = passes::geometry_fingerprint(frame.scene);
        if (bake_ && bake_->parameters == parameters && bake_->moving == moving) {
            if (geometry != placed_geometry_) place(frame.scene);
            return;
        }
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_bake");
        if (bake_) {
            for (std::uint32_t o : moving) {
                if (!std::binary_search(bake_->moving.begin(), bake_->moving.end(), o)) {
                    log::info("cssm", "object '{}' moved without being declared dynamic: rebaking the static objects "
                              "without it, and it alone with a CSM", frame.scene.objects[o].name);
                }
            }
        }
        // Replaces the resident bake only once complete: a cancelled bake loses nothing.
        bake_ = std::make_unique<CssmBake>(bake_scene(frame.scene, parameters, moving,
                                                      BakeOptions{frame.precompute.cache_dir, frame.precompute.progress}));
        for (const BakeGroup& group : bake_->groups) {
            if (group.loaded) {
                ++bakes_loaded_;
            } else {
                ++bakes_;
            }
        }
        ++bake_generation_;
        log::info("cssm", "{} groups ({} from the cache): {} cube maps of 6x{}^2 over {} atlas texels ({} -> {} bytes, {:.1f}:1)",
                  bake_->groups.size(), bakes_loaded_, bake_->cube_maps(), parameters.face_size, bake_->texel_count(),
                  bake_->uncompressed_bytes(), bake_->compressed_bytes(), compression_ratio());
        upload();
        check_overlaps(frame.scene);
        placed_geometry_ = geometry;
    }

    // Moving objects moved: their texels, the hierarchy over all texels and the GPU copies follow;
    // no bake.
    void place(const scene::Scene& scene) {
        place_texels(scene, *bake_);
        upload_placement(scene);
        check_overlaps(scene);
        placed_geometry_ = passes::geometry_fingerprint(scene);
        ++placements_;
    }

    void check_overlaps(const scene::Scene& scene) {
        overlaps_ = find_hull_overlaps(scene, bake_->moving);
        for (const HullOverlap& overlap : overlaps_) {
            log::warn("cssm", "object '{}' reaches into the convex hull of moving object '{}': visibility through '{}' "
                      "is unreliable there (CSMs answer only outside their object's hull)",
                      scene.objects[overlap.other].name, scene.objects[overlap.moving].name, scene.objects[overlap.moving].name);
        }
    }

    // Every group's compressed sequences, concatenated: cube maps, then CSMs.
    void upload() {
        const CssmBake& bake = *bake_;
        std::vector<std::uint32_t> pixel_runs, run_start, packed_depth;
        std::vector<std::uint16_t> run_depth;
        auto append = [&](const CompressedDepthMaps& depth) {
            const auto first_entry = static_cast<std::uint32_t>(pixel_runs.size());
            const auto run_base = static_cast<std::uint32_t>(run_start.size());
            for (std::uint32_t entry : depth.pixel_runs) pixel_runs.push_back(run_base + entry);
            run_start.insert(run_start.end(), depth.run_start.begin(), depth.run_start.end());
            run_depth.insert(run_depth.end(), depth.run_depth.begin(), depth.run_depth.end());
            return first_entry;
        };
        group_run_base_.clear();
        std::vector<glsl::CssmCsm> csms;
        std::vector<glm::vec4> directions;
        std::vector<std::uint32_t> nearest;
        for (std::uint32_t g = 0; g < bake.groups.size(); ++g) {
            const BakeGroup& group = bake.groups[g];
            group_run_base_.push_back(append(group.maps.depth));
            if (group.csm) {
                const std::uint32_t runs = append(group.csm->depth);
                csms.push_back({glm::vec4(group.csm->centre, group.csm->radius),
                                glm::uvec4(directions.size(), nearest.size(), runs, group.csm->face_size), g, 0, 0, 0});
                directions.insert(directions.end(), group.csm->directions.begin(), group.csm->directions.end());
                nearest.insert(nearest.end(), group.csm->nearest_map.begin(), group.csm->nearest_map.end());
            }
        }
        packed_depth.assign((run_depth.size() + 1) / 2, 0);
        for (std::size_t r = 0; r < run_depth.size(); ++r)
            packed_depth[r / 2] |= static_cast<std::uint32_t>(run_depth[r]) << (16 * (r % 2));
        pixel_runs_ = storage(pixel_runs);
        run_start_ = storage(run_start);
        run_depth_ = storage(packed_depth);
        csms_ = storage(csms);
        csm_directions_ = storage(directions);
        csm_nearest_ = storage(nearest);
        csm_count_ = static_cast<unsigned>(csms.size());
        const std::size_t texel_count = bake.texel_count();
        for (gpu::Buffer* buffer : {&direct_, &bounce_, &total_, &irradiance_, &indirect_})
            *buffer = gpu::Buffer(std::max<std::size_t>(1, texel_count) * sizeof(glm::vec4), nullptr, 0);
        cssm_bytes_ = pixel_runs_.bytes() + run_start_.bytes() + run_depth_.bytes() + csms_.bytes() + csm_directions_.bytes() +
                      csm_nearest_.bytes();
        upload_placement(*frame_scene_);
    }

    // What moves with the objects: texels, groups' frames, the hierarchy.
    void upload_placement(const scene::Scene& scene) {
        const CssmBake& bake = *bake_;
        const std::size_t texel_count = bake.texel_count();
        std::vector<glsl::CssmTexel> texels(texel_count);
        for (std::size_t t = 0; t < texel_count; ++t) {
            const std::uint32_t g = bake.texel_group[t];
            const std::uint32_t local = static_cast<std::uint32_t>(t - bake.group_first_texel[g]);
            texels[t] = {glm::vec4(bake.positions[t], bake.areas[t]),
                         glm::vec4(bake.normals[t], static_cast<float>(bake.groups[g].maps.map_of_texel[local])),
                         glm::vec4(bake.albedo[t], static_cast<float>(g)), glm::vec4(bake.emission[t], 0.0f)};
        }
        std::vector<glsl::CssmGroup> groups(bake.groups.size());
        for (std::size_t g = 0; g < groups.size(); ++g) {
            const BakeGroup& group = bake.groups[g];
            std::uint32_t csm = kNoNode;
            for (std::uint32_t c = 0, seen = 0; c <= g; ++c)
                if (bake.groups[c].csm) {
                    if (c == g) csm = seen;
                    ++seen;
                }
            groups[g] = {world_to_group(scene, group), glm::uvec4(group_run_base_[g], csm, 0, 0),
                         glm::vec4(group.maps.settings.near_plane, group.maps.settings.far_plane, 0.0f, 0.0f)};
        }
        std::vector<glsl::CssmNode> nodes(bake.tree.nodes.size());
        for (std::size_t n = 0; n < nodes.size(); ++n) {
            const RadiosityNode& node = bake.tree.nodes[n];
            nodes[n] = {glm::vec4(node.centre, node.radius), glm::vec4(node.normal, node.cone_cos),
                        glm::vec4(node.area, static_cast<float>(node.leaves), 0, 0),
                        glm::uvec4(node.child, node.skip, node.representative, node.texel)};
        }
        texels_ = storage(texels);
        groups_ = storage(groups);
        nodes_ = storage(nodes);
        node_radiance_ = gpu::Buffer(std::max<std::size_t>(1, nodes.size()) * sizeof(glm::vec4), nullptr, 0);
        level_nodes_ = storage(bake.tree.level_nodes);
        atlas_bytes_ = texels_.bytes() + 5 * direct_.bytes() + groups_.bytes();
        tree_bytes_ = nodes_.bytes() + node_radiance_.bytes() + level_nodes_.bytes();
        batch_pcf_ = -1;
    }

    // Roots of subtrees, grouped into batches whose node counts fit the per-draw budget.
    void set_batches(int pcf) {
        if (pcf == batch_pcf_) return;
        batch_pcf_ = pcf;
        const double search_steps = std::log2(std::max<double>(2.0, bake_->cube_maps())) + 2.0;
        // A visibility query: the sender's PCF taps, the receiver's (with moving objects), and each
        // CSM's lookup.
        const double queries = csm_count_ > 0 ? 2.0 : 1.0;
        const double steps_per_node = static_cast<double>(pcf * pcf) * search_steps * queries +
                                      static_cast<double>(csm_count_) * (search_steps + 8.0) + 8.0 + 64.0 * (queries - 1.0);
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
        counters_.bind(CSSM_BINDING_COUNTERS);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_GROUPS, groups_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_CSMS, csms_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_CSM_DIRECTIONS, csm_directions_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_CSM_NEAREST, csm_nearest_.id());
        program.set("u_face_size", bake_->parameters.face_size);
        program.set("u_csm_count", csm_count_);
        program.set("u_texel_size", bake_->texel_size);
        program.set("u_pcf", pcf);
        program.set("u_threshold", threshold);
        program.set("u_jitter_seed", 0u);
    }

    // Direct light on the atlas, then bounces 1 .. n-1 by hierarchical radiosity; the texels'
    // total exitance is pulled up the tree for the final gather (which makes bounce n). The
    // per-texel display runs all n bounces here instead and sums their irradiance per texel.
    void light_atlas(const FrameContext& frame, int bounces, float threshold, int pcf) {
        const auto texel_count = static_cast<unsigned>(bake_->texel_count());
        {
            gpu::GpuTimers::Scope timing(frame.timers, "cssm_atlas_direct");
            const gpu::ShaderProgram& program = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/atlas_direct.comp"));
            program.use();
            bind_tree(program, pcf, threshold);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_OUT, direct_.id());
            program.set("u_texel_count", texel_count);
            program.set("u_emission_only", 1);
            program.dispatch_threads(texel_count);
            program.set("u_emission_only", 0);
            for (std::size_t l = 0; l < frame.scene.lights.size(); ++l) {
                if (!shadows_.has_map(l)) continue;
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                passes::set_light_uniforms(program, frame.scene.lights[l]);
                shadows_.bind(program, l);
                program.dispatch_threads(texel_count);
            }
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        glCopyNamedBufferSubData(direct_.id(), total_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
        glCopyNamedBufferSubData(direct_.id(), bounce_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
        glClearNamedBufferData(indirect_.id(), GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        const int atlas_bounces = per_texel_ ? bounces : bounces - 1;
        for (int bounce = 1; bounce <= atlas_bounces; ++bounce) {
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
                gather.dispatch_threads(texel_count);
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            }
            const gpu::ShaderProgram& finish = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/bounce.comp"));
            finish.use();
            bind_tree(finish, pcf, threshold);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_IN, irradiance_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_OUT, total_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_INDIRECT, indirect_.id());
            finish.set("u_texel_count", texel_count);
            finish.dispatch_threads(texel_count);
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
        program.dispatch_threads(node_count);
        program.set("u_leaves", 0);
        const auto& first = bake_->tree.level_first;
        for (std::size_t level = 0; level + 1 < first.size(); ++level) {
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            program.set("u_first", first[level]);
            program.set("u_count", first[level + 1] - first[level]);
            program.dispatch_threads(first[level + 1] - first[level]);
        }
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    // Draws the final gather's batches, added up into `target` (which holds the direct light, or
    // nothing). A non-zero `jitter_seed` moves every sender to a random point of its area.
    void final_gather(const FrameContext& frame, const gpu::Framebuffer& target, float threshold, int pcf,
                      unsigned jitter_seed) {
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_final_gather");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "cssm/final_gather.frag", {}});
        program.use();
        bind_tree(program, pcf, threshold);
        program.set("u_jitter_seed", jitter_seed);
        program.set("u_camera_position", frame.camera.position);
        gbuffer_.bind_textures();
        glBindFramebuffer(GL_FRAMEBUFFER, target.id());
        glViewport(0, 0, frame.width, frame.height);
        frame.state.apply({.blend = gpu::Blend::additive});
        for (const Batch& batch : batches_) {
            program.set("u_first_root", batch.first);
            program.set("u_root_count", batch.count);
            triangle_.draw();
        }
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    }

    // §4.5: while nothing changes, each frame gathers from senders jittered anew and the frames'
    // mean is shown, converging over `jitter_frames` frames (then kept without gathering).
    void jittered_final_gather(const FrameContext& frame, std::uint64_t lighting, int pcf) {
        const int frames = frame.knob_int("jitter_frames");
        const float threshold = static_cast<float>(frame.knob("final_threshold"));
        std::uint64_t view = lighting ^ std::hash<float>{}(threshold) ^ (static_cast<std::uint64_t>(pcf) << 32) ^
                             (static_cast<std::uint64_t>(frame.width) << 16) ^ static_cast<std::uint64_t>(frame.height);
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) view = view * 1099511628211ull ^ std::hash<float>{}(frame.view_projection[c][r]);
        if (!jitter_mean_ || jitter_mean_.width() != frame.width || jitter_mean_.height() != frame.height) {
            jitter_mean_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, frame.width, frame.height});
            jitter_frame_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, frame.width, frame.height});
            jitter_frame_.set_filter(GL_NEAREST, GL_NEAREST);
            jitter_mean_.set_filter(GL_NEAREST, GL_NEAREST);
            jitter_target_ = gpu::Framebuffer();
            jitter_target_.attach_color(0, jitter_frame_);
            jitter_target_.set_draw_buffers(1);
            jitter_target_.check_complete("the cssm jitter frame");
            jitter_view_ = ~view;
        }
        if (view != jitter_view_) {
            jitter_view_ = view;
            jittered_frames_ = 0;
            glClearTexImage(jitter_mean_.id(), 0, GL_RGBA, GL_FLOAT, nullptr);
        }
        if (jittered_frames_ < frames) {
            ++jittered_frames_;
            glClearTexImage(jitter_frame_.id(), 0, GL_RGBA, GL_FLOAT, nullptr);
            final_gather(frame, jitter_target_, threshold, pcf, static_cast<unsigned>(jittered_frames_));
            gpu::GpuTimers::Scope timing(frame.timers, "cssm_accumulate");
            const gpu::ShaderProgram& accumulate = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/accumulate.comp"));
            accumulate.use();
            glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, jitter_frame_.id());
            glBindImageTexture(0, jitter_mean_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            accumulate.set("u_size", glm::ivec2(frame.width, frame.height));
            accumulate.set("u_weight", 1.0f / static_cast<float>(jittered_frames_));
            accumulate.dispatch_grid({frame.width, frame.height}, {8, 8});
            glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        }
        const gpu::ShaderProgram& composite = frame.shaders.get({"common/fullscreen.vert", "cssm/composite.frag", {}});
        composite.use();
        glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, jitter_mean_.id());
        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        frame.state.apply({.blend = gpu::Blend::additive});
        triangle_.draw();
    }

    // The view-dependent lightmap: one draw, each pixel blending the summed irradiance of the
    // texels around it.
    void texel_display(const FrameContext& frame, int pcf) {
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_texel_display");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "cssm/texel_display.frag", {}});
        program.use();
        bind_tree(program, pcf, 0.0f);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CSSM_BINDING_TEXEL_INDIRECT, indirect_.id());
        gbuffer_.bind_textures();
        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        frame.state.apply({.blend = gpu::Blend::additive});
        triangle_.draw();
    }

    void reset_counters() {
        if (!counters_) counters_ = gpu::CounterBuffer(CSSM_COUNTERS);
        counters_.reset();
    }

    // receivers, nodes gathered, nodes visited
    void read_counters(std::array<std::uint64_t, 3>& out) const {
        const gpu::CounterValues c = counters_.read();
        out = {c[CSSM_COUNTER_RECEIVERS], c.wide(CSSM_COUNTER_NODES_LOW, CSSM_COUNTER_NODES_HIGH),
               c.wide(CSSM_COUNTER_VISITED_LOW, CSSM_COUNTER_VISITED_HIGH)};
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
    gpu::Buffer texels_, nodes_, node_radiance_, pixel_runs_, run_start_, run_depth_, level_nodes_, roots_;
    gpu::CounterBuffer counters_;
    gpu::Buffer groups_, csms_, csm_directions_, csm_nearest_;
    std::vector<std::uint32_t> group_run_base_;
    unsigned csm_count_ = 0;
    std::vector<HullOverlap> overlaps_;
    std::uint64_t placed_geometry_ = 0;
    std::size_t placements_ = 0;
    const scene::Scene* frame_scene_ = nullptr;
    gpu::Buffer direct_, bounce_, total_, irradiance_, indirect_;
    bool per_texel_ = false;
    gpu::Texture jitter_mean_, jitter_frame_;
    gpu::Framebuffer jitter_target_;
    std::uint64_t jitter_view_ = 0;
    int jittered_frames_ = 0;
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
