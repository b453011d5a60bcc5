// The EGL context, shader embedding and the display transform.
#include "gpu_fixture.hpp"
#include "renderer/base/error.hpp"
#include "renderer/gpu/shader_program.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace bounce::test {
namespace {

TEST(Context, IsOpenGl45CoreAndNamesItsRenderer) {
    const auto& info = shared_renderer().gpu_info();
    EXPECT_FALSE(info.renderer.empty());
    EXPECT_FALSE(info.vendor.empty());
    GLint major = 0, minor = 0, profile = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    EXPECT_GE(major * 10 + minor, 45);
    EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
    EXPECT_GE(info.devices_found.size(), 1u);
    EXPECT_NE(info.summary().find(info.renderer), std::string::npos);
}

TEST(Context, DeviceChoiceParsing) {
    EXPECT_EQ(gpu::DeviceChoice::parse("auto").kind, gpu::DeviceChoice::Kind::automatic);
    EXPECT_EQ(gpu::DeviceChoice::parse("software").kind, gpu::DeviceChoice::Kind::software);
    EXPECT_EQ(gpu::DeviceChoice::parse("hardware").kind, gpu::DeviceChoice::Kind::hardware);
    EXPECT_EQ(gpu::DeviceChoice::parse("3").index, 3);
    EXPECT_THROW(gpu::DeviceChoice::parse("gpu0"), InputError);
    EXPECT_THROW(gpu::DeviceChoice::parse("-1"), InputError);
}

TEST(Context, OutOfRangeDeviceIndexNamesWhatWasFound) {
    try {
        gpu::EglContext::create(gpu::DeviceChoice::parse("99"));
        FAIL() << "device 99 should not exist";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("out of range: found [0]"), std::string::npos) << error.what();
    }
    shared_renderer();  // the shared context is still usable afterwards
}

// --device hardware takes a real GPU or refuses to start, naming what it found: a GPU node whose
// driver libraries are missing must not serve from the software rasterizer unnoticed.
TEST(Context, HardwareDeviceIsAGpuOrARefusalNamingWhatWasFound) {
    const auto& found = shared_renderer().gpu_info().devices_found;
    const bool any_hardware = std::any_of(found.begin(), found.end(), [](const auto& d) { return !d.software; });
    if (any_hardware) {
        EXPECT_FALSE(gpu::EglContext::create(gpu::DeviceChoice::parse("hardware"))->info().software);
    } else {
        try {
            gpu::EglContext::create(gpu::DeviceChoice::parse("hardware"));
            FAIL() << "no hardware device here, yet --device hardware made a context";
        } catch (const Error& error) {
            EXPECT_NE(std::string(error.what()).find("no hardware EGL device"), std::string::npos) << error.what();
            EXPECT_NE(std::string(error.what()).find("found [0] software"), std::string::npos) << error.what();
        }
    }
    shared_renderer();  // the shared context is still usable afterwards
}

// EGL gives every context on a device one display. A second context made and dropped on the render
// thread (as the hardware check above does where there is a GPU) must neither terminate that display
// nor leave the thread without the shared context: the same frame renders before and after, to the
// pixel (rasterizing one request on one context is deterministic).
TEST(Context, AnotherContextOnTheSameDeviceComesAndGoesWithoutHarmingTheFirst) {
    const scene::Scene scene = scene::make_cornell_box();
    const RenderRequest request = method_request("direct", "draft", 32);
    const RenderResult before = render_scene(scene, request);
    {
        const auto other = gpu::EglContext::create(gpu::DeviceChoice::resolve(std::nullopt));
        EXPECT_EQ(other->info().renderer, shared_renderer().gpu_info().renderer);
    }
    const auto resources = shared_renderer().upload(scene);  // GL work right after the other context went
    {
        const auto another = gpu::EglContext::create(gpu::DeviceChoice::resolve(std::nullopt));
    }
    const RenderResult after = shared_renderer().render(*resources, request);
    ASSERT_EQ(after.frame.rgba.size(), before.frame.rgba.size());
    EXPECT_EQ(after.frame.rgba, before.frame.rgba);
}

TEST(Shaders, IncludesExpandOnceWithLineDirectives) {
    const auto source = gpu::expand_shader_source("passes/direct_light.frag", {"EXAMPLE 1"});
    EXPECT_EQ(source.text.rfind("#version 450 core\n#define EXAMPLE 1\n", 0), 0u);
    // math.glsl is included by brdf.glsl and lights.glsl and the pass itself, but expanded once.
    std::size_t count = 0;
    for (const auto& file : source.files) count += file == "common/math.glsl";
    EXPECT_EQ(count, 1u);
    EXPECT_EQ(source.files.front(), "passes/direct_light.frag");
}

