// Tools for shader faults a driver may hide: the bounds-checked build (renderer/gpu/bounds_check.hpp)
// and float additions from many threads (common/float_atomics.glsl), both ways the device may run them.
#include "gpu_fixture.hpp"
#include "vct_flag_pass.hpp"
#include "renderer/gpu/bounds_check.hpp"
#include "renderer/gpu/shader_program.hpp"
#include "renderer/passes/light_geometry.hpp"

#include "common/shared_layout.h"
#include "vct/vct_layout.h"

#include <gtest/gtest.h>

#include <glm/gtc/packing.hpp>

#include <cstdio>
#include <cstring>
#include <regex>
#include <sstream>

namespace bounce::test {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The site number a rewritten access passes to bounce_checked, from the rewritten text after `from`.
unsigned site_after(const std::string& text, const std::string& from) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    const std::size_t end = text.find("u)]", at);
    const std::size_t start = text.rfind(' ', end) + 1;
    return static_cast<unsigned>(std::stoul(text.substr(start, end - start)));
}

TEST(Shaders, BoundsCheckRewritesEveryIndexIntoADeclaredArrayAndNothingElse) {
    const gpu::ExpandedSource source{
        "#version 450 core\n"
        "#extension GL_NV_shader_atomic_float : enable\n"
        "#line 2 0\n"
        "layout(std430, binding = 1) buffer Items { uint items[]; };\n"
        "uniform vec4 u_cones[4];\n"
        "#define ADD(array, i) atomicAdd(array[i], 1u)\n"
        "// items[comment] is not code\n"
        "void main() {\n"
        "    uint stack[8];\n"
        "    vec3 v = vec3(1.0);\n"
        "    stack[0] = items[items[1] + uint(u_cones[2].x)];\n"
        "    v[1] = 2.0;\n"
        "    ADD(items, 3u);\n"
        "}\n",
        {"test.comp"}};
    const std::string text = gpu::insert_bounds_checks(source, 7).text;
    // The checker comes after #version and #extension, both of which must precede any code.
    EXPECT_EQ(text.rfind("#version 450 core\n#extension GL_NV_shader_atomic_float : enable\nlayout(std430, binding = 7)", 0),
              0u)
        << text;
    EXPECT_TRUE(contains(text, "uint items[]; }"));  // declarations stay
    EXPECT_TRUE(contains(text, "uint stack[8];"));
    EXPECT_TRUE(contains(text, "uniform vec4 u_cones[4];"));
    EXPECT_TRUE(contains(text, "// items[comment] is not code"));
    EXPECT_TRUE(contains(text, "    v[1] = 2.0;"));  // a vector is not an array
    // Nested accesses are checked inside the outer index.
    EXPECT_TRUE(contains(text, "stack[bounce_checked(uint(0), uint(stack.length()), "));
    EXPECT_TRUE(contains(text, "items[bounce_checked(uint(items[bounce_checked(uint(1), uint(items.length()), "));
    EXPECT_TRUE(contains(text, "u_cones[bounce_checked(uint(2), uint(u_cones.length()), "));
    // A macro's array parameter is checked where the macro indexes it.
    EXPECT_TRUE(contains(text, "atomicAdd(array[bounce_checked(uint(i), uint(array.length()), "));
    // Sites name the file, the line the #line directives give, and the expression.
    EXPECT_EQ(gpu::bounds_check_site(site_after(text, "stack[bounce_checked(uint(0)")), "test.comp:9: stack[0]");
    EXPECT_EQ(gpu::bounds_check_site(site_after(text, "u_cones[bounce_checked")), "test.comp:9: u_cones[2]");
    EXPECT_EQ(gpu::bounds_check_site(site_after(text, "array[bounce_checked")), "test.comp:4: array[i]");

    // A shader that indexes no array is left as it was.
    const gpu::ExpandedSource plain{"#version 450 core\nvoid main() { gl_Position = vec4(0.0); }\n", {"plain.vert"}};
    EXPECT_EQ(gpu::insert_bounds_checks(plain, 7).text, plain.text);
}

// GLSL wants #extension before any code: one an included file asks for (vct/leaf_data.glsl's float
// atomics) moves up to just after #version, once, and its own line is left empty.
TEST(Shaders, ExtensionsFromIncludedFilesComeRightAfterVersion) {
    const auto source = gpu::expand_shader_source("vct/inject.comp", {"DENSE"});
    EXPECT_EQ(source.text.rfind("#version 450 core\n#extension GL_NV_shader_atomic_float : enable\n#define DENSE\n", 0), 0u)
        << source.text.substr(0, 200);
    std::size_t count = 0;
    for (std::size_t at = source.text.find("#extension"); at != std::string::npos; at = source.text.find("#extension", at + 1)) {
        ++count;
    }
    EXPECT_EQ(count, 1u);
}

