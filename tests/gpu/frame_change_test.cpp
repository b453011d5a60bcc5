// What a frame says it redid (frame_change.hpp) is what its method did: each method counts the light
// work it redoes (cssm its atlas solutions and rescales, vct its injections and rescales, isr its VPL tree builds), and a frame
// said to redo nothing must leave that count as it was, one said to redo the scene's light must add
// one. The planner prices frames by this classification, so a frame called warm that solved again
// would be priced as a warm frame and break a time budget.
#include "gpu_fixture.hpp"

#include "renderer/planning/planner.hpp"
#include "renderer/scene/builtin.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>

namespace bounce::test {
namespace {

constexpr int kSize = 32;

struct LightWork {
    const char* method;
    const char* count;  // the method's statistic that counts the light work it redid
    bool bakes;         // a `bake` request builds its structures (Method::prepare)
};

class FrameChanges : public ::testing::TestWithParam<LightWork> {};

TEST_P(FrameChanges, EachFrameSaysWhatItRedidAsItsMethodCountsIt) {
    const LightWork work = GetParam();
    scene::Scene scene = scene::make_cornell_box();
    Renderer& renderer = shared_renderer();
    auto resources = renderer.upload(scene);
    const RenderRequest draft = method_request(work.method, "draft", kSize);
    double counted = 0.0;
    // Renders `request`, checks that it was predicted to redo `expected`, that it says so, and that the
    // method's count of light work grew by `solved` (0 or 1).
    const auto frame = [&](const RenderRequest& request, FrameChange expected, int solved, const char* step) {
        SCOPED_TRACE(step);
        EXPECT_EQ(resources->change_for(request.method, plan_frame(request).knobs, resources->view_of(request)), expected);
        const RenderResult result = renderer.render(*resources, request);
        EXPECT_EQ(result.stats.change, expected);
        const double now = result.stats.method_statistics.at(work.count);
        EXPECT_EQ(now - counted, solved) << work.count;
        counted = now;
        return result;
    };
    // A frame times its shadow maps only where it drew them (the planner prices them by it).
    const auto drew_maps = [](const RenderResult& result) {
        return std::any_of(result.stats.passes.begin(), result.stats.passes.end(),
                           [](const gpu::PassTiming& pass) { return pass.pass == "shadow_maps"; });
    };
    EXPECT_TRUE(drew_maps(frame(draft, FrameChange::knobs_and_scene, 1, "the method's first frame")));
    EXPECT_FALSE(drew_maps(frame(draft, FrameChange::none, 0, "the same frame again")));
    frame(method_request(work.method, "draft", 2 * kSize), FrameChange::none, 0, "another size: nothing of the scene's");
    scene.lights.front().intensity *= 1.001f;
    // Dimmed, a light keeps its shadow map.
    EXPECT_FALSE(drew_maps(frame(draft, FrameChange::light_power, 1, "a light dimmed by a factor no image shows")));
    frame(draft, FrameChange::none, 0, "warm again");
    scene.lights.front().position.x += 0.01f;
    EXPECT_TRUE(drew_maps(frame(draft, FrameChange::lights, 1, "a light moved")));
    frame(draft, FrameChange::none, 0, "warm again");
    scene.objects.back().transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.05f, 0.0f, 0.0f)) * scene.objects.back().transform;
    scene.fit_bounds(scene.objects.size() - 1);
    EXPECT_TRUE(drew_maps(frame(draft, FrameChange::objects, 1, "an object moved")));
    const RenderRequest low = method_request(work.method, "low", kSize);
    frame(low, FrameChange::knobs, 1, "another preset");
    scene.lights.front().intensity *= 1.001f;
    frame(draft, FrameChange::knobs_and_scene, 1, "another preset after a light changed");
    // A bake builds the structures for its knobs and solves no light: the next frame redoes the light.
    // A method whose bake builds nothing leaves its next frame to build them.
    const FrameChange after = work.bakes ? FrameChange::lights : FrameChange::knobs;
    const FrameStats baked = renderer.prepare(*resources, low, [](double, const std::string&) { return true; });
    EXPECT_EQ(baked.change, work.bakes ? FrameChange::knobs : FrameChange::none);
    EXPECT_EQ(resources->change_for(low.method, plan_frame(low).knobs, resources->view_of(low)), after);
    const RenderResult after_bake = renderer.render(*resources, low);
    EXPECT_EQ(after_bake.stats.change, after);
    EXPECT_EQ(after_bake.stats.method_statistics.at(work.count) - counted, 1.0);
    resources.reset();
}

INSTANTIATE_TEST_SUITE_P(Methods, FrameChanges,
                         ::testing::Values(LightWork{"cssm", "light_updates", true},
                                           LightWork{"vct", "light_updates", true},
                                           LightWork{"isr", "vpl_tree_builds", false}),
                         [](const auto& info) { return std::string(info.param.method); });

