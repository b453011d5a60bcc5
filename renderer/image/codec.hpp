// Image encoding and decoding in memory through OpenImageIO: no temporary files.
#pragma once

#include "renderer/image/frame.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::image {

enum class ImageFormat { png, jpeg, webp, exr };

// "png", "jpeg"/"jpg", "webp", "exr" (case-insensitive); throws InputError naming the value otherwise.
ImageFormat parse_image_format(std::string_view name);
// From a path's extension (.png, .jpg, .jpeg, .webp, .exr); throws InputError otherwise.
ImageFormat image_format_from_path(const std::filesystem::path& path);
std::string_view image_format_name(ImageFormat format);

struct EncodeOptions {
    int jpeg_quality = 90;   // 1..100, JPEG and (lossy) WebP
    bool exr_half = false;   // EXR channels as half instead of float
};

// PNG, JPEG and WebP encode Frame::display_rgba8 (RGBA for PNG, RGB for JPEG and WebP); EXR encodes the linear
// Frame::rgba. Throws Error if the frame lacks the image the format needs or the encoder fails.
std::vector<std::uint8_t> encode_image(const Frame& frame, ImageFormat format,
                                       const EncodeOptions& options = {});

// A decoded image as float channels (8-bit formats are scaled to 0..1 without colour conversion).
struct DecodedImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels;  // width * height * channels, rows top to bottom
    std::string format;         // OpenImageIO's format name, e.g. "png", "openexr"

    float at(int x, int y, int channel) const {
        return pixels[(static_cast<std::size_t>(y) * width + x) * channels + channel];
    }
};

// Decodes PNG, JPEG, WebP or EXR bytes; throws InputError if they are not a readable image.
DecodedImage decode_image(std::span<const std::uint8_t> bytes);

// Writes bytes to a file atomically (temporary file in the same folder, then rename).
void write_file_atomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace bounce::image
