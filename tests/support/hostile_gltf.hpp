// Hostile glTF files built in memory, for the importer's unit tests and the daemon's integration
// tests: binary containers, images whose headers declare what their data does not hold, JSON nested
// past any sensible depth.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace bounce::test::hostile {

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value);     // little-endian
void put_u32_be(std::vector<std::uint8_t>& out, std::uint32_t value);  // big-endian (PNG)
std::uint32_t crc32(const std::uint8_t* bytes, std::size_t size);     // PNG's chunk CRC

// A binary glTF: the 12-byte header, the JSON chunk (padded with spaces) and, when `bin` is not
// empty, the BIN chunk (padded with zeros).
std::vector<std::uint8_t> make_glb(std::string json_text, std::vector<std::uint8_t> bin = {});

// A PNG of a few dozen bytes that declares width x height pixels of `bit_depth` and `colour_type`:
// a valid IHDR and IEND, no pixel data. Its header is all the importer reads before deciding.
std::vector<std::uint8_t> png_declaring(std::uint32_t width, std::uint32_t height, std::uint8_t bit_depth,
                                        std::uint8_t colour_type);
std::vector<std::uint8_t> png_declaring(std::uint32_t side);  // RGBA, 8 bits

// A JPEG of a few dozen bytes declaring width x height in three components (see hostile_gltf.cpp).
std::vector<std::uint8_t> jpeg_declaring(std::uint16_t width, std::uint16_t height, std::uint8_t frame,
                                         std::uint8_t luma);

// A GLB whose `images` are `image_count` entries all pointing at one bufferView holding `png` (or
// any image), each used by its own texture and material.
std::vector<std::uint8_t> glb_with_images(const std::vector<std::uint8_t>& png, int image_count);

// A glTF whose asset.extras nests `depth` arrays.
std::string deeply_nested(int depth);

}  // namespace bounce::test::hostile
