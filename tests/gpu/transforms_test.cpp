// A file renders alike whether its exporter placed each mesh by its node's transform or baked the
// transform into the vertices: every fit a method makes to the scene's bounds (the sun's shadow
// maps and light view, isr's radius for τ, vct's voxel grid, cssm's atlas) sees the same boxes.
#include "gpu_fixture.hpp"

#include "renderer/image/metrics.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cstdio>

namespace bounce::test {
namespace {

constexpr int kSize = 64;

// The world bounds are those of the vertices, not of each mesh box's corners transformed: a rotated
// box holds space its mesh does not fill (on this file, 23 units more above the engine, of 273).
TEST(Transforms, TheSceneBoundsAreThoseOfItsPlacedVertices) {
    const scene::Scene file = sunlit_engine();
    const scene::Scene baked = with_transforms_baked(file);
    const scene::Aabb placed = file.world_bounds(), exact = baked.world_bounds();
    // The same float products (transform times vertex) on both sides: equal, not near.
    EXPECT_EQ(placed.min, exact.min);
    EXPECT_EQ(placed.max, exact.max);
    // An object moved without fitting again keeps its looser box, which holds its vertices, never the
    // stale one; fitted again, the box of its moved vertices.
    scene::Scene moved = file;
    const std::size_t rotated = 1;
    scene::Object& object = moved.objects[rotated];
    object.transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1000.0f, 0.0f)) * object.transform;
    scene::Aabb vertices;
    for (const scene::Primitive& primitive : moved.meshes[static_cast<std::size_t>(object.mesh)].primitives) {
        for (const glm::vec3& p : primitive.positions) vertices.extend(glm::vec3(object.transform * glm::vec4(p, 1.0f)));
    }
    const scene::Aabb loose = object.world_bounds(moved.meshes[static_cast<std::size_t>(object.mesh)]);
    EXPECT_TRUE(glm::all(glm::lessThanEqual(loose.min, vertices.min)) && glm::all(glm::lessThanEqual(vertices.max, loose.max)));
    EXPECT_NE(loose.max, vertices.max);  // rotated: the corners hold more
    moved.fit_bounds(rotated);
    const scene::Aabb fitted = moved.objects[rotated].world_bounds(moved.meshes[static_cast<std::size_t>(object.mesh)]);
    EXPECT_EQ(fitted.min, vertices.min);
    EXPECT_EQ(fitted.max, vertices.max);
}

// Every GPU method's frame of the placed file against its frame of the baked copy. The two differ
// only where the GPU rounds a transformed vertex otherwise than the bake did: a pixel whose coverage
// flips, at most, which changes relMSE by at most about one pixel's share, 1 / (64 x 64) = 2.4e-4 for
// a change as large as the pixel (a relative error of 1). Before the bounds were fitted to the
// vertices (each mesh box's corners transformed), the draft frames differed by 1.5e-2 (direct: the
// sun's shadow map is fitted to the bounds), 2.5e-3 (vct), 1.4e-3 (isr) and 2.4e-4 (cssm) on
// llvmpipe; fitted, by 2e-11 (cssm: 6e-7).
TEST(Transforms, AFileRendersAsItsBakedCopyWithEveryMethod) {
    const scene::Scene file = sunlit_engine();
    const scene::Scene baked = with_transforms_baked(file);
    const double one_pixel = 1.0 / (kSize * kSize);
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        const RenderRequest request = method_request(method, "draft", kSize);
        const double between = image::compare(render_scene(file, request).frame, render_scene(baked, request).frame).rel_mse;
        std::printf("%s draft: relMSE %.2e between the placed file and its baked copy\n", method, between);
        EXPECT_LE(between, one_pixel) << method;
    }
}

}  // namespace
}  // namespace bounce::test