// Whether a photon or VPL carries flux is asked component by component (common/math.glsl's
// any_positive): NVIDIA's driver 580.159 on an H200 evaluated max(x, max(y, z)) > 0.0 as false for
// positive values under about 3e-8, so dim lights lost every photon (Stability.ZeroAndHugeIntensity...
// failed there; a compute shader comparing the two forms on the same values showed it). No shader
// may compare a maximum of components with zero again.
TEST(Shaders, NoShaderComparesAMaximumOfComponentsWithZero) {
    static const std::regex pattern(R"((max|max_component)\s*\(.*\)\s*(>|<=)\s*0\.0\b)");
    std::size_t files = 0;
    for (const auto& [path, text] : gpu::embedded_shader_files()) {
        ++files;
        if (path.rfind("checks/", 0) == 0) continue;  // self-checks that write the form on purpose
        std::istringstream lines{std::string(text)};
        std::string line;
        for (int number = 1; std::getline(lines, line); ++number) {
            const std::string code = line.substr(0, line.find("//"));  // comments may name the pattern
            EXPECT_FALSE(std::regex_search(code, pattern)) << path << ":" << number << ": " << line;
        }
    }
    EXPECT_GT(files, 40u);
    EXPECT_TRUE(std::regex_search(std::string("if (!(max(flux.r, max(flux.g, flux.b)) > 0.0)) return;"), pattern));
    EXPECT_TRUE(std::regex_search(std::string("bool lit = max_component(flux) > 0.0;"), pattern));
    EXPECT_FALSE(std::regex_search(std::string("if (!any_positive(flux)) return;"), pattern));
}

// The photons of a light-view map, a 16x16 patch of floor under the Cornell box's point light, their
// flux (about 3e-5 W at full intensity) scaled down to 1e-6 of it: every one carries flux, so
// any_positive must say so of all of them, at every intensity, on every device, and of none where the
// light has no power. The form the H200's driver miscompiled is asked beside it and only reported
// (llvmpipe keeps every photon either way; that driver kept 16 of 256 at 1e-3 and none below).
TEST(Shaders, EveryPhotonOfADimLightCarriesFlux) {
    shared_renderer();
    constexpr int kSide = 16;
    std::vector<glm::vec4> positions;
    for (int y = 0; y < kSide; ++y) {
        for (int x = 0; x < kSide; ++x) positions.push_back({(x - 7.5f) * 0.1f, 0.0f, (y - 7.5f) * 0.1f, 1.0f});
    }
    const gpu::Buffer position_buffer = gpu::storage_of(positions);
    gpu::ShaderCache shaders;
    const gpu::ShaderProgram& program = shaders.get(gpu::ProgramSource::compute_shader("checks/photon_flux_verdicts.comp"));
    scene::Light light;
    light.type = scene::LightType::point;
    light.position = {0.0f, 1.9f, 0.0f};
    for (const float intensity : {0.5f, 0.5e-3f, 0.5e-4f, 0.5e-6f, 0.0f}) {
        light.intensity = intensity;
        const gpu::Buffer verdicts = gpu::storage_of(std::vector<std::uint32_t>(2 * positions.size(), 7u));
        gpu::bind_storage(0, position_buffer);
        gpu::bind_storage(1, verdicts);
        program.use();
        program.set("u_count", static_cast<unsigned>(positions.size()));
        program.set("u_view_forward", glm::vec3(0.0f, -1.0f, 0.0f));
        program.set("u_texel_measure", 6.1e-5f);  // a 256^2 cube face's texel on its axis
        passes::set_light_uniforms(program, light);
        program.dispatch_threads(positions.size());
        gpu::storage_barrier();
        std::vector<std::uint32_t> result(2 * positions.size());
        glGetNamedBufferSubData(verdicts.id(), 0, static_cast<GLsizeiptr>(result.size() * 4), result.data());
        std::size_t carried = 0, by_max = 0;
        for (std::size_t i = 0; i < positions.size(); ++i) {
            carried += result[2 * i] == 1u;
            by_max += result[2 * i + 1] == 1u;
        }
        std::printf("intensity %g W/sr: any_positive keeps %zu of %zu photons, max(...) > 0.0 %zu\n", intensity, carried,
                    positions.size(), by_max);
        EXPECT_EQ(carried, intensity > 0.0f ? positions.size() : 0u) << "intensity " << intensity;
    }
}

