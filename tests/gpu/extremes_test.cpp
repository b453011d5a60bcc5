// Material extremes on the Cornell box: where a GI method cannot model an effect it must leave it
// out, not add a wrong one, so no GI method's error against the reference may exceed `direct`'s
// (which leaves all indirect light out). Every frame is finite. The cases are the ones that broke
// cssm's final gather: every surface at roughness 0 (glTF's default specular), and the white
// surfaces a mirror metal. Errors are relMSE against the path-traced reference through pixel
// centres (512 spp, 4 bounces); its noise adds alike to every method's error, so the comparison
// with `direct` is fair at any sample count.
#include "gpu_fixture.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <string>

namespace bounce::test {
namespace {

constexpr int kSize = 48;

struct MaterialCase {
    std::string name;
    std::function<void(scene::Material&)> edit;
};

void check_no_method_worse_than_direct(const MaterialCase& extreme) {
    scene::Scene scene = scene::make_cornell_box();
    for (scene::Material& material : scene.materials) extreme.edit(material);
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = 4;
    const image::Frame truth = pixel_centre_reference(scene, kSize, 512, settings);
    const auto error_of = [&](const std::string& method) {
        const RenderResult result = render_scene(scene, method_request(method, "high", kSize));
        EXPECT_EQ(result.frame.non_finite_count(), 0u) << extreme.name << ": " << method;
        const image::ErrorMetrics error = image::compare(result.frame, truth);
        std::printf("%s: %-6s relMSE %.4f, mean %.4f (reference %.4f)\n", extreme.name.c_str(), method.c_str(),
                    error.rel_mse, error.mean_test, error.mean_reference);
        return error.rel_mse;
    };
    const double direct = error_of("direct");
    for (const std::string method : {"vct", "isr", "cssm"}) {
        EXPECT_LE(error_of(method), direct) << extreme.name << ": " << method << " is worse than direct light alone";
    }
}

TEST(MaterialExtremes, NoGiMethodIsWorseThanDirectWhenEverySurfaceIsSmooth) {
    check_no_method_worse_than_direct({"roughness 0", [](scene::Material& m) {
                                           m.roughness = 0.0f;
                                           m.specular = 1.0f;
                                       }});
}

TEST(MaterialExtremes, NoGiMethodIsWorseThanDirectWhenTheWhiteSurfacesAreMirrors) {
    check_no_method_worse_than_direct({"mirror metal", [](scene::Material& m) {
                                           if (m.name != "white") return;
                                           m.metallic = 1.0f;
                                           m.roughness = 0.0f;
                                           m.base_color = glm::vec4(1.0f);
                                       }});
}

}  // namespace
}  // namespace bounce::test