TEST(Shaders, CompileErrorsNameFileAndLine) {
    const std::vector<std::string> files = {"passes/x.frag", "common/brdf.glsl"};
    const std::string annotated = gpu::annotate_info_log("1:12(3): error: syntax error\n0(7) : error C0000: x\n", files);
    EXPECT_NE(annotated.find("common/brdf.glsl:12(3): error: syntax error"), std::string::npos) << annotated;
    EXPECT_NE(annotated.find("passes/x.frag:7 : error C0000"), std::string::npos) << annotated;
    EXPECT_THROW(gpu::expand_shader_source("passes/missing.frag", {}), Error);
}

// sRGB encoding of the display transform: with the 'none' curve, 8-bit output is the sRGB
// encoding of radiance * 2^exposure (rounded), which we can compute exactly.
TEST(Tonemap, NoneCurveIsExposureThenSrgb) {
    scene::Scene scene;
    scene::Material glow;
    glow.base_color = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    glow.metallic = 0.0f;
    glow.specular = 0.0f;
    glow.emissive = {0.05f, 0.2f, 0.9f};
    scene.materials.push_back(glow);
    add_square(scene, "glow", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    RenderRequest request;
    request.width = request.height = 8;
    request.camera = top_down_camera(1.0f, 1.0f);
    request.display = {1.0f, image::ToneCurve::none};  // x2
    const auto result = render_scene(scene, request);
    auto srgb = [](float c) {
        c = std::clamp(c, 0.0f, 1.0f);
        const float encoded = c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
        return encoded * 255.0f;
    };
    const auto pixel = result.frame.display_at(4, 4);
    EXPECT_NEAR(pixel.r, srgb(0.1f), 0.51f);
    EXPECT_NEAR(pixel.g, srgb(0.4f), 0.51f);
    EXPECT_EQ(pixel.b, 255);  // 1.8 clips
    EXPECT_EQ(pixel.a, 255);

    // ACES and Reinhard are monotonic and map 0 to 0 and large values near white.
    request.display = {0.0f, image::ToneCurve::reinhard};
    const auto reinhard = render_scene(scene, request);
    EXPECT_NEAR(reinhard.frame.display_at(4, 4).b, srgb(0.9f / 1.9f), 0.51f);
}

// The CPU twin of the tone-map pass (image::make_display_image, used for frames made on CPU
// threads) against the GPU pass, on the direct light of the Cornell box (radiance from black to the
// lamp, spread over the curves' range by the exposures). Both compute the same float32 function;
// only the last bits of pow() and of the float-to-unorm rounding may differ, so a channel may
// differ by one 8-bit step where a value sits on a rounding boundary, never more.
TEST(Tonemap, CpuTwinMatchesTheGpuPassWithinOneStep) {
    const scene::Scene cornell = scene::make_cornell_box();
    for (const auto curve : {image::ToneCurve::none, image::ToneCurve::reinhard, image::ToneCurve::aces}) {
        for (const float exposure : {-6.0f, -2.0f, 0.0f, 2.0f, 6.0f}) {
            RenderRequest request = method_request("direct", "draft", 32);
            request.display = {exposure, curve};
            const RenderResult gpu = render_scene(cornell, request);
            image::Frame cpu = gpu.frame;
            cpu.display_rgba8.clear();
            image::make_display_image(cpu, request.display);
            ASSERT_EQ(cpu.display_rgba8.size(), gpu.frame.display_rgba8.size());
            int worst = 0;
            std::size_t differing = 0;
            for (std::size_t i = 0; i < cpu.display_rgba8.size(); ++i) {
                const int difference = std::abs(int(cpu.display_rgba8[i]) - int(gpu.frame.display_rgba8[i]));
                worst = std::max(worst, difference);
                differing += difference != 0;
            }
            EXPECT_LE(worst, 1) << "curve " << image::tone_curve_name(curve) << ", exposure " << exposure;
            // Boundary cases are rare: at most 1% of the channels.
            EXPECT_LE(differing, cpu.display_rgba8.size() / 100)
                << "curve " << image::tone_curve_name(curve) << ", exposure " << exposure;
        }
    }
}

}  // namespace
}  // namespace bounce::test
