// The importer's limits against hostile files: JSON nesting, the scene-size budget and the folder
// external files must lie in. Each hostile input is built here in memory; the memory attacks are
// also measured, by the growth of the process's peak resident size while they are refused.
#include "renderer/scene/gltf_import.hpp"
#include "support/hostile_gltf.hpp"

#include "renderer/base/error.hpp"
#include "renderer/image/codec.hpp"

#include <gtest/gtest.h>
#include <zlib.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
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

// ---- building hostile files: tests/support/hostile_gltf.hpp

using namespace bounce::test::hostile;

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

// The importer's count of an upload's size, to the byte: the smallest budget under which it is not
// refused as ResourceExhausted (it may still fail to decode: a header-only image only warns).
std::uint64_t counted_size(const std::vector<std::uint8_t>& glb) {
    auto refused_at = [&](std::uint64_t budget) {
        try {
            import_glb_memory(glb, "counted", ImportLimits{budget});
        } catch (const ResourceExhausted&) {
            return true;
        }
        return false;
    };
    if (!refused_at(0)) return 0;
    std::uint64_t refused = 0;
    std::uint64_t accepted = std::uint64_t{1} << 40;
    if (refused_at(accepted)) {
        ADD_FAILURE() << "refused even under 1 TiB";
        return accepted;
    }
    while (accepted - refused > 1) {
        const std::uint64_t middle = refused + (accepted - refused) / 2;
        (refused_at(middle) ? refused : accepted) = middle;
    }
    return accepted;
}

// A GL texture of 4 bytes a texel with all its mipmaps.
std::uint64_t mip_chain_bytes(std::uint64_t width, std::uint64_t height) {
    std::uint64_t bytes = width * height * 4;
    while (width > 1 || height > 1) {
        width = std::max<std::uint64_t>(width / 2, 1);
        height = std::max<std::uint64_t>(height / 2, 1);
        bytes += width * height * 4;
    }
    return bytes;
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
    // 32 images sharing one PNG that declares 16384 x 16384 RGBA: each makes a Texture of 1 GiB and
    // a GL texture of 1.3 GiB with its mipmaps.
    std::uint64_t growth = 0;
    const Refusal result = measured_refusal(glb_with_images(png_declaring(16384), 32), "images", growth);
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "images: the scene decodes to 74.7 GiB")) << result.message;
    EXPECT_TRUE(mentions(result.message, "the largest part is image 0 (16384x16384, 8-bit RGBA PNG) at 2.3 GiB"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

// A 16 x 16 RGBA PNG whose image data is `inflated` zero bytes, deflated: 1040 bytes are its rows.
std::vector<std::uint8_t> png_inflating_to(std::size_t inflated) {
    std::vector<std::uint8_t> png = png_declaring(16);
    const std::vector<std::uint8_t> zeros(inflated, 0);
    uLongf size = compressBound(static_cast<uLong>(zeros.size()));
    std::vector<std::uint8_t> data(size);
    EXPECT_EQ(compress2(data.data(), &size, zeros.data(), static_cast<uLong>(zeros.size()), 9), Z_OK);
    data.resize(size);
    std::vector<std::uint8_t> chunk;
    put_u32_be(chunk, static_cast<std::uint32_t>(data.size()));
    chunk.insert(chunk.end(), {'I', 'D', 'A', 'T'});
    chunk.insert(chunk.end(), data.begin(), data.end());
    put_u32_be(chunk, crc32(chunk.data() + 4, chunk.size() - 4));
    png.insert(png.end() - 12, chunk.begin(), chunk.end());  // before IEND
    return png;
}

TEST(GltfBudget, APngWhoseDataInflatesPastItsRowsIsNotDecoded) {
    // The rows of a 16 x 16 RGBA image take 1040 bytes: that much decodes.
    const Scene fits = import_glb_memory(glb_with_images(png_inflating_to(16 * (1 + 16 * 4)), 1), "fits");
    ASSERT_EQ(fits.textures.size(), 1u);
    EXPECT_EQ(fits.textures[0].width, 16);
    // 64 MiB of data in a file of about 64 KiB: the decoder would grow its buffer to hold all of it.
    const std::vector<std::uint8_t> bomb = glb_with_images(png_inflating_to(std::size_t{64} << 20), 1);
    EXPECT_LT(bomb.size(), 100000u);
    Scene scene;
    const std::uint64_t growth = peak_growth([&] { scene = import_glb_memory(bomb, "bomb"); });
    EXPECT_TRUE(scene.textures.empty());
    bool warned = false;
    for (const std::string& warning : scene.warnings) warned |= mentions(warning, "inflates past the 1040 bytes");
    EXPECT_TRUE(warned);
    // The check inflates into a 64 KiB scratch buffer; decoding would have taken over 64 MiB.
    EXPECT_LT(growth, std::uint64_t{16} << 20);
}

TEST(GltfBudget, OneHugeDeclaredImageWithinTheBudgetIsOnlyDecoded) {
    // One such image takes 2.3 GiB at the peak of its load (its Texture and GL texture), past the
    // default budget; under 3 GiB it is decoded. This one has no pixel data, so decoding it fails
    // and the material keeps its factor, with a warning.
    EXPECT_EQ(refusal([] { import_glb_memory(glb_with_images(png_declaring(16384), 1), "one"); }).type,
              "ResourceExhausted");
    const Scene scene =
        import_glb_memory(glb_with_images(png_declaring(16384), 1), "one", ImportLimits{std::uint64_t{3} << 30});
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
    // One 211 x 211 image (405 KiB at the peak: its Texture and GL texture with mipmaps) used by 32
    // materials fits a 420 KB budget.
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
    const Scene scene = import_glb_memory(make_glb(document.dump(), png), "shared", ImportLimits{420000});
    ASSERT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.textures[0].width, 211);
    for (const Material& material : scene.materials) EXPECT_EQ(material.base_color_texture.texture, 0);
}

TEST(GltfBudget, ALegitimateSceneLoadsUnderTheDefaultBudgetAndNotUnderATinyOne) {
    const fs::path box = assimp_dir / "BoxTextured-glTF/BoxTextured.gltf";
    EXPECT_EQ(import_gltf_file(box).objects.size(), 1u);
    const Refusal result = refusal([&] { import_gltf_file(box, ImportLimits{100000}); });
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "BoxTextured.gltf: the scene decodes to 406.5 KiB"))
        << result.message;
    EXPECT_TRUE(mentions(result.message, "more than its budget of 97.7 KiB")) << result.message;
    EXPECT_TRUE(
        mentions(result.message,
                 "the largest part is image 0 'CesiumLogoFlat.png' (211x211, 8-bit palette PNG) at 404.9 KiB"))
        << result.message;
}

