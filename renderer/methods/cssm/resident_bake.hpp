// The `cssm` bake a frame's knobs need, resident on the GPU: the groups baked, or loaded from the
// cache directory (bake_scene), and their compressed depth sequences (every group's cube maps,
// each moving group's CSM) concatenated into the buffers shaders/cssm/cssm_tree.glsl reads.
#pragma once

#include "renderer/gpu/shader_program.hpp"
#include "renderer/methods/cssm/cssm_bake.hpp"
#include "renderer/methods/method.hpp"

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace bounce::methods::cssm {

class ResidentBake {
public:
    // Whether the resident bake is the one the frame's knobs and moving objects need.
    bool serves(const FrameContext& frame) const;
    // Bakes what the frame needs, group by group, each loaded from the cache directory when there,
    // else baked and stored there, and uploads it. Replaces the resident bake only once complete:
    // a cancelled bake loses nothing.
    void make(const FrameContext& frame);
    // The same bake as work that runs off the render thread, on a snapshot of the scene; its result
    // goes to adopt().
    PendingWork work(const FrameContext& frame) const;
    // Makes a finished work's bake resident when it is the one the frame needs (the scene may have
    // changed since the snapshot); false otherwise, and the result is dropped.
    bool adopt(PrecomputeResult& result, const FrameContext& frame);

    explicit operator bool() const { return static_cast<bool>(bake_); }
    CssmBake& bake() { return *bake_; }
    const CssmBake& bake() const { return *bake_; }
    // Counts the bakes made resident: a new one changes every solution.
    std::uint64_t generation() const { return generation_; }
    // Where group g's cube maps start in the concatenated pixel-run table.
    std::uint32_t group_run_base(std::size_t g) const { return group_run_base_[g]; }
    unsigned csm_count() const { return csm_count_; }
    std::size_t bytes() const { return bytes_; }
    double compression_ratio() const;

    // The depth sequences and CSMs, and the bake's uniforms (face size, CSM count, texel size).
    void bind(const gpu::ShaderProgram& program) const;

    // The resident structure, each group's objects named from `scene`.
    ResidentStructure structure(const scene::Scene& scene) const;
    // Bakes made and loaded; with a bake resident, its sizes, compression and baking time.
    void add_statistics(std::map<std::string, double>& stats) const;

private:
    BakeParameters parameters(const FrameContext& frame) const;
    std::vector<std::uint32_t> moving_objects(const scene::Scene& scene) const;
    void upload();
    // Makes `bake` resident: counts it, logs it and uploads it.
    void install(std::unique_ptr<CssmBake> bake, const scene::Scene& scene);

    std::unique_ptr<CssmBake> bake_;
    std::uint64_t generation_ = 0;
    std::size_t bakes_ = 0, bakes_loaded_ = 0;
    gpu::Buffer pixel_runs_, run_start_, run_depth_, csms_, csm_directions_, csm_nearest_;
    std::vector<std::uint32_t> group_run_base_;
    unsigned csm_count_ = 0;
    std::size_t bytes_ = 0;
};

}  // namespace bounce::methods::cssm
