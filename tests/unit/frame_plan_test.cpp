// plan_frame, the one place that decides where a request runs, and CPU frames end to end: the
// reference through the CPU method interface, its CPU tone map, and cancellation.
#include "renderer/base/error.hpp"
#include "renderer/image/tone.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

namespace bounce {
namespace {

RenderRequest request_for(const std::string& method, int size) {
    RenderRequest request;
    request.method = method;
    request.preset = "draft";
    request.width = request.height = size;
    return request;
}

TEST(FramePlan, GpuMethodsRunOnTheRenderThreadAndTheReferenceOnCpuThreads) {
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        EXPECT_EQ(plan_frame(request_for(method, 8)).site, FrameSite::gpu) << method;
    }
    const FramePlan reference = plan_frame(request_for("reference", 8));
    EXPECT_EQ(reference.site, FrameSite::cpu);
    EXPECT_EQ(reference.knobs.at("spp"), 4.0);  // the draft preset, resolved
}

TEST(FramePlan, RefusesWhatCannotRunNamingTheFault) {
    auto message_of = [](const RenderRequest& request) {
        try {
            plan_frame(request);
        } catch (const InputError& error) {
            return std::string(error.what());
        }
        return std::string("(no error)");
    };
    EXPECT_NE(message_of(request_for("photon", 8)).find("unknown method 'photon'"), std::string::npos);
    RenderRequest request = request_for("reference", 8);
    request.knobs["spp"] = 0;
    EXPECT_NE(message_of(request).find("spp"), std::string::npos);
    request = request_for("direct", 0);
    EXPECT_NE(message_of(request).find("frame size 0x0"), std::string::npos);
    request = request_for("direct", Renderer::kMaxDimension + 1);
    EXPECT_NE(message_of(request).find("outside 1.."), std::string::npos);
}

TEST(CpuFrames, ReferenceRendersAndToneMapsOnTheCallingThread) {
    const scene::Scene cornell = scene::make_cornell_box();
    RenderRequest request = request_for("reference", 12);
    request.knobs = {{"spp", 2}, {"bounces", 1}};
    request.display = {1.0f, image::ToneCurve::reinhard};
    const RenderResult result = render_on_cpu(cornell, request, plan_frame(request));
    ASSERT_EQ(result.frame.width, 12);
    ASSERT_EQ(result.frame.rgba.size(), 12u * 12u * 4u);
    EXPECT_EQ(result.frame.non_finite_count(), 0u);
    EXPECT_EQ(result.stats.method, "reference");
    EXPECT_EQ(result.stats.knobs.at("spp"), 2.0);
    EXPECT_GT(result.stats.method_statistics.at("rays_traced"), 0.0);
    // The display image is the CPU tone map of the linear frame, nothing else.
    image::Frame again = result.frame;
    again.display_rgba8.clear();
    image::make_display_image(again, request.display);
    EXPECT_EQ(again.display_rgba8, result.frame.display_rgba8);
}

TEST(CpuFrames, ACancelledFrameStopsWithCancelled) {
    const scene::Scene cornell = scene::make_cornell_box();
    RenderRequest request = request_for("reference", 64);
    request.knobs = {{"spp", 65536}};  // hours of work, were it not cancelled
    const std::atomic<bool> cancelled{true};
    EXPECT_THROW(render_on_cpu(cornell, request, plan_frame(request), &cancelled), Cancelled);
}

TEST(CpuFrames, GpuPlansAreNotRenderedOnCpuThreads) {
    const scene::Scene cornell = scene::make_cornell_box();
    const RenderRequest request = request_for("direct", 8);
    EXPECT_THROW(render_on_cpu(cornell, request, plan_frame(request)), Error);
}

// The CPU tone map at values known in closed form: sRGB(x) = 1.055 x^(1/2.4) - 0.055 above
// 0.0031308, 12.92 x below; non-finite radiance is black; alpha is opaque.
TEST(CpuToneMap, MatchesTheDisplayTransformAtKnownValues) {
    image::Frame frame;
    frame.width = 4;
    frame.height = 1;
    const float nan = std::nanf("");
    frame.rgba = {0.0f, 0.001f, 0.25f, 1.0f,  0.5f, 2.0f, 100.0f, 1.0f,
                  nan, INFINITY, -1.0f, 1.0f,  0.25f, 0.25f, 0.25f, 1.0f};
    image::make_display_image(frame, {0.0f, image::ToneCurve::none});
    auto srgb8 = [](float x) {
        const float encoded = x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
        return static_cast<int>(std::lround(encoded * 255.0f));
    };
    EXPECT_EQ(frame.display_rgba8[0], 0);
    EXPECT_EQ(frame.display_rgba8[1], srgb8(0.001f));
    EXPECT_EQ(frame.display_rgba8[2], srgb8(0.25f));
    EXPECT_EQ(frame.display_rgba8[3], 255);
    EXPECT_EQ(frame.display_rgba8[4], srgb8(0.5f));
    EXPECT_EQ(frame.display_rgba8[5], 255);  // clipped
    EXPECT_EQ(frame.display_rgba8[8], 0);    // NaN
    EXPECT_EQ(frame.display_rgba8[9], 0);    // infinity: not finite, so black, as the GPU pass does
    EXPECT_EQ(frame.display_rgba8[10], 0);   // negative
    // Exposure +1 and Reinhard: 0.25 * 2 -> 0.5 / 1.5.
    image::make_display_image(frame, {1.0f, image::ToneCurve::reinhard});
    EXPECT_EQ(frame.display_rgba8[12], srgb8(0.5f / 1.5f));
}

}  // namespace
}  // namespace bounce
