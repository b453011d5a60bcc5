// Shadow maps are drawn again only when something they depend on changed.
#include "gpu_fixture.hpp"
#include "renderer/passes/shadow_maps.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace bounce::test {
namespace {

// What a pass needs to draw `scene`'s shadow maps outside a frame; the scene may change between draws.
struct MapsOfAScene {
    explicit MapsOfAScene(scene::Scene drawn) : scene(std::move(drawn)) { timers.begin_frame(); }
    // The same pass seen from another camera.
    passes::PassContext seen_from(const scene::Camera& camera) {
        return {scene, gpu_scene, shaders, state, timers, output, 16, 16, camera};
    }
    ~MapsOfAScene() { timers.resolve(); }
    Renderer& renderer = shared_renderer();  // first: it makes the GL context current on this thread
    scene::Scene scene;
    gpu::GpuScene gpu_scene{scene};
    gpu::ShaderCache shaders;
    gpu::StateCache state;
    gpu::GpuTimers timers;
    gpu::Framebuffer output;
    const passes::PassContext context{scene, gpu_scene, shaders, state, timers, output, 16, 16, scene.cameras[0]};
    passes::ShadowMaps maps;
};

TEST(ShadowMaps, ReusedUntilALightOrATransformChanges) {
    MapsOfAScene drawn(scene::make_cornell_box());
    scene::Scene& scene = drawn.scene;
    passes::ShadowMaps& maps = drawn.maps;
    const passes::PassContext& context = drawn.context;

    maps.render(context, 64);
    EXPECT_FALSE(maps.last_render_reused());
    maps.render(context, 64);
    EXPECT_TRUE(maps.last_render_reused());

    scene.objects[1].transform[3].x += 0.01f;  // a block moved
    maps.render(context, 64);
    EXPECT_FALSE(maps.last_render_reused());
    maps.render(context, 64);
    EXPECT_TRUE(maps.last_render_reused());

    scene.lights[0].position.y -= 0.01f;  // the light moved
    maps.render(context, 64);
    EXPECT_FALSE(maps.last_render_reused());
    maps.render(context, 128);  // another size
    EXPECT_FALSE(maps.last_render_reused());
    EXPECT_EQ(maps.frames_drawn(), 4u);
    EXPECT_EQ(maps.frames_reused(), 2u);
}

// Each light's map depends on where that light is and how it shines, not on its colour or
// intensity: dimming a light redraws nothing, moving one of two lights redraws its map alone.
TEST(ShadowMaps, EachMapIsRedrawnOnlyWhenItsOwnLightMovesOrReshapes) {
    scene::Scene two_lights = scene::make_cornell_box();
    scene::Light spot = two_lights.lights[0];
    spot.type = scene::LightType::spot;
    spot.direction = {0.0f, -1.0f, 0.0f};
    two_lights.lights.push_back(spot);
    MapsOfAScene drawn(std::move(two_lights));
    scene::Scene& scene = drawn.scene;
    passes::ShadowMaps& maps = drawn.maps;
    const passes::PassContext& context = drawn.context;

    maps.render(context, 64);
    EXPECT_EQ(maps.maps_drawn(), 2u);
    scene.lights[0].intensity *= 0.5f;
    scene.lights[1].color = {1.0f, 0.5f, 0.25f};
    maps.render(context, 64);
    EXPECT_TRUE(maps.last_render_reused());
    EXPECT_EQ(maps.maps_drawn(), 2u);
    scene.lights[1].outer_cone *= 0.5f;  // reshaped: its map alone
    maps.render(context, 64);
    EXPECT_FALSE(maps.last_render_reused());
    EXPECT_EQ(maps.maps_drawn(), 3u);
    scene.lights[0].position.x += 0.01f;  // moved: its map alone
    maps.render(context, 64);
    EXPECT_EQ(maps.maps_drawn(), 4u);
    scene.lights[1].intensity = 0.0f;  // no power: no map, and none drawn
    maps.render(context, 64);
    EXPECT_EQ(maps.maps_drawn(), 4u);
    EXPECT_FALSE(maps.has_map(1));
    EXPECT_TRUE(maps.has_map(0));
    scene.lights[1].intensity = 1.0f;  // power again: its map drawn
    maps.render(context, 64);
    EXPECT_EQ(maps.maps_drawn(), 5u);
    EXPECT_TRUE(maps.has_map(1));
    scene.objects[1].transform[3].x += 0.01f;  // a block moved: every map
    maps.render(context, 64);
    EXPECT_EQ(maps.maps_drawn(), 7u);
}

// A directional light's view cascades follow the camera: a camera that moves redraws them and not
// the light's map over the scene; one that stays, or moves along the light (the cascades see the
// same across it), reuses both; cascades no longer asked for are let go.
TEST(ShadowMaps, ACameraThatMovesRedrawsTheViewCascadesAlone) {
    scene::Scene wide;
    wide.materials.push_back(matte({0.5f, 0.5f, 0.5f}));
    add_square(wide, "ground", glm::vec3(0.0f), 200.0f, {0, 1, 0}, 0);
    wide.lights.push_back(directional_light(glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)), 3.0f));
    wide.cameras.push_back(top_down_camera(3.0f, 1.0f));
    MapsOfAScene drawn(std::move(wide));
    passes::ShadowMaps& maps = drawn.maps;

    maps.render(drawn.context, 256, 2);
    EXPECT_EQ(maps.maps_drawn(), 1u);
    EXPECT_EQ(maps.view_cascades_drawn(), 2u);
    const float scene_texel = glm::length(drawn.scene.world_bounds().extent()) / 256.0f;
    EXPECT_GT(maps.finest_view_texel(0), 0.0f);
    EXPECT_LT(maps.finest_view_texel(0), scene_texel);
    const std::size_t with_cascades = maps.bytes();
    EXPECT_EQ(with_cascades, passes::ShadowMaps::bytes_for(drawn.scene, 256, 2));
    maps.render(drawn.context, 256, 2);
    EXPECT_TRUE(maps.last_render_reused());

    scene::Camera along = drawn.scene.cameras[0];
    along.position -= 0.5f * drawn.scene.lights[0].direction;
    maps.render(drawn.seen_from(along), 256, 2);
    EXPECT_TRUE(maps.last_render_reused());

    // The first frame's passes: the maps over the scene and their cascades, timed as `shadow_maps`.
    const auto pass_names = [&] {
        std::vector<std::string> names;
        for (const gpu::PassTiming& pass : drawn.timers.resolve()) names.push_back(pass.pass);
        drawn.timers.begin_frame();
        return names;
    };
    EXPECT_EQ(pass_names(), std::vector<std::string>{"shadow_maps"});

    scene::Camera moved = drawn.scene.cameras[0];
    moved.position.x += 5.0f;
    maps.render(drawn.seen_from(moved), 256, 2);
    EXPECT_FALSE(maps.last_render_reused());
    // Cascades alone, timed apart: the planner prices a change of the lights by `shadow_maps`.
    EXPECT_EQ(pass_names(), std::vector<std::string>{"shadow_view_cascades"});
    EXPECT_EQ(maps.maps_drawn(), 1u);  // the map over the scene kept
    EXPECT_EQ(maps.view_cascades_drawn(), 4u);
    EXPECT_EQ(maps.frames_drawn(), 2u);
    maps.render(drawn.seen_from(moved), 256, 2);
    EXPECT_TRUE(maps.last_render_reused());

    maps.render(drawn.seen_from(moved), 256, 0);
    EXPECT_EQ(maps.finest_view_texel(0), 0.0f);
    EXPECT_EQ(maps.bytes(), passes::ShadowMaps::bytes_for(drawn.scene, 256, 0));
    EXPECT_LT(maps.bytes(), with_cascades);
    EXPECT_EQ(maps.maps_drawn(), 1u);
}

// A reused map gives the same frame as a freshly drawn one, and a moved light changes it; a dimmed
// light keeps its map and renders as a fresh one does.
TEST(ShadowMaps, ReusedMapsRenderTheSameFrame) {
    scene::Scene scene = scene::make_cornell_box();
    RenderRequest request;
    request.width = request.height = 48;
    auto resources = shared_renderer().upload(scene);
    const auto first = shared_renderer().render(*resources, request);
    const auto second = shared_renderer().render(*resources, request);
    EXPECT_EQ(first.frame.rgba, second.frame.rgba);
    scene.lights[0].position.x -= 0.1f;
    const auto moved = shared_renderer().render(*resources, request);
    EXPECT_NE(first.frame.rgba, moved.frame.rgba);
    const auto fresh = render_scene(scene, request);
    EXPECT_EQ(moved.frame.rgba, fresh.frame.rgba);
    scene.lights[0].intensity *= 0.25f;
    const auto dimmed = shared_renderer().render(*resources, request);
    EXPECT_NE(dimmed.frame.rgba, moved.frame.rgba);
    EXPECT_EQ(dimmed.frame.rgba, render_scene(scene, request).frame.rgba);
}

}  // namespace
}  // namespace bounce::test
