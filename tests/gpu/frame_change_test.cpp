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

// A frame counts the programs it compiled, once per renderer: the first frame of a preset on a new
// renderer compiles its method's, the same frame again and a frame of another size compile none,
// and the planner keeps the time of the frames that compiled nothing alone (record_frame). On
// llvmpipe the first took 137 ms, compiling 5 programs, and the frame that built another scene 9 ms.
TEST(ProgramsCompiled, AFrameCountsTheProgramsItCompiledOncePerRenderer) {
    Renderer fresh(gpu::DeviceChoice::resolve(std::nullopt));
    const scene::Scene scene = scene::make_cornell_box();
    auto resources = fresh.upload(scene);
    const RenderRequest draft = method_request("direct", "draft", kSize);
    const RenderResult first = fresh.render(*resources, draft);
    EXPECT_EQ(first.stats.change, FrameChange::knobs_and_scene);
    EXPECT_GT(first.stats.programs_compiled, 0u);
    const RenderResult again = fresh.render(*resources, draft);
    EXPECT_EQ(again.stats.programs_compiled, 0u);
    EXPECT_EQ(fresh.render(*resources, method_request("direct", "draft", 2 * kSize)).stats.programs_compiled, 0u);
    // Another scene on the same renderer: its first frame builds the scene's structures, with the
    // programs the renderer holds.
    auto other = fresh.upload(scene);
    const RenderResult built = fresh.render(*other, draft);
    EXPECT_EQ(built.stats.change, FrameChange::knobs_and_scene);
    EXPECT_EQ(built.stats.programs_compiled, 0u);
    planning::SceneMeasurements measured;
    planning::DeviceCosts device("test");
    device.set("direct", "draft", {1.0, 0.0});
    planning::record_frame(measured, nullptr, device, first.stats, kSize, kSize);
    planning::record_frame(measured, nullptr, device, built.stats, kSize, kSize);
    const auto kept = measured.changed_frames("direct", "draft", -1, FrameChange::knobs_and_scene);
    ASSERT_EQ(kept.size(), 1u);
    EXPECT_DOUBLE_EQ(kept.front().measured_ms, built.stats.render_ms);
    other.reset();
    resources.reset();
}

// A camera moved across the sun redraws the view cascades and nothing else (no shadow map over the
// scene, none of the method's light work), and its frame says so (`view`), before and after: the
// planner prices such frames by the cascades, where before they passed for warm frames (direct
// ultra in the bench street: 613 ms, its warm frames 2.5). A camera moved along the sun, its far
// plane its own, fits the same cascades, and redoes nothing. A frame of another shape fits other
// cascades; a frame of the same shape at another size does not, and the planner asks at the size a
// plan renders at. A switch of preset from a moved camera redoes both. A light dimmed as the camera
// moved is predicted as a move of the lights and says it was a change of power. Another count of
// cascades alone redraws them as a moved camera does, and none drops them.
struct ViewWork {
    const char* method;
    const char* count;  // the method's statistic that counts the light work it redid; none for direct
};

class ViewChanges : public ::testing::TestWithParam<ViewWork> {};