// flag_nodes.comp reads fragment `index` for every thread below u_fragment_count: told of two
// fragments where the buffer holds one, the second thread reads past the end.
TEST(Shaders, BoundsCheckedProgramsReportTheFirstOutOfBoundsAccess) {
    shared_renderer();  // its context is current
    gpu::ShaderCache shaders;
    const gpu::ShaderProgram& flag =
        shaders.get(gpu::ProgramSource::compute_shader("vct/flag_nodes.comp", {gpu::kBoundsCheckDefine}));
    gpu::BoundsCheckBuffer checks(BOUNCE_BINDING_BOUNDS_CHECK);
    checks.bind();
    const FlagPassBuffers buffers({0u}, std::vector<std::uint32_t>(VCT_FRAGMENT_WORDS, 0u));
    dispatch_flag_pass(flag, 0u, 1u, 1u);
    EXPECT_FALSE(checks.take().has_value()) << "one fragment in a buffer of one";

    dispatch_flag_pass(flag, 0u, 1u, 2u);
    const auto violation = checks.take();
    ASSERT_TRUE(violation.has_value());
    EXPECT_EQ(violation->count, 1u);
    EXPECT_EQ(violation->index, VCT_FRAGMENT_WORDS);
    EXPECT_EQ(violation->length, VCT_FRAGMENT_WORDS);
    EXPECT_TRUE(contains(violation->site, "vct/flag_nodes.comp:18: fragments[index * VCT_FRAGMENT_WORDS]")) << violation->site;
    EXPECT_TRUE(contains(violation->describe(), "read index 7 of an array of 7")) << violation->describe();
    EXPECT_FALSE(checks.take().has_value()) << "taking a violation clears the record";
}

// 20000 voxel fragments on one lattice point, summed by vct's leaf accumulation into one slot. Every
// term is a multiple of 1/4 and every partial sum under 2^24 / 4, so floats add them exactly in any
// order: both the hardware atomic and the compare-and-swap loop must give the exact sums.
TEST(FloatAtomics, ThousandsOfThreadsAddingToOneWordSumExactlyEitherWay) {
    shared_renderer();
    constexpr std::uint32_t kFragments = 20000;
    constexpr float kArea = 0.25f, kEmission = 2.0f;
    std::vector<std::uint32_t> words;
    for (std::uint32_t i = 0; i < kFragments; ++i) {
        const std::uint32_t lattice = 1u | (1u << 10) | (1u << 20);
        std::uint32_t emission = 0, area = 0;
        std::memcpy(&emission, &kEmission, 4);
        std::memcpy(&area, &kArea, 4);
        words.insert(words.end(), {lattice, glm::packUnorm4x8(glm::vec4(1.0f)), glm::packSnorm4x8(glm::vec4(0, 0, 1, 0)),
                                   emission, emission, emission, area});
    }
    const gpu::Buffer fragments = gpu::storage_of(words);
    constexpr unsigned kSide = 4;  // dense lattice: 64 slots
    for (const bool compare_and_swap : {false, true}) {
        SCOPED_TRACE(compare_and_swap ? "compare-and-swap" : "the device's float atomics where it has them");
        std::vector<std::string> defines = {"DENSE"};
        if (compare_and_swap) defines.push_back("FLOAT_ADD_BY_COMPARE_AND_SWAP");
        gpu::ShaderCache shaders;
        const gpu::ShaderProgram& accumulate =
            shaders.get(gpu::ProgramSource::compute_shader("vct/accumulate_leaves.comp", defines));
        const gpu::Buffer sums = gpu::storage_of(std::vector<float>(kSide * kSide * kSide * VCT_LEAF_SUM_WORDS, 0.0f));
        gpu::bind_storage(VCT_BINDING_FRAGMENTS, fragments);
        gpu::bind_storage(VCT_BINDING_LEAF_SUMS, sums);
        accumulate.set("u_fragment_count", kFragments);
        accumulate.set("u_dense_side", kSide);
        accumulate.dispatch_threads(kFragments);
        gpu::storage_barrier();
        std::vector<float> result(kSide * kSide * kSide * VCT_LEAF_SUM_WORDS);
        glGetNamedBufferSubData(sums.id(), 0, static_cast<GLsizeiptr>(result.size() * 4), result.data());
        const std::size_t slot = (1 + kSide * (1 + kSide * 1)) * VCT_LEAF_SUM_WORDS;
        const float area = kFragments * kArea;
        EXPECT_EQ(result[slot + 0], area);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(result[slot + 1 + c], area) << "albedo " << c;
            EXPECT_EQ(result[slot + 4 + c], c == 2 ? area : 0.0f) << "normal " << c;
            EXPECT_EQ(result[slot + 7 + c], area * kEmission) << "emission " << c;
        }
        float elsewhere = 0.0f;
        for (std::size_t i = 0; i < result.size(); ++i) elsewhere += (i / VCT_LEAF_SUM_WORDS == slot / VCT_LEAF_SUM_WORDS) ? 0.0f : std::abs(result[i]);
        EXPECT_EQ(elsewhere, 0.0f);
    }
}

}  // namespace
}  // namespace bounce::test
