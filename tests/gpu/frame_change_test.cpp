// What a frame says it redid (frame_change.hpp) is what its method did: each method counts the light
// work it redoes (cssm its atlas solutions and rescales, vct its injections and rescales, isr its VPL tree builds), and a frame
// said to redo nothing must leave that count as it was, one said to redo the scene's light must add
// one. The planner prices frames by this classification, so a frame called warm that solved again
// would be priced as a warm frame and break a time budget.
#include "gpu_fixture.hpp"

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
        EXPECT_EQ(resources->change_for(request.method, plan_frame(request).knobs), expected);
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
    EXPECT_EQ(resources->change_for(low.method, plan_frame(low).knobs), after);
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

}  // namespace
}  // namespace bounce::test
