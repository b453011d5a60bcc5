// The bench corpus (bench/corpus.hpp) is generated, so its scenes are checked like imported ones:
// finite, no degenerate triangles, lights and a camera that looks at them; and the analysis tells
// the open street from the closed rooms as the theory of enclosures says.
#include "bench/corpus.hpp"
#include "bench/scenes.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/scene/mesh_utils.hpp"
#include "renderer/scene_analysis.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <unistd.h>

namespace bounce {
namespace {

TEST(Corpus, EverySceneIsWellFormedAndInView) {
    const auto scenes = bench::corpus_scenes();
    ASSERT_EQ(scenes.size(), 5u);
    for (const auto& bench_scene : scenes) {
        SCOPED_TRACE(bench_scene.name);
        const scene::Scene& scene = bench_scene.scene;
        EXPECT_NO_THROW(scene::validate_finite(scene));
        EXPECT_FALSE(scene.lights.empty());
        ASSERT_EQ(scene.cameras.size(), 1u);
        for (const auto& object : scene.objects) {
            const auto& mesh = scene.meshes.at(static_cast<std::size_t>(object.mesh));
            for (const auto& primitive : mesh.primitives) {
                EXPECT_LT(primitive.material, static_cast<int>(scene.materials.size()));
                for (std::size_t t = 0; t < primitive.triangle_count(); ++t) {
                    ASSERT_GT(scene::world_triangle_area(object.transform, primitive, t), 0.0f) << object.name;
                }
            }
        }
        // Rays through a grid over the view: all but the sky (outdoor, foliage) meet a surface.
        const raytrace::RayScene rays(scene);
        const scene::Camera& camera = scene.cameras.front();
        const glm::vec3 right = glm::cross(camera.forward(), camera.up());
        const float half = std::tan(0.5f * camera.vertical_fov);
        int hits = 0, total = 0;
        for (int y = -8; y <= 8; ++y) {
            for (int x = -8; x <= 8; ++x, ++total) {
                const glm::vec3 direction =
                    glm::normalize(camera.forward() + (x / 8.0f) * half * right + (y / 8.0f) * half * camera.up());
                if (rays.intersect(camera.position, direction, 0.0f, 1e4f)) ++hits;
            }
        }
        EXPECT_GT(hits, total / 2);
    }
}

// Light leaves an open street after a bounce or two; in closed rooms it bounces on.
TEST(Corpus, TheOpenStreetNeedsFewerBouncesThanTheClosedRooms) {
    std::map<std::string, BounceEnergy> bounces;
    for (const auto& bench_scene : bench::corpus_scenes()) bounces[bench_scene.name] = analyze_scene(bench_scene.scene).bounces;
    for (const char* closed : {"furnished_room", "glossy_gallery"}) {
        SCOPED_TRACE(closed);
        EXPECT_GT(bounces.at(closed).bounces_for(0.05), bounces.at("outdoor").bounces_for(0.05));
    }
}

// A deployment's files as bench scenes (bench/quality --gltf): named by their stem, their reference
// cached under a hash of what they render from. An edit of an external buffer (a .glb whose
// triangle is in triangle.bin) changes that hash although the .glb's own bytes do not change; the
// same files read again keep it. Two files of one stem are refused, naming both.
TEST(Corpus, AFilesSceneIsKeyedByWhatItRendersFrom) {
    const auto data = std::filesystem::path(BOUNCE_SOURCE_DIR) / "tests/data/gltf";
    const auto directory =
        std::filesystem::temp_directory_path() / ("bounce-gltf-scenes-" + std::to_string(::getpid()));
    std::filesystem::create_directories(directory);
    for (const char* name : {"external_buffer.glb", "triangle.bin"}) {
        std::filesystem::copy_file(data / name, directory / name, std::filesystem::copy_options::overwrite_existing);
    }
    const auto scenes = bench::gltf_scenes({directory / "external_buffer.glb"});
    ASSERT_EQ(scenes.size(), 1u);
    EXPECT_EQ(scenes[0].name, "external_buffer");
    EXPECT_NE(scenes[0].file_hash, 0u);
    EXPECT_EQ(bench::gltf_scenes({directory / "external_buffer.glb"})[0].file_hash, scenes[0].file_hash);
    {
        std::fstream bin(directory / "triangle.bin", std::ios::in | std::ios::out | std::ios::binary);
        const float moved = 2.0f;  // the second vertex's x, 1 before
        bin.seekp(3 * sizeof(float));
        bin.write(reinterpret_cast<const char*>(&moved), sizeof(moved));
    }
    EXPECT_NE(bench::gltf_scenes({directory / "external_buffer.glb"})[0].file_hash, scenes[0].file_hash);
    try {
        bench::gltf_scenes({directory / "external_buffer.glb", data / "external_buffer.glb"});
        ADD_FAILURE() << "two files of one stem were taken";
    } catch (const std::runtime_error& error) {
        EXPECT_NE(std::string(error.what()).find("two scenes named 'external_buffer'"), std::string::npos)
            << error.what();
    }
    std::filesystem::remove_all(directory);
}

}  // namespace
}  // namespace bounce