// ---- what an image counts, from its header

TEST(GltfBudget, SixteenBitPngsCountTwoBytesASampleWhileDecoded) {
    constexpr std::uint64_t side = 1024;
    constexpr std::uint64_t pixels = side * side;
    const std::uint64_t eight = counted_size(glb_with_images(png_declaring(side, side, 8, 6), 1));
    const std::uint64_t sixteen = counted_size(glb_with_images(png_declaring(side, side, 16, 6), 1));
    // Decoding an 8-bit RGBA PNG holds at most 8 bytes a pixel and 1 a row: its inflated rows (4
    // bytes a pixel, a filter byte a row) and the image they are unfiltered into (4), then that and
    // tinygltf's copy. The Texture made from it (4 bytes a pixel) and its GL texture with mipmaps
    // hold more, and set the count.
    EXPECT_EQ(eight, pixels * 4 + mip_chain_bytes(side, side));
    // At 16 bits every sample takes two bytes while decoded: twice what the 8-bit decode holds,
    // 16 bytes a pixel and 1 a row, now past the Texture and GL texture (the same as for 8 bits).
    EXPECT_EQ(sixteen, 2 * (pixels * 8) + side);
    EXPECT_GT(sixteen, eight);
}

TEST(GltfBudget, AnImageUsedInTwoColourSpacesCountsTwoTextures) {
    // One 1024 x 1024 RGBA image as base colour (sRGB) and as metallic-roughness (linear) becomes
    // two Textures and two GL textures; it is decoded once.
    constexpr std::uint64_t side = 1024;
    const std::vector<std::uint8_t> png = png_declaring(side, side, 8, 6);
    json document = {{"asset", {{"version", "2.0"}}},
                     {"buffers", {{{"byteLength", png.size()}}}},
                     {"bufferViews", {{{"buffer", 0}, {"byteLength", png.size()}}}},
                     {"images", {{{"bufferView", 0}, {"mimeType", "image/png"}}}},
                     {"textures", {{{"source", 0}}}},
                     {"materials",
                      {{{"pbrMetallicRoughness",
                         {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}}}}}}}}};
    EXPECT_EQ(counted_size(make_glb(document.dump(), png)), 2 * (side * side * 4 + mip_chain_bytes(side, side)));
}