TEST_P(ViewChanges, AMovedCameraRedrawsTheViewCascadesAlone) {
    const ViewWork work = GetParam();
    const std::string method = work.method;
    scene::Scene scene = sunlit_ground();
    Renderer& renderer = shared_renderer();
    auto resources = renderer.upload(scene);
    RenderRequest request = method_request(method, "draft", kSize);
    request.camera = scene.cameras.front();
    double counted = 0.0;
    const auto frame = [&](const RenderRequest& asked, FrameChange predicted, FrameChange said, const char* step) {
        SCOPED_TRACE(step);
        EXPECT_EQ(resources->change_for(asked.method, plan_frame(asked).knobs, resources->view_of(asked)), predicted);
        const RenderResult result = renderer.render(*resources, asked);
        EXPECT_EQ(result.stats.change, said);
        if (*work.count) {
            const double now = result.stats.method_statistics.at(work.count);
            const bool solved = said != FrameChange::none && said != FrameChange::view;
            EXPECT_EQ(now - counted, solved ? 1.0 : 0.0) << work.count;
            counted = now;
        }
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
    // The planner, for the camera as it is, at the size each plan renders at.
    const planning::PlanningInputs::ChangeOf change = planning::changes_on(*resources, *request.camera);
    EXPECT_EQ(change(method, "draft", {}, 2 * kSize, kSize), FrameChange::none);
    EXPECT_EQ(change(method, "draft", {}, kSize, kSize / 2), FrameChange::none);  // the same shape
    EXPECT_EQ(change(method, "draft", {}, kSize, kSize), FrameChange::view);
    EXPECT_EQ(change(method, "draft", {{"shadow_cascades", 0}}, 2 * kSize, kSize), FrameChange::none);
    frame(request, FrameChange::view, FrameChange::view, "the first shape again");
    // Another preset from a moved camera: the structures its knobs select, and the cascades where the
    // switch keeps the maps (maps of another size are all drawn anew).
    RenderRequest low = request;
    low.preset = "low";
    low.camera->position.x -= 0.5f;
    const bool keeps_maps = same_maps(plan_frame(request).knobs, plan_frame(low).knobs);
    if (method == "cssm" || method == "isr") ASSERT_TRUE(keeps_maps);  // their presets share 2048-texel maps
    const FrameChange switched = keeps_maps ? FrameChange::knobs_and_view : FrameChange::knobs;
    const RenderResult low_frame = frame(low, switched, switched, "another preset from a moved camera");
    EXPECT_TRUE(low_frame.stats.ran(keeps_maps ? "shadow_view_cascades" : "shadow_maps"));
    EXPECT_NE(low_frame.stats.ran("shadow_maps"), keeps_maps);
    request.camera = low.camera;
    frame(request, FrameChange::knobs, FrameChange::knobs, "the first preset again, the camera kept");
    // A light dimmed as the camera moved: the light's work and the cascades, no map over the scene.
    scene.lights.front().intensity *= 1.001f;
    request.camera->position.z += 1.0f;
    const RenderResult dimmed = frame(request, FrameChange::lights, FrameChange::light_power, "dimmed and moved");
    EXPECT_TRUE(dimmed.stats.ran("shadow_view_cascades"));
    EXPECT_FALSE(dimmed.stats.ran("shadow_maps"));
    // Another count of cascades: those drawn anew, and nothing else.
    RenderRequest fewer = request;
    fewer.knobs["shadow_cascades"] = 2;
    const RenderResult recascaded = frame(fewer, FrameChange::view, FrameChange::view, "two cascades");
    EXPECT_TRUE(recascaded.stats.ran("shadow_view_cascades"));
    EXPECT_FALSE(recascaded.stats.ran("shadow_maps"));
    // Without cascades (dropped, a warm frame's work) a moved camera redoes nothing.
    RenderRequest without = request;
    without.knobs["shadow_cascades"] = 0;
    const RenderResult turned_off = frame(without, FrameChange::none, FrameChange::none, "the cascades turned off");
    EXPECT_FALSE(turned_off.stats.ran("shadow_maps"));
    without.camera->position.z += 1.0f;
    frame(without, FrameChange::none, FrameChange::none, "the camera moved, no cascades");
    EXPECT_EQ(planning::changes_on(*resources, *without.camera)(method, "draft", {{"shadow_cascades", 0}}, kSize, kSize),
              FrameChange::none);
    EXPECT_EQ(planning::changes_on(*resources, *without.camera)(method, "draft", {}, kSize, kSize), FrameChange::view);
    // A bake then builds nothing that the cascades change: the next frame redraws them alone, and
    // solves no light.
    request.camera = without.camera;
    EXPECT_EQ(renderer.prepare(*resources, request, [](double, const std::string&) { return true; }).change,
              FrameChange::none);
    frame(request, FrameChange::view, FrameChange::view, "a frame after a bake with the cascades back");
    resources.reset();
}

INSTANTIATE_TEST_SUITE_P(Methods, ViewChanges,
                         ::testing::Values(ViewWork{"direct", ""}, ViewWork{"cssm", "light_updates"},
                                           ViewWork{"vct", "light_updates"}, ViewWork{"isr", "vpl_tree_builds"}),
                         [](const auto& info) { return std::string(info.param.method); });

// vct in its ambient-occlusion mode (`ao`) draws no shadow maps, so a moved camera redoes nothing,
// as predicted as it is said (it was predicted to redraw cascades it never draws); the frame of light
// after it draws every map, a switch of knobs.
TEST(ViewChanges, AmbientOcclusionRedrawsNoCascadesForAMovedCamera) {
    scene::Scene scene = sunlit_ground();
    Renderer& renderer = shared_renderer();
    auto resources = renderer.upload(scene);
    RenderRequest request = method_request("vct", "draft", kSize);
    request.camera = scene.cameras.front();
    request.knobs["ao"] = 1;
    EXPECT_FALSE(renderer.render(*resources, request).stats.ran("shadow_maps"));
    request.camera->position.x += 1.0f;
    EXPECT_EQ(resources->change_for("vct", plan_frame(request).knobs, resources->view_of(request)), FrameChange::none);
    const RenderResult moved = renderer.render(*resources, request);
    EXPECT_EQ(moved.stats.change, FrameChange::none);
    EXPECT_FALSE(moved.stats.ran("shadow_view_cascades"));
    // Light again: every map drawn, as predicted; then the same move redraws the cascades.
    request.knobs["ao"] = 0;
    EXPECT_EQ(resources->change_for("vct", plan_frame(request).knobs, resources->view_of(request)), FrameChange::knobs);
    const RenderResult lit = renderer.render(*resources, request);
    EXPECT_EQ(lit.stats.change, FrameChange::knobs);
    EXPECT_TRUE(lit.stats.ran("shadow_maps"));
    request.camera->position.x += 1.0f;
    EXPECT_EQ(resources->change_for("vct", plan_frame(request).knobs, resources->view_of(request)), FrameChange::view);
    resources.reset();
}

// A camera moved in the Cornell box redoes nothing: no light of it casts view cascades. With a sun
// added, the same move (the camera inside the box, where the cascades near it are finer than the
// sun's map over the box) redraws them.
TEST(ViewChanges, OnlyASunsCascadesMakeAMovedCameraRedoAnything) {
    scene::Scene scene = scene::make_cornell_box();
    ASSERT_TRUE(std::none_of(scene.lights.begin(), scene.lights.end(),
                             [](const scene::Light& light) { return light.type == scene::LightType::directional; }));
    const scene::Aabb box = scene.world_bounds();
    auto resources = shared_renderer().upload(scene);
    RenderRequest request = method_request("direct", "draft", kSize);
    request.camera = scene::Camera::look_at(box.center() + 0.3f * box.extent(), box.min, {0.0f, 1.0f, 0.0f}, 0.7f);
    const auto moved_frame = [&] {
        shared_renderer().render(*resources, request);
        request.camera->position.x -= 0.1f * box.extent().x;
        const FrameChange predicted = resources->change_for("direct", plan_frame(request).knobs, resources->view_of(request));
        EXPECT_EQ(shared_renderer().render(*resources, request).stats.change, predicted);
        return predicted;
    };
    EXPECT_EQ(resources->state_now(plan_frame(request).knobs, resources->view_of(request)).view, 0u);
    EXPECT_EQ(moved_frame(), FrameChange::none);
    scene.lights.push_back(directional_light(glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)), 1.0f));
    shared_renderer().render(*resources, request);  // the new light's maps
    EXPECT_NE(resources->state_now(plan_frame(request).knobs, resources->view_of(request)).view, 0u);
    EXPECT_EQ(moved_frame(), FrameChange::view);
    resources.reset();
}

