#include "renderer/scene/gltf_import.hpp"

#include "renderer/base/error.hpp"
#include "support/hostile_gltf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace bounce::scene {
namespace {

const std::filesystem::path assimp_dir = BOUNCE_ASSIMP_MODELS_DIR;
const std::filesystem::path own_dir = std::filesystem::path(BOUNCE_TEST_DATA_DIR) / "gltf";

// The message of the InputError that importing `path` throws ("" when it loads).
std::string import_error(const std::filesystem::path& path) {
    try {
        import_gltf_file(path);
    } catch (const InputError& error) {
        return error.what();
    }
    return "";
}

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
    std::ifstream stream(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
}

// The warnings other than "no lights" (which every unlit test file also earns).
std::vector<std::string> warnings_besides_unlit(const Scene& scene) {
    std::vector<std::string> rest;
    for (const std::string& warning : scene.warnings) {
        if (warning.find("no lights and no emissive") == std::string::npos) rest.push_back(warning);
    }
    return rest;
}

std::size_t warnings_mentioning(const Scene& scene, const std::string& text) {
    std::size_t count = 0;
    for (const std::string& warning : scene.warnings) count += warning.find(text) != std::string::npos;
    return count;
}

void expect_near(const glm::vec3& actual, const glm::vec3& expected, float tolerance = 1e-5f) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_sound_primitive(const Primitive& primitive) {
    const std::size_t vertices = primitive.positions.size();
    ASSERT_EQ(primitive.normals.size(), vertices);
    ASSERT_EQ(primitive.tangents.size(), vertices);
    EXPECT_EQ(primitive.indices.size() % 3, 0u);
    for (std::uint32_t index : primitive.indices) EXPECT_LT(index, vertices);
    for (std::size_t v = 0; v < vertices; ++v) {
        const glm::vec3& normal = primitive.normals[v];
        const glm::vec4& tangent = primitive.tangents[v];
        EXPECT_TRUE(std::isfinite(normal.x) && std::isfinite(normal.y) && std::isfinite(normal.z));
        EXPECT_NEAR(glm::length(normal), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::length(glm::vec3(tangent)), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::dot(normal, glm::vec3(tangent)), 0.0f, 1e-5f);
        EXPECT_TRUE(tangent.w == 1.0f || tangent.w == -1.0f);
    }
}

// ---- malformed files from the assimp test models: each is refused with its fault named

TEST(GltfImportRejects, IndexOutOfRange) {
    const std::string message = import_error(assimp_dir / "IndexOutOfRange/IndexOutOfRange.gltf");
    EXPECT_NE(message.find("IndexOutOfRange.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("mesh 0 primitive 0: index"), std::string::npos) << message;
    EXPECT_NE(message.find("out of range (24 vertices)"), std::string::npos) << message;
}

TEST(GltfImportRejects, AllIndicesOutOfRange) {
    const std::string message = import_error(assimp_dir / "IndexOutOfRange/AllIndicesOutOfRange.gltf");
    EXPECT_NE(message.find("AllIndicesOutOfRange.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("at position 0 is out of range (24 vertices)"), std::string::npos) << message;
}

TEST(GltfImportRejects, MissingBuffer) {
    const std::string message = import_error(assimp_dir / "MissingBin/BoxTextured.gltf");
    EXPECT_NE(message.find("BoxTextured.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("File not found : BoxTextured0.bin"), std::string::npos) << message;
}

TEST(GltfImportRejects, PrimitivesNotAnArray) {
    const std::string message = import_error(assimp_dir / "wrongTypes/badArray.gltf");
    EXPECT_NE(message.find("meshes[0].primitives must be an array (found object)"), std::string::npos)
        << message;
}

TEST(GltfImportRejects, NormalScaleNotANumber) {
    const std::string message = import_error(assimp_dir / "wrongTypes/badNumber.gltf");
    EXPECT_NE(message.find("materials[0].normalTexture.scale must be a number"), std::string::npos)
        << message;
    // The same file also lacks the required normalTexture.index; the type fault is reported first.
}

TEST(GltfImportRejects, PbrNotAnObject) {
    const std::string message = import_error(assimp_dir / "wrongTypes/badObject.gltf");
    EXPECT_NE(message.find("materials[0].pbrMetallicRoughness must be an object (found array)"),
              std::string::npos)
        << message;
}

TEST(GltfImportRejects, NameNotAString) {
    const std::string message = import_error(assimp_dir / "wrongTypes/badString.gltf");
    EXPECT_NE(message.find("scenes[0].name must be a string (found number 42)"), std::string::npos)
        << message;
}

TEST(GltfImportRejects, NegativeTextureIndex) {
    const std::string message = import_error(assimp_dir / "wrongTypes/badUint.gltf");
    EXPECT_NE(message.find("materials[0].pbrMetallicRoughness.baseColorTexture.index must be a non-negative "
                           "integer (found number -1)"),
              std::string::npos)
        << message;
}

TEST(GltfImportRejects, SceneNotAnIndex) {
    const std::string message = import_error(assimp_dir / "SchemaFailures/sceneWrongType.gltf");
    EXPECT_NE(
        message.find("sceneWrongType.gltf: scene must be a non-negative integer (found string \"hello\")"),
        std::string::npos)
        << message;
}

TEST(GltfImportRejects, RecursiveNodes) {
    const std::string message = import_error(assimp_dir / "RecursiveNodes/RecursiveNodes.gltf");
    EXPECT_NE(message.find("RecursiveNodes.gltf"), std::string::npos) << message;
    EXPECT_NE(message.find("is its own ancestor: the node hierarchy has a cycle"), std::string::npos)
        << message;
}

TEST(GltfImportRejects, InfinitePositions) {
    const std::string message =
        import_error(assimp_dir / "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb");
    EXPECT_NE(message.find("BoxWithInfinites.glb: mesh 0 primitive 0: vertex"), std::string::npos) << message;
    EXPECT_NE(message.find("non-finite position"), std::string::npos) << message;
}

TEST(GltfImportRejects, IncorrectVertexArrays) {
    // Cube.bin holds 514 bytes, but bufferViews 2 to 4 reach up to byte 1800.
    const std::string message = import_error(assimp_dir / "IncorrectVertexArrays/Cube.gltf");
    EXPECT_NE(message.find("Cube.gltf: bufferViews[2] (bytes 504..936) exceeds buffer 0 (514 bytes)"),
              std::string::npos)
        << message;
}

TEST(GltfImportRejects, DracoIsRequiredButUnsupported) {
    const std::string message = import_error(assimp_dir / "draco/2CylinderEngine.gltf");
    EXPECT_NE(message.find("requires the unsupported extension KHR_draco_mesh_compression"),
              std::string::npos)
        << message;
}

TEST(GltfImportRejects, MalformedExtensionValue) {
    // badExtension.gltf is a valid box except that KHR_texture_transform is a string: glTF's schema
    // (and the Khronos validator) require extension values to be objects.
    const std::string message = import_error(assimp_dir / "wrongTypes/badExtension.gltf");
    EXPECT_NE(message.find("KHR_texture_transform must be an object"), std::string::npos) << message;
}

// KHR_texture_transform as the Khronos sample (TextureTransformTest) writes it: offset, rotation
// and scale composed as translation * rotation * scale, applied where textures are sampled.
TEST(GltfImportAccepts, TextureTransformsAsTheirSpecificationComposesThem) {
    const Scene scene = import_gltf_file(assimp_dir / "textureTransform/TextureTransformTest.gltf");
    const auto transform_of = [&](const std::string& name) {
        for (const auto& material : scene.materials) {
            if (material.name == name) {
                EXPECT_TRUE(material.base_color_texture.valid()) << name;
                return material.base_color_texture;
            }
        }
        ADD_FAILURE() << "no material " << name;
        return TextureRef{};
    };
    const auto near = [](glm::vec2 a, glm::vec2 b) { return glm::length(a - b) < 1e-5f; };
    EXPECT_TRUE(near(transform_of("Offset U").transform({0.25f, 0.25f}), {0.75f, 0.25f}));
    EXPECT_TRUE(near(transform_of("Offset UV").transform({0.0f, 0.0f}), {0.5f, 0.5f}));
    const float angle = 0.39269908169872414f;
    EXPECT_TRUE(near(transform_of("Rotation").transform({1.0f, 0.0f}), {std::cos(angle), std::sin(angle)}));
    EXPECT_TRUE(near(transform_of("Scale").transform({1.0f, 2.0f}), {1.5f, 3.0f}));
    // All: offset (-0.2, -0.1), rotation 0.3, scale 1.5, applied scale first.
    const glm::vec2 scaled(1.5f, 0.0f);
    const glm::vec2 rotated(scaled.x * std::cos(0.3f), scaled.x * std::sin(0.3f));
    EXPECT_TRUE(near(transform_of("All").transform({1.0f, 0.0f}), rotated + glm::vec2(-0.2f, -0.1f)));
    EXPECT_TRUE(near(transform_of("Correct").transform({0.3f, 0.6f}), {0.3f, 0.6f}));  // none: identity
}


// ---- valid files from the assimp test models

TEST(GltfImportAccepts, MorphCube) {
    const Scene scene =
        import_gltf_file(assimp_dir / "glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf");
    EXPECT_EQ(scene.name, "AnimatedMorphCube");
    ASSERT_EQ(scene.objects.size(), 1u);
    EXPECT_EQ(scene.objects[0].name, "AnimatedMorphCube");
    ASSERT_EQ(scene.meshes.size(), 1u);
    ASSERT_EQ(scene.meshes[0].primitives.size(), 1u);
    const Primitive& primitive = scene.meshes[0].primitives[0];
    EXPECT_EQ(primitive.positions.size(), 24u);
    EXPECT_EQ(primitive.triangle_count(), 12u);
    expect_sound_primitive(primitive);
    // Eight of the file's tangents lie along their normals; they are replaced.
    EXPECT_EQ(warnings_mentioning(scene, "8 tangents"), 1u);
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_NEAR(scene.materials[0].base_color.r, 0.6038274f, 1e-6f);
    EXPECT_FLOAT_EQ(scene.materials[0].roughness, 0.5f);
    EXPECT_FLOAT_EQ(scene.materials[0].metallic, 0.0f);
    // The node scales by 100: the world bounds are 100 times the mesh bounds.
    EXPECT_NEAR(scene.world_bounds().extent().x, 100.0f * scene.meshes[0].bounds.extent().x, 1e-3f);
    ASSERT_EQ(scene.cameras.size(), 1u);
    EXPECT_EQ(scene.cameras[0].name, "default");
}

void expect_textured_box(const Scene& scene) {
    ASSERT_EQ(scene.objects.size(), 1u);
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Primitive& primitive = scene.meshes[0].primitives.at(0);
    EXPECT_EQ(primitive.positions.size(), 24u);
    EXPECT_EQ(primitive.uv0.size(), 24u);
    EXPECT_EQ(primitive.triangle_count(), 12u);
    expect_sound_primitive(primitive);
    ASSERT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.textures[0].width, 211);
    EXPECT_EQ(scene.textures[0].height, 211);
    EXPECT_EQ(scene.textures[0].rgba8.size(), 211u * 211u * 4u);
    EXPECT_TRUE(scene.textures[0].srgb);
    EXPECT_EQ(scene.materials.at(0).base_color_texture.texture, 0);
    EXPECT_EQ(scene.materials[0].metallic, 0.0f);
    // The root node's matrix turns the box's Z-up into Y-up.
    expect_near(scene.world_bounds().min, glm::vec3(-0.5f), 1e-5f);
    expect_near(scene.world_bounds().max, glm::vec3(0.5f), 1e-5f);
    EXPECT_TRUE(warnings_besides_unlit(scene).empty());
}

TEST(GltfImportAccepts, BoxTextured) {
    const Scene scene = import_gltf_file(assimp_dir / "BoxTextured-glTF/BoxTextured.gltf");
    EXPECT_EQ(scene.name, "BoxTextured");
    expect_textured_box(scene);
}

TEST(GltfImportAccepts, BoxTexturedBinary) {
    expect_textured_box(import_gltf_file(assimp_dir / "BoxTextured-glTF-Binary/BoxTextured.glb"));
}

TEST(GltfImportAccepts, Cameras) {
    const Scene scene = import_gltf_file(assimp_dir / "cameras/Cameras.gltf");
    // One perspective camera; the orthographic one is skipped with a warning.
    ASSERT_EQ(scene.cameras.size(), 1u);
    EXPECT_EQ(scene.cameras[0].name, "camera_0");
    EXPECT_FLOAT_EQ(scene.cameras[0].vertical_fov, 0.7f);
    EXPECT_FLOAT_EQ(scene.cameras[0].z_near, 0.01f);
    EXPECT_FLOAT_EQ(scene.cameras[0].z_far, 100.0f);
    expect_near(scene.cameras[0].position, {0.5f, 0.5f, 3.0f});
    expect_near(scene.cameras[0].forward(), {0.0f, 0.0f, -1.0f});
    EXPECT_EQ(warnings_mentioning(scene, "orthographic"), 1u);
    EXPECT_EQ(scene.objects.size(), 1u);
}

// NoScene.gltf names "scene": 0 with no scenes at all: an unresolved reference (the Khronos
// validator's error too), refused; a scene without nodes is an empty scene.
TEST(GltfImportRejects, ADefaultSceneThatDoesNotExist) {
    const std::string message = import_error(assimp_dir / "TestNoRootNode/NoScene.gltf");
    EXPECT_NE(message.find("the default scene 0 does not exist (there are 0 scenes)"), std::string::npos) << message;
}

// assimp's issue_3269: a primitive with TEXCOORD_1 and no TEXCOORD_0 (glTF numbers indexed
// attributes from 0 without gaps).
TEST(GltfImportRejects, TexcoordsWithAGap) {
    const std::string message = import_error(assimp_dir / "issue_3269/texcoord_crash.gltf");
    EXPECT_NE(message.find("has TEXCOORD_1 without TEXCOORD_0"), std::string::npos) << message;
}

TEST(GltfImportAccepts, NoRootNode) {
    for (const char* file : {"SceneWithoutNodes.gltf"}) {
        const Scene scene = import_gltf_file(assimp_dir / "TestNoRootNode" / file);
        EXPECT_TRUE(scene.objects.empty()) << file;
        EXPECT_TRUE(scene.meshes.empty()) << file;
        ASSERT_EQ(scene.cameras.size(), 1u) << file;
        EXPECT_EQ(scene.cameras[0].name, "default") << file;
        EXPECT_TRUE(std::isfinite(scene.cameras[0].position.z)) << file;
    }
}

// ---- our own files (tests/data/gltf)

TEST(GltfImportOwn, MissingTextureFallsBackToTheFactor) {
    const Scene scene = import_gltf_file(own_dir / "missing_texture.gltf");
    ASSERT_EQ(scene.objects.size(), 1u);
    EXPECT_EQ(warnings_besides_unlit(scene).size(), 1u);
    EXPECT_EQ(warnings_mentioning(scene, "does_not_exist.png"), 1u);
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_FALSE(scene.materials[0].base_color_texture.valid());
    EXPECT_EQ(scene.materials[0].base_color, glm::vec4(0.2f, 0.4f, 0.6f, 1.0f));
    EXPECT_TRUE(scene.textures.empty());
}

TEST(GltfImportOwn, PngChunkPastTheEndIsNotDecoded) {
    // Its IDAT chunk declares 512 MiB in a file of a hundred bytes: the decoder would allocate it all.
    const Scene scene = import_gltf_file(own_dir / "oversized_png_chunk.gltf");
    ASSERT_EQ(scene.objects.size(), 1u);
    EXPECT_EQ(warnings_mentioning(scene, "a PNG chunk runs past the end of the image"), 1u);
    EXPECT_TRUE(scene.textures.empty());
}

TEST(GltfImportOwn, RequiredUnsupportedExtensionIsRefused) {
    const std::string message = import_error(own_dir / "required_unsupported_extension.gltf");
    EXPECT_NE(message.find("required_unsupported_extension.gltf: requires the unsupported extension "
                           "KHR_materials_transmission"),
              std::string::npos)
        << message;
}

TEST(GltfImportOwn, UnknownOptionalExtensionWarns) {
    const Scene scene = import_gltf_file(own_dir / "unknown_optional_extension.gltf");
    EXPECT_EQ(scene.objects.size(), 1u);
    EXPECT_EQ(scene.objects[0].name, "sparkly");
    EXPECT_EQ(warnings_mentioning(scene, "VENDOR_sparkles"), 1u);
}

TEST(GltfImportOwn, PunctualLightsInWorldSpace) {
    // The parent "rig" moves by (10, 0, 0) and turns 90 degrees about +Y, which maps local -Z to -X.
    // Intensities are KHR_lights_punctual's candela (point, spot) and lux (directional), held as
    // W/sr and W/m^2 at 683 lm/W.
    const Scene scene = import_gltf_file(own_dir / "lights.gltf");
    ASSERT_EQ(scene.lights.size(), 3u);
    const Light& point = scene.lights[0];
    EXPECT_EQ(point.name, "bulb");
    EXPECT_EQ(point.type, LightType::point);
    EXPECT_FLOAT_EQ(point.intensity, 5.0f / 683.0f);
    expect_near(point.color, {1.0f, 0.9f, 0.8f});
    expect_near(point.position, {13.0f, 2.0f, 0.0f});

    const Light& spot = scene.lights[1];
    EXPECT_EQ(spot.name, "torch");
    EXPECT_EQ(spot.type, LightType::spot);
    EXPECT_FLOAT_EQ(spot.intensity, 20.0f / 683.0f);
    expect_near(spot.radiant(), glm::vec3(20.0f, 10.0f, 5.0f) / 683.0f, 1e-7f);
    expect_near(spot.position, {10.0f, 0.0f, -1.0f});
    expect_near(spot.direction, {-1.0f, 0.0f, 0.0f});
    EXPECT_FLOAT_EQ(spot.inner_cone, 0.2f);
    EXPECT_FLOAT_EQ(spot.outer_cone, 0.5f);

    const Light& sun = scene.lights[2];
    EXPECT_EQ(sun.name, "sun");  // the node's name when the light has none
    EXPECT_EQ(sun.type, LightType::directional);
    EXPECT_FLOAT_EQ(sun.intensity, 3.0f / 683.0f);
    expect_near(sun.color, glm::vec3(1.0f));
    expect_near(sun.direction, {0.0f, -1.0f, 0.0f});
}

TEST(GltfImportOwn, EmissiveStrengthAndSpecular) {
    const Scene scene = import_gltf_file(own_dir / "emissive_strength.gltf");
    ASSERT_EQ(scene.materials.size(), 1u);
    const Material& material = scene.materials[0];
    EXPECT_EQ(material.name, "lamp");
    expect_near(material.emissive, glm::vec3(4.0f, 2.0f, 1.0f) / 683.0f, 1e-7f);  // nits -> W/(m^2 sr)
    EXPECT_FLOAT_EQ(material.specular, 0.5f);
    EXPECT_FLOAT_EQ(material.roughness, 0.3f);
    EXPECT_FLOAT_EQ(material.metallic, 0.0f);
    EXPECT_TRUE(material.double_sided);
    EXPECT_TRUE(warnings_besides_unlit(scene).empty());
}

TEST(GltfImportOwn, TopologiesAndNames) {
    const Scene scene = import_gltf_file(own_dir / "topology.gltf");
    ASSERT_EQ(scene.meshes.size(), 3u);

    const Primitive& flat = scene.meshes[0].primitives.at(0);  // non-indexed: 0..n-1
    EXPECT_EQ(flat.indices, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
    expect_sound_primitive(flat);
    expect_near(flat.normals[0], {0.0f, 0.0f, 1.0f});
    expect_near(scene.meshes[0].bounds.max, {3.0f, 1.0f, 0.0f});

    const Primitive& quad = scene.meshes[1].primitives.at(0);  // u8 indices, normalized u8 UVs
    EXPECT_EQ(quad.indices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
    ASSERT_EQ(quad.uv0.size(), 4u);
    EXPECT_EQ(quad.uv0[1], glm::vec2(1.0f, 1.0f));
    EXPECT_EQ(quad.uv0[3], glm::vec2(0.0f, 0.0f));
    expect_sound_primitive(quad);

    // Strip and fan become lists with consistent (counter-clockwise) winding; the lines are skipped.
    const Mesh& mixed = scene.meshes[2];
    ASSERT_EQ(mixed.primitives.size(), 2u);
    EXPECT_EQ(mixed.primitives[0].indices, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2}));
    EXPECT_EQ(mixed.primitives[1].indices, (std::vector<std::uint32_t>{1, 2, 0, 2, 3, 0}));
    for (const Primitive& primitive : mixed.primitives) {
        expect_sound_primitive(primitive);
        for (const glm::vec3& normal : primitive.normals) expect_near(normal, {0.0f, 0.0f, 1.0f});
    }
    EXPECT_EQ(warnings_mentioning(scene, "mesh 2 primitive 2: points and lines"), 1u);

    // Meshes are shared; names are unique.
    ASSERT_EQ(scene.objects.size(), 4u);
    EXPECT_EQ(scene.objects[0].name, "thing");
    EXPECT_EQ(scene.objects[1].name, "thing_2");
    EXPECT_EQ(scene.objects[2].name, "object_2");
    EXPECT_EQ(scene.objects[3].name, "thing_3");
    EXPECT_EQ(scene.objects[1].mesh, 1);
    EXPECT_EQ(scene.objects[3].mesh, 1);
    EXPECT_EQ(scene.triangle_count(), 2u + 2u + 4u + 2u);
}

TEST(GltfImportOwn, NanPositionIsRefused) {
    const std::string message = import_error(own_dir / "nan_position.gltf");
    EXPECT_NE(message.find("nan_position.gltf: mesh 0 primitive 0: vertex 1 has a non-finite position"),
              std::string::npos)
        << message;
}

TEST(GltfImportOwn, ZeroAreaTrianglesGetFiniteNormals) {
    const Scene scene = import_gltf_file(own_dir / "zero_area.gltf");
    const Primitive& primitive = scene.meshes.at(0).primitives.at(0);
    EXPECT_EQ(primitive.triangle_count(), 3u);
    expect_sound_primitive(primitive);
    expect_near(primitive.normals[3], {0.0f, 0.0f, 1.0f});
}

TEST(GltfImportOwn, BrokenJsonIsRefused) {
    const std::string message = import_error(own_dir / "broken_json.gltf");
    EXPECT_NE(message.find("broken_json.gltf: invalid JSON"), std::string::npos) << message;
}

TEST(GltfImportOwn, TexturesColourSpacesAndTangents) {
    const Scene scene = import_gltf_file(own_dir / "textured.gltf");
    // The grey image is used as sRGB base colour and as linear normal map: two Textures.
    ASSERT_EQ(scene.textures.size(), 3u);
    const Material& material = scene.materials.at(0);
    const Texture& base = scene.textures.at(static_cast<std::size_t>(material.base_color_texture.texture));
    const Texture& normal = scene.textures.at(static_cast<std::size_t>(material.normal_texture.texture));
    const Texture& packed =
        scene.textures.at(static_cast<std::size_t>(material.metallic_roughness_texture.texture));
    EXPECT_TRUE(base.srgb);
    EXPECT_FALSE(normal.srgb);
    EXPECT_FALSE(packed.srgb);
    EXPECT_EQ(base.name, "grey");
    EXPECT_EQ(base.rgba8, normal.rgba8);
    // Grey expands to RGB with opaque alpha, rows top to bottom.
    EXPECT_EQ(base.rgba8, (std::vector<std::uint8_t>{0, 0, 0, 255, 128, 128, 128, 255, 255, 255, 255, 255, 64,
                                                     64, 64, 255}));
    // 16-bit samples are scaled to 8 bits.
    EXPECT_EQ(packed.rgba8, (std::vector<std::uint8_t>{255, 128, 0, 255}));
    EXPECT_FLOAT_EQ(material.normal_scale, 0.5f);

    // No TANGENT in the file: generated from the UVs (u grows along +X here, v grows along -Y).
    const Primitive& primitive = scene.meshes.at(0).primitives.at(0);
    expect_sound_primitive(primitive);
    for (const glm::vec4& tangent : primitive.tangents) {
        expect_near(glm::vec3(tangent), {1.0f, 0.0f, 0.0f});
        EXPECT_EQ(tangent.w, 1.0f);
    }
}

TEST(GltfImportOwn, UndecodableImageOnlyWarns) {
    // external_image.glb's image URI names a .gltf file: found, but not an image.
    const Scene scene = import_gltf_file(own_dir / "external_image.glb");
    EXPECT_EQ(scene.objects.size(), 1u);
    const auto warnings = warnings_besides_unlit(scene);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("'missing_texture.gltf'"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("cannot decode"), std::string::npos) << warnings[0];
    EXPECT_FALSE(scene.materials.at(0).base_color_texture.valid());
}

TEST(GltfImportOwn, Limits) {
    const std::string message = import_error(own_dir / "huge_accessor.gltf");
    EXPECT_NE(message.find("accessor 0 has 268435457 elements, more than the limit"), std::string::npos)
        << message;
    // An oversized image is refused from its header, before decoding; the scene still loads.
    const Scene scene = import_gltf_file(own_dir / "huge_image.gltf");
    EXPECT_TRUE(scene.textures.empty());
    EXPECT_FALSE(scene.materials.at(0).emissive_texture.valid());
    EXPECT_EQ(warnings_mentioning(scene, "20000x1 pixels exceeds the limit of 16384 per side"), 1u);
}

// ---- uploads

TEST(GltfImportMemory, LoadsAnEmbeddedGlb) {
    const std::vector<std::uint8_t> bytes =
        read_bytes(assimp_dir / "BoxTextured-glTF-Binary/BoxTextured.glb");
    ASSERT_FALSE(bytes.empty());
    const Scene scene = import_glb_memory(bytes, "upload");
    EXPECT_EQ(scene.name, "upload");
    expect_textured_box(scene);
}

TEST(GltfImportMemory, RefusesExternalFiles) {
    for (const char* file : {"external_buffer.glb", "external_image.glb"}) {
        const std::vector<std::uint8_t> bytes = read_bytes(own_dir / file);
        ASSERT_FALSE(bytes.empty());
        try {
            import_glb_memory(bytes, "upload");
            ADD_FAILURE() << file << " loaded";
        } catch (const InputError& error) {
            EXPECT_NE(std::string(error.what()).find("upload: "), std::string::npos) << error.what();
            EXPECT_NE(std::string(error.what()).find("refers to the external file"), std::string::npos)
                << error.what();
        }
    }
    // From disk, the same external buffer is fine.
    EXPECT_EQ(import_gltf_file(own_dir / "external_buffer.glb").objects.size(), 1u);
}

TEST(GltfImportMemory, RefusesGarbage) {
    const std::vector<std::uint8_t> not_glb = {'{', '}'};
    EXPECT_THROW(import_glb_memory(not_glb, "upload"), InputError);
    std::vector<std::uint8_t> truncated = read_bytes(assimp_dir / "BoxTextured-glTF-Binary/BoxTextured.glb");
    truncated.resize(truncated.size() / 2);
    try {
        import_glb_memory(truncated, "upload");
        ADD_FAILURE() << "a truncated GLB loaded";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("truncated GLB"), std::string::npos) << error.what();
    }
}

// The chunks must tile the file, each within it and a multiple of 4 bytes long, as the format
// requires: tinygltf finds the chunk after the JSON one by the JSON chunk's length, and a GLB whose
// JSON length was one byte long (a flipped bit, found by scripts/fuzz; its request is in
// server/fuzz/corpus) made it copy past the end of the data. Each such file is refused by name.
TEST(GltfImportMemory, RefusesChunksThatDoNotTileTheFile) {
    const std::vector<std::uint8_t> box =
        read_bytes(assimp_dir / "BoxTextured-glTF-Binary/BoxTextured.glb");
    ASSERT_NO_THROW(import_glb_memory(box, "upload"));
    const auto u32_at = [](const std::vector<std::uint8_t>& bytes, std::size_t offset) {
        std::uint32_t value = 0;
        for (std::size_t i = 0; i < 4; ++i) value |= static_cast<std::uint32_t>(bytes[offset + i]) << (8 * i);
        return value;
    };
    const auto set_u32 = [](std::vector<std::uint8_t>& bytes, std::size_t offset, std::uint32_t value) {
        for (std::size_t i = 0; i < 4; ++i) bytes[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
    };
    const auto refusal = [](const std::vector<std::uint8_t>& bytes) {
        try {
            import_glb_memory(bytes, "upload");
        } catch (const InputError& error) {
            return std::string(error.what());
        }
        return std::string("loaded");
    };
    std::vector<std::uint8_t> json_long = box;
    set_u32(json_long, 12, u32_at(json_long, 12) + 1);
    EXPECT_NE(refusal(json_long).find("not a multiple of 4"), std::string::npos) << refusal(json_long);
    std::vector<std::uint8_t> bin_past_the_end = box;
    const std::size_t bin_header = 20 + u32_at(bin_past_the_end, 12);
    set_u32(bin_past_the_end, bin_header, u32_at(bin_past_the_end, bin_header) + 4);
    EXPECT_NE(refusal(bin_past_the_end).find("exceeds the file"), std::string::npos)
        << refusal(bin_past_the_end);
    std::vector<std::uint8_t> trailing = box;
    trailing.insert(trailing.end(), {0, 0, 0, 0});
    EXPECT_NE(refusal(trailing).find("data past its end"), std::string::npos) << refusal(trailing);
    std::vector<std::uint8_t> header_cut = box;  // a last chunk of a header and nothing more
    header_cut.insert(header_cut.end(), {4, 0, 0, 0});
    set_u32(header_cut, 8, static_cast<std::uint32_t>(header_cut.size()));
    EXPECT_NE(refusal(header_cut).find("needs 8 bytes"), std::string::npos) << refusal(header_cut);
}

TEST(GltfImportMemory, RefusesALengthShorterThanItsHeaders) {
    // A total length under the 20 bytes of headers once let a JSON chunk length past the input through.
    std::vector<std::uint8_t> glb = {'g', 'l', 'T', 'F', 2, 0, 0, 0, 0, 0, 0, 0,  // total length 0
                                     0, 0, 4, 0, 'J', 'S', 'O', 'N'};             // 262144 bytes of JSON
    glb.resize(64, ' ');
    try {
        import_glb_memory(glb, "upload");
        ADD_FAILURE() << "a GLB shorter than its headers loaded";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("truncated GLB: header says 0 bytes"), std::string::npos)
            << error.what();
    }
}

TEST(GltfImportAccepts, UnlitSceneEarnsOneWarning) {
    const Scene scene = import_gltf_file(assimp_dir / "BoxTextured-glTF/BoxTextured.gltf");
    EXPECT_EQ(warnings_mentioning(scene, "no lights and no emissive"), 1u);
}

}  // namespace
}  // namespace bounce::scene

namespace bounce::scene {
namespace {

// A copy of one of the project's test files with `from` replaced by `to`, in a temporary folder
// beside copies of its buffers, handed to `use` and removed after.
template <typename Use>
auto with_edited(const std::string& file, const std::string& from, const std::string& to, Use&& use) {
    const auto dir = std::filesystem::temp_directory_path() / ("bounce-gltf-edit-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::copy(own_dir, dir, std::filesystem::copy_options::recursive);
    std::ifstream in(dir / file);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    std::ofstream(dir / file, std::ios::trunc) << text;
    struct Cleanup {
        std::filesystem::path dir;
        ~Cleanup() { std::filesystem::remove_all(dir); }
    } cleanup{dir};
    return use(dir / file);
}

// The import's fault message for an edited file ("" when it loads), and the scene it loads.
std::string import_error_of_edited(const std::string& file, const std::string& from, const std::string& to) {
    return with_edited(file, from, to, [](const std::filesystem::path& path) { return import_error(path); });
}
Scene import_edited(const std::string& file, const std::string& from, const std::string& to) {
    return with_edited(file, from, to, [](const std::filesystem::path& path) { return import_gltf_file(path); });
}

// Indices as tinygltf reads them: JSON integers in [0, INT_MAX]. A float index or one past INT_MAX
// would be dropped or wrapped by tinygltf's int fields (a silently different scene), so the file is
// refused naming it; a light index past INT_MAX would not even convert to int.
TEST(GltfImportRejects, IndicesThatAreNotIntegersOrPastIntMax) {
    EXPECT_EQ(import_error_of_edited("emissive_strength.gltf", "\"mesh\": 0", "\"mesh\": 0"), "");
    EXPECT_NE(import_error_of_edited("emissive_strength.gltf", "\"mesh\": 0", "\"mesh\": 0.0"), "");
    EXPECT_NE(import_error_of_edited("emissive_strength.gltf", "\"mesh\": 0", "\"mesh\": 4294967296"), "");
    EXPECT_NE(import_error_of_edited("lights.gltf", "\"light\": 0", "\"light\": 3e9").find("light"), std::string::npos);
}

// Each member of KHR_texture_transform is checked: wrong types and counts refuse the file, naming
// the texture and the member; texCoord overrides the textureInfo's.
TEST(GltfImportRejects, MalformedTextureTransforms) {
    const std::string anchor = "\"baseColorTexture\": {\n     \"index\": 0";
    const auto with = [&](const std::string& transform) {
        return import_error_of_edited("textured.gltf", anchor,
                                      anchor + ", \"extensions\": {\"KHR_texture_transform\": " + transform + "}");
    };
    EXPECT_EQ(with(R"({"offset": [0.5, 0.25], "rotation": 1, "scale": [2, 2]})"), "");
    EXPECT_NE(with(R"({"offset": [0.5, 0.25, 1]})").find("baseColorTexture KHR_texture_transform offset must be an array of 2 numbers"),
              std::string::npos);
    EXPECT_NE(with(R"({"scale": ["2", 2]})").find("scale must be an array of 2 numbers"), std::string::npos);
    EXPECT_NE(with(R"({"rotation": "half"})").find("rotation must be a number"), std::string::npos);
    EXPECT_NE(with(R"({"texCoord": -1})").find("texCoord must be a non-negative integer"), std::string::npos);
    EXPECT_NE(with(R"({"scale": [1e39, 1]})").find("scale"), std::string::npos);
    EXPECT_NE(with(R"("sideways")").find("must be an object"), std::string::npos);
}


// A texture read through a UV set the primitive lacks (textured.gltf without its TEXCOORD_0): the
// set is filled with (0, 0), the same for every method and the reference, with a warning.
TEST(GltfImportAccepts, AMissingUvSetReadsZeroWithAWarning) {
    const Scene scene = import_edited("textured.gltf", ",\n      \"TEXCOORD_0\": 1", "");
    EXPECT_GE(warnings_mentioning(scene, "samples TEXCOORD_0, which the primitive lacks"), 1u);
    for (const auto& mesh : scene.meshes) {
        for (const auto& primitive : mesh.primitives) {
            ASSERT_EQ(primitive.uv0.size(), primitive.positions.size());
            for (const glm::vec2& uv : primitive.uv0) EXPECT_EQ(uv, glm::vec2(0.0f));
        }
    }
}


// KHR_mesh_quantization as gltfpack writes it: positions as 16-bit integers (not normalized, the
// node's scale dequantizes them, 8-byte stride for alignment), normals as normalized bytes, texture
// coordinates as normalized 16-bit integers. The same file without the extension is refused: core
// glTF allows float positions only.
std::vector<std::uint8_t> quantized_square(bool declare_extension) {
    std::vector<std::uint8_t> bin;
    const auto put16 = [&](std::int16_t v) { bin.push_back(static_cast<std::uint8_t>(v & 0xff)), bin.push_back(static_cast<std::uint8_t>((v >> 8) & 0xff)); };
    for (const auto& [x, z] : std::vector<std::pair<int, int>>{{-1000, -1000}, {1000, -1000}, {1000, 1000}, {-1000, 1000}}) {
        put16(static_cast<std::int16_t>(x)), put16(0), put16(static_cast<std::int16_t>(z)), put16(0);  // 8-byte stride
    }
    for (int i = 0; i < 4; ++i) bin.insert(bin.end(), {0, 127, 0, 0});  // normals, 4-byte stride
    for (const auto& [u, v] : std::vector<std::pair<int, int>>{{0, 0}, {65535, 0}, {65535, 65535}, {0, 65535}}) {
        put16(static_cast<std::int16_t>(static_cast<std::uint16_t>(u))), put16(static_cast<std::int16_t>(static_cast<std::uint16_t>(v)));
    }
    for (const std::uint16_t index : {0, 2, 1, 0, 3, 2}) bin.push_back(index & 0xff), bin.push_back(index >> 8);
    const std::string used = declare_extension ? R"("extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],)" : "";
    return test::hostile::make_glb(R"({"asset": {"version": "2.0"}, )" + used + R"(
      "scene": 0, "scenes": [{"nodes": [0]}],
      "nodes": [{"name": "square", "mesh": 0, "scale": [0.001, 0.001, 0.001]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
      "buffers": [{"byteLength": 76}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 32, "byteStride": 8},
                      {"buffer": 0, "byteOffset": 32, "byteLength": 16, "byteStride": 4},
                      {"buffer": 0, "byteOffset": 48, "byteLength": 16},
                      {"buffer": 0, "byteOffset": 64, "byteLength": 12}],
      "accessors": [{"bufferView": 0, "componentType": 5122, "count": 4, "type": "VEC3", "min": [-1000, 0, -1000], "max": [1000, 0, 1000]},
                    {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3"},
                    {"bufferView": 2, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC2"},
                    {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}]})",
                                   bin);
}

TEST(GltfImportAccepts, QuantizedMeshes) {
    const auto glb = quantized_square(true);
    const Scene scene = import_glb_memory(glb, "quantized");
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Primitive& primitive = scene.meshes[0].primitives[0];
    ASSERT_EQ(primitive.positions.size(), 4u);
    expect_near(primitive.positions[2], {1000.0f, 0.0f, 1000.0f});
    expect_near(glm::vec3(scene.objects[0].transform * glm::vec4(primitive.positions[2], 1.0f)), {1.0f, 0.0f, 1.0f});
    for (const glm::vec3& normal : primitive.normals) expect_near(normal, {0.0f, 1.0f, 0.0f});
    ASSERT_EQ(primitive.uv0.size(), 4u);
    EXPECT_EQ(primitive.uv0[2], glm::vec2(1.0f, 1.0f));
    EXPECT_EQ(primitive.uv0[1], glm::vec2(1.0f, 0.0f));

    try {
        import_glb_memory(quantized_square(false), "unquantized");
        ADD_FAILURE() << "integer positions without KHR_mesh_quantization loaded";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("POSITION: accessor 0 is VEC3 of SHORT, expected VEC3 of FLOAT"),
                  std::string::npos) << error.what();
    }
}


// glTF's alphaMode: MASK keeps its cutoff (0.5 when absent), BLEND is coverage with a warning,
// OPAQUE (the default) covers everything, and an unknown mode refuses the file.
TEST(GltfImportAccepts, AlphaModes) {
    const std::string anchor = "\"pbrMetallicRoughness\": {";
    const auto material_with = [&](const std::string& alpha) { return import_edited("textured.gltf", anchor, alpha + anchor); };
    const auto refusal_with = [&](const std::string& alpha) {
        return import_error_of_edited("textured.gltf", anchor, alpha + anchor);
    };
    const Scene masked = material_with(R"("alphaMode": "MASK", "alphaCutoff": 0.3, )");
    EXPECT_EQ(masked.materials[0].alpha_mode, scene::AlphaMode::mask);
    EXPECT_FLOAT_EQ(masked.materials[0].alpha_cutoff, 0.3f);
    EXPECT_EQ(masked.materials[0].coverage(0.29f), 0.0f);
    EXPECT_EQ(masked.materials[0].coverage(0.3f), 1.0f);
    EXPECT_FLOAT_EQ(material_with(R"("alphaMode": "MASK", )").materials[0].alpha_cutoff, 0.5f);
    const Scene blended = material_with(R"("alphaMode": "BLEND", )");
    EXPECT_EQ(blended.materials[0].alpha_mode, scene::AlphaMode::blend);
    EXPECT_FLOAT_EQ(blended.materials[0].coverage(0.25f), 0.25f);
    EXPECT_EQ(blended.materials[0].coverage(-1.0f), 0.0f);
    EXPECT_EQ(blended.materials[0].coverage(std::nanf("")), 0.0f);
    EXPECT_EQ(warnings_mentioning(blended, "alphaMode BLEND is rendered as coverage"), 1u);
    const Scene opaque = material_with(R"("alphaMode": "OPAQUE", )");
    EXPECT_EQ(opaque.materials[0].alpha_mode, scene::AlphaMode::opaque);
    EXPECT_EQ(opaque.materials[0].coverage(0.0f), 1.0f);
    EXPECT_NE(refusal_with(R"("alphaMode": "GLASS", )").find("alphaMode 'GLASS' is none of OPAQUE, MASK, BLEND"),
              std::string::npos);
}


// glTF samplers: filters and wraps are read per texture (one image under two samplers is two
// textures); a value glTF does not define refuses the file.
TEST(GltfImportAccepts, Samplers) {
    const std::string anchor = "\"textures\": [\n  {\n   \"source\": 0\n  }";
    const std::string with_sampler = "\"samplers\": [{\"magFilter\": 9728, \"minFilter\": 9984, \"wrapS\": 33071, "
                                     "\"wrapT\": 33648}],\n \"textures\": [\n  {\n   \"source\": 0, \"sampler\": 0\n  }";
    const Scene scene = import_edited("textured.gltf", anchor, with_sampler);
    ASSERT_FALSE(scene.textures.empty());
    const TextureSampler& sampler = scene.textures[0].sampler;
    EXPECT_TRUE(sampler.mag_nearest);
    EXPECT_EQ(sampler.min_filter, TextureSampler::MinFilter::nearest_mipmap_nearest);
    EXPECT_EQ(sampler.wrap_s, TextureSampler::Wrap::clamp_to_edge);
    EXPECT_EQ(sampler.wrap_t, TextureSampler::Wrap::mirrored_repeat);
    const Scene plain = import_edited("textured.gltf", anchor, anchor);
    EXPECT_EQ(plain.textures[0].sampler, TextureSampler{});
    const auto refusal = [&](const std::string& member) {
        return import_error_of_edited("textured.gltf", anchor,
                                      "\"samplers\": [{" + member + "}],\n \"textures\": [\n  {\n   \"source\": 0, "
                                      "\"sampler\": 0\n  }");
    };
    EXPECT_NE(refusal("\"magFilter\": 1234").find("magFilter is 1234"), std::string::npos);
    EXPECT_NE(refusal("\"minFilter\": 9727").find("minFilter is 9727"), std::string::npos);
    EXPECT_NE(refusal("\"wrapS\": 0").find("wrapS is 0"), std::string::npos);
}

// KHR_materials_specular's colour factor, its two textures and KHR_materials_ior are read;
// malformed values refuse the file.
TEST(GltfImportAccepts, SpecularColourAndIor) {
    const std::string anchor = "\"pbrMetallicRoughness\": {";
    const auto extensions = [&](const std::string& text) { return "\"extensions\": {" + text + "}, " + anchor; };
    const Scene scene = import_edited("textured.gltf", anchor, extensions(R"("KHR_materials_specular": {
        "specularFactor": 0.5, "specularColorFactor": [1, 0.5, 0.25], "specularTexture": {"index": 0},
        "specularColorTexture": {"index": 0, "texCoord": 0}}, "KHR_materials_ior": {"ior": 2.4})"));
    EXPECT_FLOAT_EQ(scene.materials[0].specular, 0.5f);
    EXPECT_EQ(scene.materials[0].specular_color, glm::vec3(1.0f, 0.5f, 0.25f));
    EXPECT_FLOAT_EQ(scene.materials[0].ior, 2.4f);
    EXPECT_TRUE(scene.materials[0].specular_texture.valid());
    EXPECT_TRUE(scene.materials[0].specular_color_texture.valid());
    // The same image as linear data (specular) and as sRGB (colour): two textures.
    EXPECT_NE(scene.materials[0].specular_texture.texture, scene.materials[0].specular_color_texture.texture);
    const auto refusal = [&](const std::string& text) {
        return import_error_of_edited("textured.gltf", anchor, extensions(text));
    };
    EXPECT_NE(refusal(R"("KHR_materials_ior": {"ior": 0.5})").find("ior is 0.5, not 0 or at least 1"), std::string::npos);
    EXPECT_NE(refusal(R"("KHR_materials_specular": {"specularColorFactor": [1, 1]})")
                  .find("specularColorFactor must be an array of 3 numbers"),
              std::string::npos);
    EXPECT_NE(refusal(R"("KHR_materials_specular": {"specularTexture": {"index": "zero"}})")
                  .find("specularTexture must be an object with an integer index"),
              std::string::npos);
}

}  // namespace
}  // namespace bounce::scene
