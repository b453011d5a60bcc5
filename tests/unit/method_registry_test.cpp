#include "renderer/base/error.hpp"
#include "renderer/memory_admission.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

namespace bounce::methods {
namespace {

std::string message_of(const std::function<void()>& action) {
    try {
        action();
    } catch (const InputError& error) {
        return error.what();
    }
    return "(no error)";
}

TEST(MethodRegistry, PresetsResolveAndOverridesApply) {
    const auto& registry = MethodRegistry::builtin();
    EXPECT_EQ(registry.resolve("direct", "draft", {}).at("shadow_map_size"), 256.0);
    EXPECT_EQ(registry.resolve("direct", "ultra", {}).at("shadow_map_size"), 4096.0);
    EXPECT_EQ(registry.resolve("direct", "low", {{"shadow_map_size", 300}}).at("shadow_map_size"), 300.0);
}

TEST(MethodRegistry, FailsLoudlyNamingTheFault) {
    const auto& registry = MethodRegistry::builtin();
    EXPECT_NE(message_of([&] { registry.find("photon"); }).find("unknown method 'photon' (known: direct, vct, isr, cssm, reference)"),
              std::string::npos);
    EXPECT_NE(message_of([&] { registry.resolve("direct", "insane", {}); }).find("unknown preset 'insane'"),
              std::string::npos);
    EXPECT_NE(message_of([&] { registry.resolve("direct", "low", {{"bounces", 2}}); })
                  .find("unknown knob 'bounces' for method 'direct' (knobs: shadow_map_size, shadow_cascades)"),
              std::string::npos);
    EXPECT_NE(message_of([&] { registry.resolve("direct", "low", {{"shadow_map_size", 1e9}}); }).find("outside"),
              std::string::npos);
    EXPECT_NE(message_of([&] { registry.resolve("direct", "low", {{"shadow_map_size", 100.5}}); }).find("integer"),
              std::string::npos);
    EXPECT_NE(message_of([&] { registry.resolve("direct", "low", {{"shadow_map_size", std::nan("")}}); }).find("outside"),
              std::string::npos);
    // isr's hole filling of its maps: the levels 0 to 2, whole, and every preset's 2.
    for (const double dilation : {-1.0, 3.0, std::nan("")}) {
        EXPECT_NE(message_of([&] { registry.resolve("isr", "low", {{"ism_dilation", dilation}}); }).find("outside"),
                  std::string::npos)
            << dilation;
    }
    EXPECT_NE(message_of([&] { registry.resolve("isr", "low", {{"ism_dilation", 1.5}}); }).find("integer"), std::string::npos);
    for (const std::string preset : {"draft", "low", "medium", "high", "ultra"}) {
        EXPECT_EQ(registry.resolve("isr", preset, {}).at("ism_dilation"), 2.0) << preset;
    }
    EXPECT_EQ(registry.resolve("isr", "low", {{"ism_dilation", 0}}).at("ism_dilation"), 0.0);
    // The share of occluded indirect light below which the scene turns it off: a share, 0 to 1.
    for (const double share : {-0.1, 1.5, std::nan("")}) {
        EXPECT_NE(message_of([&] { registry.resolve("isr", "low", {{"ism_open_below", share}}); }).find("outside"),
                  std::string::npos)
            << share;
    }
    EXPECT_EQ(registry.resolve("isr", "draft", {}).at("ism_open_below"), 0.0);  // no maps to dilate
    for (const std::string preset : {"low", "medium", "high", "ultra"}) {
        const double share = registry.resolve("isr", preset, {}).at("ism_open_below");
        EXPECT_GT(share, 0.0) << preset;
        EXPECT_LT(share, 0.5) << preset;  // under IndirectVisibility::kMostlyOccluded, where isr draft is ruled out
    }
}

TEST(MethodRegistry, ReferenceIsACpuMethodWithValidatedKnobs) {
    const auto& registry = MethodRegistry::builtin();
    EXPECT_EQ(registry.find("reference").device, MethodDevice::cpu);
    EXPECT_EQ(registry.resolve("reference", "ultra", {}).at("spp"), 1024.0);
    EXPECT_EQ(registry.resolve("reference", "draft", {{"bounces", 0}}).at("bounces"), 0.0);
    EXPECT_THROW(registry.resolve("reference", "draft", {{"spp", 0}}), InputError);
    EXPECT_THROW(registry.create("reference"), Error);  // not a GL method
    EXPECT_EQ(registry.create_cpu("reference")->name(), "reference");
    EXPECT_THROW(registry.create_cpu("direct"), Error);  // not a CPU method
}

// What isr tells the planner of its indirect visibility is what its frames hold: a frame is said to
// model it exactly where its memory estimate has the imperfect shadow maps, at every preset, mode
// and map size. Every other method models it in every frame (or has no indirect light).
TEST(MethodRegistry, IsrSaysItModelsIndirectVisibilityWhereItsFramesMakeTheMaps) {
    const auto& registry = MethodRegistry::builtin();
    const scene::Scene scene = scene::make_cornell_box();
    const MethodInfo& isr = registry.find("isr");
    ASSERT_TRUE(isr.unmodelled_indirect_visibility);
    int modelled = 0, unmodelled = 0;
    for (const auto& preset : preset_names()) {
        for (const double mode : {0.0, 1.0, 2.0}) {
            for (const double ism_size : {0.0, 16.0, 64.0}) {
                const KnobValues knobs = registry.resolve("isr", preset, {{"mode", mode}, {"ism_size", ism_size}});
                bool maps = false;
                for (const auto& structure : frame_estimate(isr, {scene, knobs, 32, 32})) {
                    maps = maps || structure.name == "imperfect_shadow_maps";
                }
                const std::string reason = isr.unmodelled_indirect_visibility(knobs);
                EXPECT_EQ(reason.empty(), maps) << preset << " mode " << mode << " ism_size " << ism_size << ": "
                                                << reason;
                ++(maps ? modelled : unmodelled);
            }
        }
    }
    EXPECT_EQ(modelled, 5 * 2);  // mode 2 with maps of 16 or 64 texels
    EXPECT_EQ(unmodelled, 5 * 7);
    for (const char* method : {"direct", "vct", "cssm", "reference"}) {
        EXPECT_FALSE(registry.find(method).unmodelled_indirect_visibility) << method;
    }
}

// The scene analysis sizes vct's thin walls by the method's own word: its leaf voxels, the scene's
// extent over `resolution` (docs/methods.md, "vct"). No other method has voxels.
TEST(MethodRegistry, VctSaysHowLargeItsVoxelsAre) {
    const auto& registry = MethodRegistry::builtin();
    const MethodInfo& vct = registry.find("vct");
    ASSERT_TRUE(vct.voxel_size);
    for (const auto& preset : preset_names()) {
        const KnobValues knobs = registry.resolve("vct", preset, {});
        EXPECT_DOUBLE_EQ(vct.voxel_size(knobs, 12.0), 12.0 / knobs.at("resolution")) << preset;
    }
    EXPECT_DOUBLE_EQ(vct.voxel_size(registry.resolve("vct", "low", {{"resolution", 100}}), 5.0), 0.05);
    for (const char* method : {"direct", "isr", "cssm", "reference"}) {
        EXPECT_FALSE(registry.find(method).voxel_size) << method;
    }
}

TEST(MethodRegistry, IncompleteMethodsAreRejected) {
    MethodRegistry registry;
    MethodInfo info;
    info.name = "half";
    info.knobs = {{"k", 0, 1, false, ""}};
    info.presets = {{"draft", {{"k", 0.5}}}};
    info.create = [] { return std::unique_ptr<Method>(); };
    EXPECT_THROW(registry.add(info), Error);
}

}  // namespace
}  // namespace bounce::methods
