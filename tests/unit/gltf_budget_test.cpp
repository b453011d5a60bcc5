// The importer's limits against hostile files: JSON nesting, the scene-size budget and the folder
// external files must lie in. Each hostile input is built here in memory; the memory attacks are
// also measured, by the growth of the process's peak resident size while they are refused.
#include "renderer/scene/gltf_import.hpp"

#include "renderer/base/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

namespace bounce::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path assimp_dir = BOUNCE_ASSIMP_MODELS_DIR;

// The peak resident size may grow by this much while a memory attack is refused: far below the
// attack's multi-GiB decode, far above the parser's working set.
constexpr std::uint64_t max_peak_growth = std::uint64_t{256} << 20;

// ---- building hostile files

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
    for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// A binary glTF: the 12-byte header, the JSON chunk (padded with spaces) and, when `bin` is not
// empty, the BIN chunk (padded with zeros).
std::vector<std::uint8_t> make_glb(std::string json_text, std::vector<std::uint8_t> bin = {}) {
    while (json_text.size() % 4 != 0) json_text += ' ';
    while (bin.size() % 4 != 0) bin.push_back(0);
    const std::size_t total = 12 + 8 + json_text.size() + (bin.empty() ? 0 : 8 + bin.size());
    std::vector<std::uint8_t> out = {'g', 'l', 'T', 'F'};
    put_u32(out, 2);
    put_u32(out, static_cast<std::uint32_t>(total));
    put_u32(out, static_cast<std::uint32_t>(json_text.size()));
    put_u32(out, 0x4E4F534Au);  // "JSON"
    out.insert(out.end(), json_text.begin(), json_text.end());
    if (!bin.empty()) {
        put_u32(out, static_cast<std::uint32_t>(bin.size()));
        put_u32(out, 0x004E4942u);  // "BIN\0"
        out.insert(out.end(), bin.begin(), bin.end());
    }
    return out;
}