// A file as a CAD exporter writes it (assimp's 2CylinderEngine: 65 rotated nodes, a sun added), seen
// from halfway to its centre, so that the cascades near the camera are finer than the sun's map over
// it: a camera moved across it is predicted and said to redraw the cascades, for every GPU method,
// and the frame after it from the same camera redoes nothing.
TEST(ViewChanges, AnExportedFilesMovedCameraRedrawsItsCascadesAsPredicted) {
    const scene::Scene file = sunlit_engine();
    auto resources = shared_renderer().upload(file);
    const scene::Aabb bounds = file.world_bounds();
    for (const char* method : {"direct", "cssm", "vct", "isr"}) {
        SCOPED_TRACE(method);
        RenderRequest request = method_request(method, "draft", kSize);
        scene::Camera camera = camera_for(file, request);
        camera.position += 0.5f * (bounds.center() - camera.position);
        request.camera = camera;
        shared_renderer().render(*resources, request);
        ASSERT_NE(resources->state_now(plan_frame(request).knobs, resources->view_of(request)).view, 0u);
        request.camera->position += 0.05f * glm::length(bounds.extent()) * (camera.orientation * glm::vec3(1, 0, 0));
        EXPECT_EQ(resources->change_for(method, plan_frame(request).knobs, resources->view_of(request)),
                  FrameChange::view);
        const RenderResult moved = shared_renderer().render(*resources, request);
        EXPECT_EQ(moved.stats.change, FrameChange::view);
        EXPECT_TRUE(moved.stats.ran("shadow_view_cascades"));
        EXPECT_EQ(shared_renderer().render(*resources, request).stats.change, FrameChange::none);
        // Other counts of cascades alone. The engine is small beside the camera's depth range: every
        // cascade reaches past it and is cut to the same window, so any count fits the same ones and
        // redoes nothing, as predicted (a switch of knobs, with every map, before such switches were
        // classed by what they draw). ViewChanges.AMovedCameraRedrawsTheViewCascadesAlone has a
        // count that fits others.
        const std::uint64_t fitted = resources->state_of(method)->view;
        for (const int cascades : {4, 2, 1}) {
            SCOPED_TRACE(cascades);
            request.knobs["shadow_cascades"] = cascades;
            EXPECT_EQ(resources->state_now(plan_frame(request).knobs, resources->view_of(request)).view, fitted);
            EXPECT_EQ(resources->change_for(method, plan_frame(request).knobs, resources->view_of(request)),
                      FrameChange::none);
            const RenderResult recascaded = shared_renderer().render(*resources, request);
            EXPECT_EQ(recascaded.stats.change, FrameChange::none);
            EXPECT_FALSE(recascaded.stats.ran("shadow_maps"));
            EXPECT_FALSE(recascaded.stats.ran("shadow_view_cascades"));
        }
    }
    resources.reset();
}

}  // namespace
}  // namespace bounce::test