TEST(GltfBudget, AJpegIsCountedFromItsFrameHeader) {
    // 400 x 300, progressive, every component at full size: decoding holds three planes (1 byte a
    // sample) and their coefficients (2 bytes a sample), a line buffer each, and the 4-channel
    // result (and a byte): 13 bytes a pixel, past the Texture and GL texture.
    constexpr std::uint64_t width = 400;
    constexpr std::uint64_t height = 300;
    constexpr std::uint64_t pixels = width * height;
    const std::uint64_t progressive = counted_size(glb_with_images(jpeg_declaring(width, height, 0xC2, 0x11), 1));
    const std::uint64_t plane = width * 304;  // 300 rows padded to whole blocks of 8
    EXPECT_EQ(progressive, pixels * 4 + 1 + 3 * (plane + 15) + 3 * (2 * plane + 15) + 3 * (width + 3));
    // Baseline and 4:2:0 (chroma planes a quarter of the pixels, all planes padded to 16 x 16
    // blocks): decoding holds less than the Texture and GL texture.
    const std::uint64_t baseline = counted_size(glb_with_images(jpeg_declaring(width, height, 0xC0, 0x22), 1));
    EXPECT_EQ(baseline, pixels * 4 + mip_chain_bytes(width, height));
    // Within its count it is decoded: stb_image makes a frame without scans a grey image.
    const Scene scene =
        import_glb_memory(glb_with_images(jpeg_declaring(width, height, 0xC2, 0x11), 1), "jpeg", ImportLimits{progressive});
    ASSERT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.textures[0].width, 400);
}

TEST(GltfBudget, AJpegPastTheBudgetIsRefusedFromItsHeaderWithoutDecoding) {
    // Decoding it would take 595 MiB (stb_image decodes a frame without scans as a grey image);
    // the peak resident size shows that nothing was.
    std::uint64_t growth = 0;
    Refusal result;
    growth = peak_growth([&] {
        result = refusal([&] {
            import_glb_memory(glb_with_images(jpeg_declaring(8000, 6000, 0xC2, 0x11), 1), "photo",
                              ImportLimits{64 << 20});
        });
    });
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "photo: the scene decodes to 595.1 MiB, more than its budget of 64.0 MiB"))
        << result.message;
    EXPECT_TRUE(mentions(result.message, "the largest part is image 0 (8000x6000, 3-component progressive JPEG)"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

TEST(GltfBudget, APngDeclaring16384SquaredIsRefusedUnderASmallBudgetNamingIt) {
    std::uint64_t growth = 0;
    Refusal result;
    growth = peak_growth([&] {
        result = refusal([&] {
            import_glb_memory(glb_with_images(png_declaring(16384, 16384, 16, 2), 1), "big", ImportLimits{64 << 20});
        });
    });
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message, "big: the scene decodes to ")) << result.message;
    EXPECT_TRUE(mentions(result.message, "more than its budget of 64.0 MiB")) << result.message;
    EXPECT_TRUE(mentions(result.message, "the largest part is image 0 (16384x16384, 16-bit RGB PNG)"))
        << result.message;
    EXPECT_LT(growth, max_peak_growth);
}

TEST(GltfBudget, ImagesTheDecoderCannotReadAreNotCounted) {
    // A lossless JPEG (SOF3), a 12-bit one and a 16-bit palette PNG: stb_image refuses all three, so
    // they only warn, and count nothing.
    std::vector<std::uint8_t> twelve_bit = jpeg_declaring(4000, 3000, 0xC0, 0x11);
    twelve_bit[24] = 12;  // the frame header's precision
    const std::array<std::pair<std::vector<std::uint8_t>, std::string>, 3> cases = {{
        {jpeg_declaring(4000, 3000, 0xC3, 0x11), "a JPEG coded as SOF3 (lossless, hierarchical or arithmetic)"},
        {twelve_bit, "a 12-bit JPEG of 3 components cannot be decoded"},
        {png_declaring(4000, 3000, 16, 3), "a PNG of bit depth 16, colour type 3"},
    }};
    for (const auto& [image, expected] : cases) {
        const std::vector<std::uint8_t> glb = glb_with_images(image, 1);
        EXPECT_EQ(counted_size(glb), 0u) << expected;
        const Scene scene = import_glb_memory(glb, "unreadable", ImportLimits{1024});
        bool warned = false;
        for (const std::string& warning : scene.warnings) warned |= mentions(warning, expected);
        EXPECT_TRUE(warned) << expected;
    }
}

