// The bench corpus beyond Cornell boxes: scenes of the kinds users render, generated here (no
// downloads) so that every run measures the same geometry. Each stresses what a method leaves out:
// enclosed lamps behind thin shades, sun through openings onto many bounces, an open scene where
// one bounce is all there is, glossy transport, alpha-masked foliage.
#pragma once

#include "bench/scenes.hpp"

#include <vector>

namespace bounce::bench {

// furnished_room, atrium, outdoor, glossy_gallery, foliage. `detail` scales the tessellation of
// curved parts (columns, shades, spheres, leaves): 1 gives a few thousand triangles a scene.
std::vector<BenchScene> corpus_scenes(int detail = 1);

}  // namespace bounce::bench
