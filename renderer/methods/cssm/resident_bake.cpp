#include "renderer/methods/cssm/resident_bake.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"

#include "cssm/cssm_layout.h"

#include <fmt/format.h>

namespace bounce::methods::cssm {

BakeParameters ResidentBake::parameters(const FrameContext& frame) const {
    return {static_cast<float>(frame.knob("atlas_resolution")), frame.knob_int("face_size"),
            static_cast<Traversal>(frame.knob_int("traversal")), frame.knob_int("csm_directions")};
}

// The objects to bake as moving: those declared so, and those moved since the static group was
// baked (moving one of those costs a rebake of the static group without it, once).
std::vector<std::uint32_t> ResidentBake::moving_objects(const scene::Scene& scene) const {
    std::vector<std::uint32_t> moving;
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
        if (scene.objects[o].mesh < 0) continue;
        const bool was_moving = bake_ && std::binary_search(bake_->moving.begin(), bake_->moving.end(), o);
        const bool moved = bake_ && o < bake_->baked_transforms.size() && bake_->baked_transforms[o] != scene.objects[o].transform;
        if (scene.objects[o].dynamic || was_moving || moved) moving.push_back(o);
    }
    return moving;
}

bool ResidentBake::serves(const FrameContext& frame) const {
    return bake_ && bake_->parameters == parameters(frame) && bake_->moving == moving_objects(frame.scene);
}

namespace {

// A finished bake on its way from the worker that made it to the render thread.
struct BakeResult final : PrecomputeResult {
    std::unique_ptr<CssmBake> bake;
};

}  // namespace

void ResidentBake::make(const FrameContext& frame) {
    install(std::make_unique<CssmBake>(bake_scene(frame.scene, parameters(frame), moving_objects(frame.scene),
                                                  BakeOptions{frame.precompute.cache_dir, frame.precompute.progress})),
            frame.scene);
}

PendingWork ResidentBake::work(const FrameContext& frame) const {
    const BakeParameters wanted = parameters(frame);
    const std::vector<std::uint32_t> moving = moving_objects(frame.scene);
    Hasher key;
    key.add(wanted.atlas_resolution).add(wanted.face_size).add(static_cast<int>(wanted.traversal)).add(wanted.csm_directions);
    for (std::uint32_t o : moving) key.add(o);
    auto snapshot = std::make_shared<const scene::Scene>(frame.scene);
    return {fmt::format("cssm-bake-{:016x}", key.value()),
            [snapshot, wanted, moving, cache_dir = frame.precompute.cache_dir](const PrecomputeProgress& progress) {
                auto result = std::make_shared<BakeResult>();
                result->bake = std::make_unique<CssmBake>(bake_scene(*snapshot, wanted, moving, BakeOptions{cache_dir, progress}));
                return std::shared_ptr<PrecomputeResult>(std::move(result));
            }};
}

bool ResidentBake::adopt(PrecomputeResult& result, const FrameContext& frame) {
    auto* finished = dynamic_cast<BakeResult*>(&result);
    if (!finished || !finished->bake || !(finished->bake->parameters == parameters(frame)) ||
        finished->bake->moving != moving_objects(frame.scene)) {
        return false;
    }
    // Texels were placed where the snapshot had the moving objects; they may have moved since.
    CssmBake& bake = *finished->bake;
    const bool moved = std::any_of(bake.moving.begin(), bake.moving.end(), [&](std::uint32_t o) {
        return bake.baked_transforms[o] != frame.scene.objects[o].transform;
    });
    if (moved) place_texels(frame.scene, bake);
    install(std::move(finished->bake), frame.scene);
    return true;
}

void ResidentBake::install(std::unique_ptr<CssmBake> bake, const scene::Scene& scene) {
    if (bake_) {
        for (std::uint32_t o : bake->moving) {
            if (!std::binary_search(bake_->moving.begin(), bake_->moving.end(), o)) {
                log::info("cssm", "object '{}' moved without being declared dynamic: rebaking the static objects "
                          "without it, and it alone with a CSM", scene.objects[o].name);
            }
        }
    }
    const BakeParameters wanted = bake->parameters;
    bake_ = std::move(bake);
    for (const BakeGroup& group : bake_->groups) {
        if (group.loaded) {
            ++bakes_loaded_;
        } else {
            ++bakes_;
        }
    }
    ++generation_;
    log::info("cssm", "{} groups ({} from the cache): {} cube maps of 6x{}^2 over {} atlas texels ({} -> {} bytes, {:.1f}:1)",
              bake_->groups.size(), bakes_loaded_, bake_->cube_maps(), wanted.face_size, bake_->texel_count(),
              bake_->uncompressed_bytes(), bake_->compressed_bytes(), compression_ratio());
    upload();
}