TEST(GltfBudget, EncodedPngsAndJpegsAreReadAndCountedFromTheirHeaders) {
    // Real files, as an encoder writes them (more chunks and segments than the header alone).
    image::Frame frame;
    frame.width = 48;
    frame.height = 32;
    frame.display_rgba8.resize(48 * 32 * 4);
    for (std::size_t i = 0; i < frame.display_rgba8.size(); ++i) {
        frame.display_rgba8[i] = static_cast<std::uint8_t>(i * 7);
    }
    for (const image::ImageFormat format : {image::ImageFormat::png, image::ImageFormat::jpeg}) {
        const std::vector<std::uint8_t> glb = glb_with_images(image::encode_image(frame, format), 1);
        const std::uint64_t size = counted_size(glb);
        EXPECT_GE(size, std::uint64_t{48 * 32 * 4} + mip_chain_bytes(48, 32));
        const Scene scene = import_glb_memory(glb, "encoded", ImportLimits{size});
        ASSERT_EQ(scene.textures.size(), 1u) << image::image_format_name(format);
        EXPECT_EQ(scene.textures[0].width, 48);
        EXPECT_EQ(scene.textures[0].height, 32);
    }
}

// ---- strips, fans and sparse accessors

// A mesh of one primitive of `mode` whose POSITION accessor has `vertices` elements and no
// bufferView (all zeros).
std::string primitive_scene(int mode, std::uint64_t vertices) {
    return json{{"asset", {{"version", "2.0"}}},
                {"accessors", {{{"componentType", 5126}, {"count", vertices}, {"type", "VEC3"}}}},
                {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"mode", mode}}}}}}}}
        .dump();
}

TEST(GltfBudget, StripsAndFansCountTheTriangleListsTheyBecome) {
    constexpr std::uint64_t vertices = 1000;
    // Positions (12 bytes a vertex), the normals and tangents made (28) and the index list made (4).
    const std::uint64_t list = counted_size(make_glb(primitive_scene(4, 999)));
    EXPECT_EQ(list, 999 * (12 + 28 + 4));
    // A strip or fan of n vertices also becomes a list of n - 2 triangles (12 bytes each).
    for (const int mode : {5, 6}) {
        const std::vector<std::uint8_t> glb = make_glb(primitive_scene(mode, vertices));
        EXPECT_EQ(counted_size(glb), vertices * (12 + 28 + 4) + (vertices - 2) * 12) << mode;
        EXPECT_NO_THROW(import_glb_memory(glb, "strip", ImportLimits{counted_size(glb)})) << mode;
    }
    // 2^28 - 1 vertices in a 200-byte file.
    const Refusal result = refusal([] { import_glb_memory(make_glb(primitive_scene(5, 268435455)), "strip"); });
    EXPECT_EQ(result.type, "ResourceExhausted");
    EXPECT_TRUE(mentions(result.message,
                         "the largest part is the normals, tangents and indices made for mesh 0 primitive 0 at 11.0 GiB"))
        << result.message;
}

