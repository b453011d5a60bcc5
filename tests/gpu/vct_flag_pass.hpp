// vct's flag pass (shaders/vct/flag_nodes.comp) on buffers a test fills: the node pool, the
// counters and the voxel fragments, bound where the pass reads them, and one dispatch of it.
#pragma once

#include "renderer/gpu/gl_objects.hpp"
#include "renderer/gpu/shader_program.hpp"

#include "vct/vct_layout.h"

#include <cstdint>
#include <vector>

namespace bounce::test {

struct FlagPassBuffers {
    gpu::Buffer nodes, counters, fragments;

    FlagPassBuffers(const std::vector<std::uint32_t>& node_words, const std::vector<std::uint32_t>& fragment_words)
        : nodes(gpu::storage_of(node_words)),
          counters(gpu::storage_of(std::vector<std::uint32_t>(VCT_COUNTERS, 0u))),
          fragments(gpu::storage_of(fragment_words)) {
        gpu::bind_storage(VCT_BINDING_NODES, nodes);
        gpu::bind_storage(VCT_BINDING_COUNTERS, counters);
        gpu::bind_storage(VCT_BINDING_FRAGMENTS, fragments);
    }
};

// Flags level `level` of an octree whose leaves are at `leaf_level` from `fragment_count` fragments.
inline void dispatch_flag_pass(const gpu::ShaderProgram& flag, std::uint32_t level, std::uint32_t leaf_level,
                               std::uint32_t fragment_count) {
    flag.set("u_level", level);
    flag.set("u_leaf_level", leaf_level);
    flag.set("u_fragment_count", fragment_count);
    flag.dispatch_threads(fragment_count);
}

}  // namespace bounce::test