std::uint32_t crc32(const std::uint8_t* bytes, std::size_t size) {
    std::uint32_t crc = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < size; ++i) {
        crc ^= bytes[i];
        for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

void put_u32_be(std::vector<std::uint8_t>& out, std::uint32_t value) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// A PNG of a few dozen bytes that declares `side` x `side` RGBA pixels: a valid IHDR and IEND, no
// pixel data. Its header is all the importer reads before deciding.
std::vector<std::uint8_t> png_declaring(std::uint32_t side) {
    std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    auto chunk = [&](const char* type, const std::vector<std::uint8_t>& data) {
        put_u32_be(png, static_cast<std::uint32_t>(data.size()));
        const std::size_t start = png.size();
        png.insert(png.end(), type, type + 4);
        png.insert(png.end(), data.begin(), data.end());
        put_u32_be(png, crc32(png.data() + start, png.size() - start));
    };
    std::vector<std::uint8_t> header;
    put_u32_be(header, side);
    put_u32_be(header, side);
    header.insert(header.end(), {8, 6, 0, 0, 0});  // 8 bits, RGBA, deflate, adaptive filters, no interlace
    chunk("IHDR", header);
    chunk("IEND", {});
    return png;
}

// A GLB whose `images` are `image_count` entries all pointing at one bufferView holding `png`, each
// used by its own texture and material.
std::vector<std::uint8_t> glb_with_images(const std::vector<std::uint8_t>& png, int image_count) {
    json document = {{"asset", {{"version", "2.0"}}},
                     {"buffers", {{{"byteLength", png.size()}}}},
                     {"bufferViews", {{{"buffer", 0}, {"byteLength", png.size()}}}},
                     {"images", json::array()},
                     {"textures", json::array()},
                     {"materials", json::array()}};
    for (int i = 0; i < image_count; ++i) {
        document["images"].push_back({{"bufferView", 0}, {"mimeType", "image/png"}});
        document["textures"].push_back({{"source", i}});
        document["materials"].push_back({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", i}}}}}});
    }
    return make_glb(document.dump(), png);
}

// ---- measuring and catching

std::uint64_t status_kib(const std::string& field) {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.starts_with(field)) return std::stoull(line.substr(field.size()));
    }
    return 0;
}

// How far the peak resident size rises while `work` runs. The peak is reset first (Linux: 5 to
// clear_refs) so that earlier tests in the same process do not hide the growth.
template <typename Work>
std::uint64_t peak_growth(Work&& work) {
    {
        std::ofstream reset("/proc/self/clear_refs");
        reset << "5";
        reset.close();
        // Without the reset an earlier peak would hide the growth and every bound would pass.
        if (!reset) ADD_FAILURE() << "cannot reset the peak resident size through /proc/self/clear_refs";
    }
    const std::uint64_t before = status_kib("VmHWM:");
    work();
    const std::uint64_t after = status_kib("VmHWM:");
    return (after > before ? after - before : 0) * 1024;
}

struct Refusal {
    std::string type;  // "ResourceExhausted", "InputError" or "" when it loaded
    std::string message;
};

template <typename Import>
Refusal refusal(Import&& import) {
    try {
        import();
    } catch (const ResourceExhausted& error) {
        return {"ResourceExhausted", error.what()};
    } catch (const InputError& error) {
        return {"InputError", error.what()};
    }
    return {};
}

// An upload's refusal, with how far the peak resident size rose while it was refused (printed too).
Refusal measured_refusal(const std::vector<std::uint8_t>& glb, const std::string& name,
                         std::uint64_t& growth) {
    Refusal result;
    growth = peak_growth([&] { result = refusal([&] { import_glb_memory(glb, name); }); });
    std::cout << name << ": the peak resident size grew by " << growth / 1024 << " KiB\n";
    return result;
}

bool mentions(const std::string& message, const std::string& text) {
    return message.find(text) != std::string::npos;
}

// A folder of its own under the temporary directory, removed afterwards.
class TempFolder {
public:
    TempFolder() : path_(fs::temp_directory_path() / ("bounce_gltf_budget_" + std::to_string(::getpid()))) {
        fs::remove_all(path_);
        fs::create_directories(path_ / "scene");
    }
    ~TempFolder() { fs::remove_all(path_); }
    const fs::path& path() const { return path_; }
    fs::path write(const fs::path& relative, const std::string& text) const {
        std::ofstream(path_ / relative, std::ios::binary) << text;
        return path_ / relative;
    }

private:
    fs::path path_;
};

// ---- JSON nesting

std::string deeply_nested(int depth) {
    return R"({"asset": {"version": "2.0", "extras": )" + std::string(static_cast<std::size_t>(depth), '[') +
           std::string(static_cast<std::size_t>(depth), ']') + "}}";
}

TEST(GltfBudget, DeepJsonInAGlbIsRefusedBeforeParsing) {
    std::uint64_t growth = 0;
    const Refusal result = measured_refusal(make_glb(deeply_nested(300000)), "deep", growth);
    EXPECT_EQ(result.type, "InputError");
    EXPECT_TRUE(mentions(result.message, "deep: the JSON nests arrays and objects more than 128 levels deep"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

TEST(GltfBudget, DeepJsonInAGltfFileIsRefused) {
    const TempFolder folder;
    const Refusal result =
        refusal([&] { import_gltf_file(folder.write("scene/deep.gltf", deeply_nested(300000))); });
    EXPECT_EQ(result.type, "InputError");
    EXPECT_TRUE(mentions(result.message, "deep.gltf: the JSON nests arrays and objects more than 128 levels"))
        << result.message;
}

TEST(GltfBudget, BracketsInStringsAndModerateNestingLoad) {
    // Brackets, quotes and backslashes inside strings do not count; 100 levels is within the limit.
    const std::string text =
        R"({"asset": {"version": "2.0", "extras": {"note": "[[[{{{ \"[[[ \\", "deep": )" +
        std::string(100, '[') + std::string(100, ']') + "}}, \"x\": \"" + std::string(1000, '[') + "\"}";
    const TempFolder folder;
    EXPECT_NO_THROW(import_gltf_file(folder.write("scene/strings.gltf", text)));
    EXPECT_NO_THROW(import_glb_memory(make_glb(text), "strings"));
}

// ---- the scene-size budget

TEST(GltfBudget, HugeAccessorWithoutBufferViewIsRefused) {
    // 300 bytes: an accessor of 2^28 - 1 vertices that has no bufferView (all zeros), read as
    // POSITION by four primitives. Loading it would take tens of GiB.
    const std::string text =
        R"({"asset":{"version":"2.0"},"accessors":[{"componentType":5126,"count":268435455,"type":"VEC3"}],)"
        R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}},{"attributes":{"POSITION":0}},)"
        R"({"attributes":{"POSITION":0}},{"attributes":{"POSITION":0}}]}]})";
    const std::vector<std::uint8_t> glb = make_glb(text);
    EXPECT_LT(glb.size(), 320u);
    std::uint64_t growth = 0;
    const Refusal result = measured_refusal(glb, "huge", growth);
    EXPECT_EQ(result.type, "ResourceExhausted");
    // 268435455 x 12 bytes x 4 primitives; each primitive also gets 32 bytes a vertex of normals,
    // tangents and indices.
    EXPECT_TRUE(
        mentions(result.message, "huge: the scene decodes to 44.0 GiB, more than its budget of 2.0 GiB"))
        << result.message;
    EXPECT_TRUE(
        mentions(result.message, "the largest part is accessor 0 (POSITION of 4 primitives) at 12.0 GiB"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

TEST(GltfBudget, ManyImagesOfAHugeDeclaredSizeAreRefusedFromTheirHeaders) {
    // 32 images sharing one PNG that declares 16384 x 16384: 1.3 GiB each once decoded, with mipmaps.
    std::uint64_t growth = 0;
    const Refusal result = measured_refusal(glb_with_images(png_declaring(16384), 32), "images", growth);
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "images: the scene decodes to 42.7 GiB")) << result.message;
    EXPECT_TRUE(mentions(result.message, "the largest part is image 0 (16384x16384) at 1.3 GiB"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

TEST(GltfBudget, OneHugeDeclaredImageWithinTheBudgetIsOnlyDecoded) {
    // One such image fits the default budget; this one has no pixel data, so decoding it fails and
    // the material keeps its factor, with a warning.
    const Scene scene = import_glb_memory(glb_with_images(png_declaring(16384), 1), "one");
    EXPECT_TRUE(scene.textures.empty());
    EXPECT_FALSE(scene.materials.at(0).base_color_texture.valid());
    // Past the per-side limit, the header alone decides: no decode, a warning.
    const Scene wide = import_glb_memory(glb_with_images(png_declaring(16385), 1), "wide");
    bool warned = false;
    for (const std::string& warning : wide.warnings) {
        warned |= mentions(warning, "16385x16385 pixels exceeds the limit of 16384 per side");
    }
    EXPECT_TRUE(warned);
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
    std::ifstream stream(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
}

TEST(GltfBudget, AnImageUsedByManyMaterialsIsDecodedAndCountedOnce) {
    // One 211 x 211 image (232 KiB with mipmaps) used by 32 materials fits a 300 KB budget.
    const std::vector<std::uint8_t> png = read_bytes(assimp_dir / "BoxTextured-glTF/CesiumLogoFlat.png");
    ASSERT_FALSE(png.empty());
    json document = {{"asset", {{"version", "2.0"}}},
                     {"buffers", {{{"byteLength", png.size()}}}},
                     {"bufferViews", {{{"buffer", 0}, {"byteLength", png.size()}}}},
                     {"images", {{{"bufferView", 0}, {"mimeType", "image/png"}}}},
                     {"textures", {{{"source", 0}}}},
                     {"materials", json::array()}};
    for (int i = 0; i < 32; ++i) {
        document["materials"].push_back({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    }
    const Scene scene = import_glb_memory(make_glb(document.dump(), png), "shared", ImportLimits{300000});
    ASSERT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.textures[0].width, 211);
    for (const Material& material : scene.materials) EXPECT_EQ(material.base_color_texture.texture, 0);
}

TEST(GltfBudget, ALegitimateSceneLoadsUnderTheDefaultBudgetAndNotUnderATinyOne) {
    const fs::path box = assimp_dir / "BoxTextured-glTF/BoxTextured.gltf";
    EXPECT_EQ(import_gltf_file(box).objects.size(), 1u);
    const Refusal result = refusal([&] { import_gltf_file(box, ImportLimits{100000}); });
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "BoxTextured.gltf: the scene decodes to 233."))
        << result.message;
    EXPECT_TRUE(mentions(result.message, "more than its budget of 97.7 KiB")) << result.message;
    EXPECT_TRUE(
        mentions(result.message, "the largest part is image 0 'CesiumLogoFlat.png' (211x211) at 231.9 KiB"))
        << result.message;
}

// ---- URIs of a file import stay in its folder

std::string scene_with_uris(const std::string& buffer_uri, const std::string& image_uri) {
    json document = {{"asset", {{"version", "2.0"}}}};
    if (!buffer_uri.empty()) document["buffers"] = {{{"uri", buffer_uri}, {"byteLength", 4}}};
    if (!image_uri.empty()) document["images"] = {{{"uri", image_uri}}};
    return document.dump();
}

TEST(GltfBudget, UrisLeadingOutOfTheFolderAreRefused) {
    const TempFolder folder;
    folder.write("outside.bin", "abcd");
    folder.write("scene/inside.bin", "abcd");
    fs::create_symlink(folder.path() / "outside.bin", folder.path() / "scene/link.bin");
    const std::array<std::array<std::string, 3>, 6> cases = {{
        {"../outside.bin", "", "buffers[0].uri '../outside.bin' leads outside the folder of the glTF file"},
        {"", "%2e%2e/outside.bin", "images[0].uri '%2e%2e/outside.bin' leads outside the folder"},
        {"sub/../../outside.bin", "", "buffers[0].uri 'sub/../../outside.bin' leads outside the folder"},
        {"link.bin", "", "buffers[0].uri 'link.bin' leads outside the folder"},
        {"data:x/../../outside.bin", "", "buffers[0].uri 'data:x/../../outside.bin' leads outside"},
        {(folder.path() / "scene/inside.bin").string(), "", "is not a relative path"},
    }};
    for (const auto& [buffer_uri, image_uri, expected] : cases) {
        const fs::path file = folder.write("scene/escape.gltf", scene_with_uris(buffer_uri, image_uri));
        const Refusal result = refusal([&] { import_gltf_file(file); });
        EXPECT_EQ(result.type, "InputError") << buffer_uri << image_uri;
        EXPECT_TRUE(mentions(result.message, "escape.gltf: ")) << result.message;
        EXPECT_TRUE(mentions(result.message, expected)) << result.message;
    }
    // Inside the folder, by a plain name, through `..` that stays inside, or as data:, all load.
    fs::create_directories(folder.path() / "scene/sub");
    const char* const data_uri = "data:application/octet-stream;base64,YWJjZA==";
    for (const char* uri : {"inside.bin", "sub/../inside.bin", data_uri}) {
        const fs::path file = folder.write("scene/fine.gltf", scene_with_uris(uri, ""));
        EXPECT_NO_THROW(import_gltf_file(file)) << uri;
    }
}

}  // namespace
}  // namespace bounce::scene