TEST(GltfBudget, SparseAccessorsAreRefusedCleanly) {
    // A sparse POSITION accessor replacing one of its three vertices: not supported, refused by name.
    std::vector<std::uint8_t> bin(16, 0);
    json document = {
        {"asset", {{"version", "2.0"}}},
        {"buffers", {{{"byteLength", bin.size()}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteLength", 4}}, {{"buffer", 0}, {"byteOffset", 4}, {"byteLength", 12}}}},
        {"accessors",
         {{{"componentType", 5126},
           {"count", 3},
           {"type", "VEC3"},
           {"sparse",
            {{"count", 1},
             {"indices", {{"bufferView", 0}, {"componentType", 5125}}},
             {"values", {{"bufferView", 1}}}}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}}};
    const Refusal small = refusal([&] { import_glb_memory(make_glb(document.dump(), bin), "sparse"); });
    EXPECT_EQ(small.type, "InputError");
    EXPECT_TRUE(mentions(small.message, "sparse: mesh 0 primitive 0 POSITION: sparse accessor 0 is not supported"))
        << small.message;
    // One that declares 2^28 - 1 elements is counted as dense, and refused before anything is read.
    document["accessors"][0]["count"] = 268435455;
    const Refusal huge = refusal([&] { import_glb_memory(make_glb(document.dump(), bin), "sparse"); });
    EXPECT_EQ(huge.type, "ResourceExhausted") << huge.message;
}

// ---- numbers past their ranges

// One triangle at +-`coordinate` under node 0, with `extra` merged into the document (cameras,
// lights, more nodes); node 1, when `extra` adds it, is in the scene too.
std::vector<std::uint8_t> triangle_with(float coordinate, const json& extra = json::object()) {
    std::vector<std::uint8_t> bin;
    for (const float value : {-coordinate, -coordinate, 0.0f, coordinate, 0.0f, 0.0f, 0.0f, coordinate, coordinate}) {
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
        bin.insert(bin.end(), bytes, bytes + 4);
    }
    json document = {{"asset", {{"version", "2.0"}}},
                     {"buffers", {{{"byteLength", bin.size()}}}},
                     {"bufferViews", {{{"buffer", 0}, {"byteLength", bin.size()}}}},
                     {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}}}},
                     {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
                     {"nodes", {{{"name", "tri"}, {"mesh", 0}}}},
                     {"scenes", {{{"nodes", {0}}}}}};
    document.merge_patch(extra);
    if (document["nodes"].size() > 1) document["scenes"][0]["nodes"] = {0, 1};
    return make_glb(document.dump(), bin);
}

json light_node(const json& light, const json& translation = {0, 0, 1}) {
    return {{"extensionsUsed", {"KHR_lights_punctual"}},
            {"extensions", {{"KHR_lights_punctual", {{"lights", {light}}}}}},
            {"nodes", {{{"name", "tri"}, {"mesh", 0}},
                       {{"name", "lamp"}, {"translation", translation},
                        {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}}}};
}

json camera_node(const json& perspective, const json& translation = {0, 0, 3}) {
    return {{"cameras", {{{"type", "perspective"}, {"perspective", perspective}}}},
            {"nodes", {{{"name", "tri"}, {"mesh", 0}}, {{"name", "eye"}, {"camera", 0}, {"translation", translation}}}}};
}

TEST(GltfBudget, NumbersPastTheirRangesAreRefused) {
    const json pass = {{"yfov", 0.8}, {"znear", 0.1}};
    const std::array<std::pair<std::vector<std::uint8_t>, std::string>, 8> cases = {{
        // Past the range of a float: converting them would be undefined behaviour.
        {triangle_with(1, {{"nodes", {{{"name", "tri"}, {"mesh", 0}, {"translation", {1e39, 0, 0}}}}}}),
         "node 0 translation is 1e+39, past the range of a float"},
        {triangle_with(1, {{"materials", {{{"emissiveFactor", {1, 1, 1e39}}}}}}),
         "material 0 ('') emissiveFactor is 1e+39, past the range of a float"},
        // Each in range, their product not.
        {triangle_with(1, {{"extensionsUsed", {"KHR_materials_emissive_strength"}},
                           {"materials", {{{"emissiveFactor", {1e30, 0, 0}},
                                           {"extensions", {{"KHR_materials_emissive_strength",
                                                            {{"emissiveStrength", 1e30}}}}}}}}}),
         "material 0 (''): its emissive factor times its strength is past the range of a float"},
        // The ranges light.set allows.
        {triangle_with(1, light_node({{"type", "point"}, {"intensity", 1e13}})),
         "light 0 ('') has the intensity 1e+13, outside [0, 1e+12]"},
        {triangle_with(1, light_node({{"type", "point"}, {"color", {1, -1, 1}}})), "has the color vec3(1.000000, -1.000000"},
        // Distances a projection divides by.
        {triangle_with(1, camera_node({{"yfov", 0.8}, {"znear", 1e16}})),
         "camera 0 ('') has the znear 1e+16, past the limit of 1e+15 m"},
        // Views look from a position to the position plus a unit vector: past 2^24 m they are NaN.
        {triangle_with(1, camera_node(pass, {0, 0, 2e7})), "camera 'eye' lies at vec3(0.000000, 0.000000, 20000000.000000)"},
        {triangle_with(1, light_node({{"type", "point"}}, {-3e7, 0, 0})), "light 'lamp' lies at vec3(-30000000.000000"},
    }};
    for (const auto& [glb, expected] : cases) {
        const Refusal result = refusal([&] { import_glb_memory(glb, "numbers"); });
        EXPECT_EQ(result.type, "InputError") << expected;
        EXPECT_TRUE(mentions(result.message, expected)) << result.message;
    }
    // At the edges of those ranges they load.
    EXPECT_NO_THROW(import_glb_memory(triangle_with(1, light_node({{"type", "point"}, {"intensity", 1e12},
                                                                   {"color", {1e6, 0, 1e6}}},
                                                                  {1e7, -1e7, 1e7})),
                                      "edges"));
    EXPECT_NO_THROW(import_glb_memory(triangle_with(1, camera_node({{"yfov", 0.8}, {"znear", 1e14}}, {1e7, 0, 0})),
                                      "edges"));
}

TEST(GltfBudget, ObjectsPastTheirReachAreRefused) {
    // Finite floats whose bounds overflow, or that a node scales past the limit.
    const Refusal far = refusal([] { import_glb_memory(triangle_with(3e38f, camera_node({{"yfov", 0.8}, {"znear", 0.1}})), "far"); });
    EXPECT_EQ(far.type, "InputError");
    EXPECT_TRUE(mentions(far.message, "far: object 'tri' (its world bounds) lies at")) << far.message;
    EXPECT_TRUE(mentions(far.message, "past the limit of 1e+15 m from the origin on an axis")) << far.message;
    const json scaled = {{"nodes", {{{"name", "tri"}, {"mesh", 0}, {"scale", {1e12, 1e12, 1e12}}},
                                    {{"name", "eye"}, {"camera", 0}, {"translation", {0, 0, 3}}}}},
                         {"cameras", {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}}}};
    EXPECT_TRUE(mentions(refusal([&] { import_glb_memory(triangle_with(1e4f, scaled), "scaled"); }).message,
                         "object 'tri' (its world bounds) lies at"));
    // Within it, with a camera of its own, a scene loads; without one, a default camera that frames
    // it would stand past max_eye_coordinate.
    EXPECT_NO_THROW(import_glb_memory(triangle_with(1e14f, camera_node({{"yfov", 0.8}, {"znear", 0.1}})), "large"));
    const Refusal unframed = refusal([] { import_glb_memory(triangle_with(1e14f), "unframed"); });
    EXPECT_EQ(unframed.type, "InputError");
    EXPECT_TRUE(mentions(unframed.message, "the file has no camera, and one that frames the whole scene would stand"))
        << unframed.message;
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

TEST(GltfBudget, UrisAreDecodedAsTinygltfDecodesThemAndInvalidEscapesRefused) {
    const TempFolder folder;
    folder.write("scene/inside.bin", "abcd");
    folder.write("scene/with space.bin", "abcd");
    // tinygltf reads "%zz" as a NUL byte and "%2z" as a space; such URIs are refused, whatever
    // they would lead to.
    for (const std::string uri : {"inside.bin%zz", "sub/../..%zz/x.bin", "with%2zspace.bin", "%%2e"}) {
        const fs::path file = folder.write("scene/escape.gltf", scene_with_uris(uri, ""));
        const Refusal result = refusal([&] { import_gltf_file(file); });
        EXPECT_EQ(result.type, "InputError") << uri;
        EXPECT_TRUE(mentions(result.message, "buffers[0].uri '" + uri + "' has the invalid percent escape"))
            << result.message;
    }
    // Valid escapes, '+' for a space and a '%' too near the end to be an escape read as tinygltf
    // reads them.
    for (const std::string uri : {"in%73ide.bin", "with+space.bin", "with%20space.bin"}) {
        const fs::path file = folder.write("scene/fine.gltf", scene_with_uris(uri, ""));
        EXPECT_NO_THROW(import_gltf_file(file)) << uri;
    }
    folder.write("scene/x%4", "abcd");
    EXPECT_NO_THROW(import_gltf_file(folder.write("scene/fine.gltf", scene_with_uris("x%4", "")))) << "x%4";
}

}  // namespace
}  // namespace bounce::scene
