#include "support/hostile_gltf.hpp"

#include <nlohmann/json.hpp>

namespace bounce::test::hostile {

using nlohmann::json;

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
    for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// A binary glTF: the 12-byte header, the JSON chunk (padded with spaces) and, when `bin` is not
// empty, the BIN chunk (padded with zeros).
std::vector<std::uint8_t> make_glb(std::string json_text, std::vector<std::uint8_t> bin) {
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

// A PNG of a few dozen bytes that declares `width` x `height` pixels of `colour_type` (6: RGBA) at
// `bit_depth`: a valid IHDR and IEND, no pixel data. Its header is all the importer reads before
// deciding.
std::vector<std::uint8_t> png_declaring(std::uint32_t width, std::uint32_t height, std::uint8_t bit_depth,
                                        std::uint8_t colour_type) {
    std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    auto chunk = [&](const char* type, const std::vector<std::uint8_t>& data) {
        put_u32_be(png, static_cast<std::uint32_t>(data.size()));
        const std::size_t start = png.size();
        png.insert(png.end(), type, type + 4);
        png.insert(png.end(), data.begin(), data.end());
        put_u32_be(png, crc32(png.data() + start, png.size() - start));
    };
    std::vector<std::uint8_t> header;
    put_u32_be(header, width);
    put_u32_be(header, height);
    header.insert(header.end(), {bit_depth, colour_type, 0, 0, 0});  // deflate, adaptive filters, no interlace
    chunk("IHDR", header);
    chunk("IEND", {});
    return png;
}

std::vector<std::uint8_t> png_declaring(std::uint32_t side) { return png_declaring(side, side, 8, 6); }

// A JPEG of a few dozen bytes: SOI, a JFIF APP0 segment, a frame header with the marker `frame`
// (0xC0 baseline, 0xC2 progressive, ...) declaring `width` x `height` in three components sampled
// by `luma` (horizontal << 4 | vertical; chroma 1 x 1), and EOI. No tables, no scan.
std::vector<std::uint8_t> jpeg_declaring(std::uint16_t width, std::uint16_t height, std::uint8_t frame,
                                         std::uint8_t luma) {
    std::vector<std::uint8_t> jpeg = {0xFF, 0xD8, 0xFF, 0xE0, 0, 16, 'J', 'F', 'I', 'F', 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};
    const auto byte = [](unsigned value) { return static_cast<std::uint8_t>(value & 0xFF); };
    jpeg.insert(jpeg.end(), {0xFF, frame, 0, 17, 8, byte(height >> 8), byte(height), byte(width >> 8),
                             byte(width), 3, 1, luma, 0, 2, 0x11, 1, 3, 0x11, 1});
    jpeg.insert(jpeg.end(), {0xFF, 0xD9});
    return jpeg;
}

// A GLB whose `images` are `image_count` entries all pointing at one bufferView holding `png` (or
// any image), each used by its own texture and material.
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

std::string deeply_nested(int depth) {
    return R"({"asset": {"version": "2.0", "extras": )" + std::string(static_cast<std::size_t>(depth), '[') +
           std::string(static_cast<std::size_t>(depth), ']') + "}}";
}

}  // namespace bounce::test::hostile