double ResidentBake::compression_ratio() const {
    return bake_->compressed_bytes() > 0 ? static_cast<double>(bake_->uncompressed_bytes()) / bake_->compressed_bytes() : 0.0;
}

// Every group's compressed sequences, concatenated: cube maps, then CSMs.
void ResidentBake::upload() {
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
    pixel_runs_ = gpu::storage_of(pixel_runs);
    run_start_ = gpu::storage_of(run_start);
    run_depth_ = gpu::storage_of(packed_depth);
    csms_ = gpu::storage_of(csms);
    csm_directions_ = gpu::storage_of(directions);
    csm_nearest_ = gpu::storage_of(nearest);
    csm_count_ = static_cast<unsigned>(csms.size());
    bytes_ = pixel_runs_.bytes() + run_start_.bytes() + run_depth_.bytes() + csms_.bytes() + csm_directions_.bytes() +
             csm_nearest_.bytes();
}

void ResidentBake::bind(const gpu::ShaderProgram& program) const {
    gpu::bind_storage(CSSM_BINDING_PIXEL_RUNS, pixel_runs_);
    gpu::bind_storage(CSSM_BINDING_RUN_START, run_start_);
    gpu::bind_storage(CSSM_BINDING_RUN_DEPTH, run_depth_);
    gpu::bind_storage(CSSM_BINDING_CSMS, csms_);
    gpu::bind_storage(CSSM_BINDING_CSM_DIRECTIONS, csm_directions_);
    gpu::bind_storage(CSSM_BINDING_CSM_NEAREST, csm_nearest_);
    program.set("u_face_size", bake_->parameters.face_size);
    program.set("u_csm_count", csm_count_);
    program.set("u_texel_size", bake_->texel_size);
}

ResidentStructure ResidentBake::structure(const scene::Scene& scene) const {
    std::string objects;
    for (const BakeGroup& group : bake_->groups) {
        objects += fmt::format(
            "{}{} ({}: {} texels, {} cube maps, {} bytes compressed{})", objects.empty() ? "" : "; ",
            group.moving ? "moving object '" + scene.objects[group.objects.front()].name + "'"
                         : fmt::format("{} static objects", group.objects.size()),
            group.loaded ? "from the cache" : "baked", group.atlas.texels.size(), group.maps.depth.maps,
            group.maps.depth.compressed_bytes(),
            group.csm ? fmt::format("; its CSM: {} directions, {} bytes compressed", group.csm->directions.size(),
                                    group.csm->depth.compressed_bytes())
                      : "");
    }
    return {"coherent_surface_shadow_maps", bytes_,
            fmt::format("{} depth cube maps of 6x{}^2 in {} order, CSMs for moving objects: {} bytes raw, "
                        "{} compressed ({:.1f}:1). {}",
                        bake_->cube_maps(), bake_->parameters.face_size, traversal_name(bake_->parameters.traversal),
                        bake_->uncompressed_bytes(), bake_->compressed_bytes(), compression_ratio(), objects)};
}

void ResidentBake::add_statistics(std::map<std::string, double>& stats) const {
    stats.insert({{"bakes", static_cast<double>(bakes_)}, {"bakes_loaded", static_cast<double>(bakes_loaded_)}});
    if (!bake_) return;
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
                  {"cube_maps", static_cast<double>(bake_->cube_maps())},
                  {"cube_face_size", static_cast<double>(bake_->parameters.face_size)},
                  {"uncompressed_bytes", static_cast<double>(bake_->uncompressed_bytes())},
                  {"compressed_bytes", static_cast<double>(bake_->compressed_bytes())},
                  {"compression_ratio", compression_ratio()},
                  {"bake_seconds", bake_seconds}});
}

}  // namespace bounce::methods::cssm