// A sun over a ground with a blocker, seen from above at an angle: the scene a moved camera
// changes the view cascades of.
scene::Scene sunlit_ground() {
    scene::Scene scene;
    scene.materials.push_back(matte({0.5f, 0.5f, 0.5f}));
    add_square(scene, "ground", glm::vec3(0.0f), 20.0f, {0, 1, 0}, 0);
    add_square(scene, "blocker", glm::vec3(0.0f, 1.0f, 0.0f), 0.5f, {0, 1, 0}, 0);
    scene.lights.push_back(directional_light(glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)), 3.0f));
    scene.cameras.push_back(scene::Camera::look_at({4.0f, 3.0f, 4.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 0.8f));
    // A far plane of its own: one derived from the scene moves with the camera, and the cascades'
    // depths with it.
    scene.cameras.back().z_far = 60.0f;
    return scene;
}

// A camera moved across the sun redraws the view cascades and nothing else, and its frame says so
// (`view`), before and after: the planner prices such frames by the cascades, where before they
// passed for warm frames that took up to ten times as long. A camera moved along the sun, its far
// plane its own, keeps the cascades' fit, and redoes nothing. A frame of another shape fits other
// cascades; a frame of the same shape at another size does not.
class ViewChanges : public ::testing::TestWithParam<const char*> {};

TEST_P(ViewChanges, AMovedCameraRedrawsTheViewCascadesAlone) {
    const std::string method = GetParam();
    scene::Scene scene = sunlit_ground();
    Renderer& renderer = shared_renderer();
    auto resources = renderer.upload(scene);
    RenderRequest request = method_request(method, "draft", kSize);
    request.camera = scene.cameras.front();
    const auto frame = [&](const RenderRequest& asked, FrameChange predicted, FrameChange said, const char* step) {
        SCOPED_TRACE(step);
        EXPECT_EQ(resources->change_for(asked.method, plan_frame(asked).knobs, resources->view_of(asked)), predicted);
        const RenderResult result = renderer.render(*resources, asked);
        EXPECT_EQ(result.stats.change, said);
        return result;
    };
    const RenderResult first = frame(request, FrameChange::knobs_and_scene, FrameChange::knobs_and_scene, "the first frame");
    EXPECT_TRUE(first.stats.ran("shadow_maps"));
    frame(request, FrameChange::none, FrameChange::none, "the same frame again");
    request.camera->position.x += 1.0f;
    const RenderResult moved = frame(request, FrameChange::view, FrameChange::view, "the camera moved across the sun");
    EXPECT_TRUE(moved.stats.ran("shadow_view_cascades"));
    EXPECT_FALSE(moved.stats.ran("shadow_maps"));
    frame(request, FrameChange::none, FrameChange::none, "warm again");
    request.camera->position -= 2.0f * scene.lights.front().direction;
    const RenderResult along = frame(request, FrameChange::none, FrameChange::none, "the camera moved along the sun");
    EXPECT_FALSE(along.stats.ran("shadow_view_cascades"));
    RenderRequest smaller = request;
    smaller.width = smaller.height = kSize / 2;
    frame(smaller, FrameChange::none, FrameChange::none, "the same shape, smaller");
    RenderRequest wider = request;
    wider.width = 2 * kSize;
    frame(wider, FrameChange::view, FrameChange::view, "another shape");
    // Without cascades a moved camera redoes nothing.
    RenderRequest without = request;
    without.knobs["shadow_cascades"] = 0;
    frame(without, FrameChange::knobs, FrameChange::knobs, "the cascades turned off");
    without.camera->position.z += 1.0f;
    frame(without, FrameChange::none, FrameChange::none, "the camera moved, no cascades");
    // The planner sees what the frame would redo from the request's view.
    request.camera->position.z += 1.0f;
    EXPECT_EQ(planning::changes_on(*resources, resources->view_of(without))(method, "draft", {{"shadow_cascades", 0}}),
              FrameChange::none);
    EXPECT_EQ(planning::changes_on(*resources, resources->view_of(request))(method, "draft", {{"shadow_cascades", 0}}),
              FrameChange::none);
    EXPECT_EQ(planning::changes_on(*resources, resources->view_of(request))(method, "draft", {}), FrameChange::knobs);
    resources.reset();
}

INSTANTIATE_TEST_SUITE_P(Methods, ViewChanges, ::testing::Values("direct", "cssm", "vct", "isr"),
                         [](const auto& info) { return std::string(info.param); });

// Without a sun no light casts view cascades: a moved camera redoes nothing.
TEST(ViewChanges, WithoutASunAMovedCameraRedoesNothing) {
    scene::Scene scene = scene::make_cornell_box();
    ASSERT_TRUE(std::none_of(scene.lights.begin(), scene.lights.end(),
                             [](const scene::Light& light) { return light.type == scene::LightType::directional; }));
    auto resources = shared_renderer().upload(scene);
    RenderRequest request = method_request("direct", "draft", kSize);
    request.camera = camera_for(scene, request);
    shared_renderer().render(*resources, request);
    request.camera->position.x += 0.1f;
    EXPECT_EQ(resources->state_now(plan_frame(request).knobs, resources->view_of(request)).view, 0u);
    EXPECT_EQ(resources->change_for("direct", plan_frame(request).knobs, resources->view_of(request)), FrameChange::none);
    EXPECT_EQ(shared_renderer().render(*resources, request).stats.change, FrameChange::none);
    resources.reset();
}

}  // namespace
}  // namespace bounce::test
