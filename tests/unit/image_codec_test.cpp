#include "renderer/image/codec.hpp"
#include "renderer/image/frame.hpp"

#include "renderer/base/error.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

namespace bounce::image {
namespace {

Frame make_frame(int width, int height) {
    Frame frame;
    frame.width = width;
    frame.height = height;
    frame.rgba.assign(static_cast<std::size_t>(width) * height * 4, 0.0f);
    return frame;
}

// A smooth gradient in the display image; JPEG handles this well, so its error must be small.
Frame gradient_frame(int width, int height) {
    Frame frame = make_frame(width, height);
    frame.display_rgba8.resize(frame.rgba.size());
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 4;
            frame.display_rgba8[i] = static_cast<std::uint8_t>(255 * x / (width - 1));
            frame.display_rgba8[i + 1] = static_cast<std::uint8_t>(255 * y / (height - 1));
            frame.display_rgba8[i + 2] = static_cast<std::uint8_t>(128 + 64 * x / (width - 1));
            frame.display_rgba8[i + 3] = 255;
        }
    }
    return frame;
}

// Mean absolute error, in 8-bit steps over RGB, of a lossy format's round trip.
double lossy_mean_error(const Frame& frame, int quality, ImageFormat format = ImageFormat::jpeg) {
    EncodeOptions options;
    options.jpeg_quality = quality;
    const auto bytes = encode_image(frame, format, options);
    const DecodedImage image = decode_image(bytes);
    EXPECT_EQ(image.width, frame.width);
    EXPECT_EQ(image.height, frame.height);
    EXPECT_EQ(image.channels, 3);
    EXPECT_EQ(image.format, image_format_name(format));
    double sum = 0.0;
    for (int y = 0; y < frame.height; ++y) {
        for (int x = 0; x < frame.width; ++x) {
            const glm::u8vec4 want = frame.display_at(x, y);
            for (int c = 0; c < 3; ++c) sum += std::abs(image.at(x, y, c) * 255.0 - want[c]);
        }
    }
    return sum / (static_cast<double>(frame.width) * frame.height * 3);
}

std::uint32_t bits(float value) {
    std::uint32_t out = 0;
    std::memcpy(&out, &value, sizeof out);
    return out;
}

TEST(ImageCodec, ExrFloatRoundTripIsBitExact) {
    Frame frame = make_frame(13, 7);
    const float specials[] = {0.1f, 1e-30f, 1e30f, -0.0f, 0.0f, -3.75f, 1.0f / 3.0f, 65504.0f, 7e-41f};
    for (std::size_t i = 0; i < frame.rgba.size(); ++i) {
        frame.rgba[i] = (i < std::size(specials)) ? specials[i]
                                                   : std::sin(static_cast<float>(i) * 0.37f) * 10.0f;
    }
    const auto bytes = encode_image(frame, ImageFormat::exr);
    ASSERT_GE(bytes.size(), 4u);
    EXPECT_EQ(bytes[0], 0x76);
    const DecodedImage image = decode_image(bytes);
    EXPECT_EQ(image.format, "openexr");
    ASSERT_EQ(image.width, 13);
    ASSERT_EQ(image.height, 7);
    ASSERT_EQ(image.channels, 4);
    ASSERT_EQ(image.pixels.size(), frame.rgba.size());
    for (std::size_t i = 0; i < frame.rgba.size(); ++i) {
        ASSERT_EQ(bits(image.pixels[i]), bits(frame.rgba[i])) << "value " << i << " = " << frame.rgba[i];
    }
}

TEST(ImageCodec, ExrHalfRoundTripWithinHalfPrecision) {
    Frame frame = make_frame(16, 9);
    for (std::size_t i = 0; i < frame.rgba.size(); ++i) {
        // Normal half range is about 6.1e-5 .. 65504; stay well inside it.
        frame.rgba[i] = (i % 2 ? -1.0f : 1.0f) * (0.001f + static_cast<float>(i) * 3.7f);
    }
    EncodeOptions options;
    options.exr_half = true;
    const auto half_bytes = encode_image(frame, ImageFormat::exr, options);
    const auto float_bytes = encode_image(frame, ImageFormat::exr);
    EXPECT_LT(half_bytes.size(), float_bytes.size());
    const DecodedImage image = decode_image(half_bytes);
    ASSERT_EQ(image.channels, 4);
    ASSERT_EQ(image.pixels.size(), frame.rgba.size());
    for (std::size_t i = 0; i < frame.rgba.size(); ++i) {
        const float want = frame.rgba[i];
        EXPECT_LT(std::abs(image.pixels[i] - want) / std::abs(want), 1e-3f) << "value " << i;
    }
}

TEST(ImageCodec, PngRoundTripIsExact) {
    Frame frame = make_frame(17, 5);
    frame.display_rgba8.resize(frame.rgba.size());
    for (std::size_t i = 0; i < frame.display_rgba8.size(); ++i) {
        frame.display_rgba8[i] = static_cast<std::uint8_t>((i * 37 + 11) % 256);
    }
    const auto bytes = encode_image(frame, ImageFormat::png);
    ASSERT_GE(bytes.size(), 8u);
    EXPECT_EQ(bytes[0], 0x89);
    EXPECT_EQ(bytes[1], 'P');
    const DecodedImage image = decode_image(bytes);
    EXPECT_EQ(image.format, "png");
    ASSERT_EQ(image.width, 17);
    ASSERT_EQ(image.height, 5);
    ASSERT_EQ(image.channels, 4);
    for (int y = 0; y < frame.height; ++y) {
        for (int x = 0; x < frame.width; ++x) {
            const glm::u8vec4 want = frame.display_at(x, y);
            for (int c = 0; c < 4; ++c) {
                ASSERT_EQ(std::lround(image.at(x, y, c) * 255.0f), want[c]) << x << "," << y << " c" << c;
            }
        }
    }
}

TEST(ImageCodec, JpegDecodesWithSmallErrorAndQualityMatters) {
    const Frame frame = gradient_frame(64, 48);
    const double error_95 = lossy_mean_error(frame, 95);
    const double error_20 = lossy_mean_error(frame, 20);
    // Mean absolute error in 8-bit steps over the RGB channels.
    EXPECT_LT(error_95, 1.5);
    EXPECT_LT(error_20, 8.0);
    EXPECT_LT(error_95, error_20);
    RecordProperty("jpeg_error_q95", std::to_string(error_95));
    RecordProperty("jpeg_error_q20", std::to_string(error_20));
}

TEST(ImageCodec, JpegQualityOutOfRangeIsInputError) {
    const Frame frame = gradient_frame(8, 8);
    EncodeOptions options;
    options.jpeg_quality = 0;
    EXPECT_THROW(encode_image(frame, ImageFormat::jpeg, options), InputError);
    options.jpeg_quality = 101;
    EXPECT_THROW(encode_image(frame, ImageFormat::jpeg, options), InputError);
}

TEST(ImageCodec, GarbageBytesAreInputError) {
    const std::vector<std::uint8_t> garbage = {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'};
    EXPECT_THROW(decode_image(garbage), InputError);
    EXPECT_THROW(decode_image(std::span<const std::uint8_t>{}), InputError);
    // Right magic, nothing behind it.
    const std::vector<std::uint8_t> exr_magic_only = {0x76, 0x2F, 0x31, 0x01, 0x02, 0x00};
    EXPECT_THROW(decode_image(exr_magic_only), InputError);
}

TEST(ImageCodec, TruncatedPngIsInputError) {
    const Frame frame = gradient_frame(32, 32);
    const auto bytes = encode_image(frame, ImageFormat::png);
    ASSERT_GT(bytes.size(), 100u);
    for (std::size_t keep : {bytes.size() / 2, std::size_t{40}, std::size_t{12}}) {
        const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.begin() + keep);
        EXPECT_THROW(decode_image(truncated), InputError) << "kept " << keep << " bytes";
    }
}

TEST(ImageCodec, EncodeWithoutDisplayPixelsThrows) {
    Frame frame = make_frame(4, 4);
    EXPECT_THROW(encode_image(frame, ImageFormat::png), Error);
    EXPECT_THROW(encode_image(frame, ImageFormat::jpeg), Error);
    try {
        encode_image(frame, ImageFormat::png);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("display_rgba8"), std::string::npos) << e.what();
    }
    frame.display_rgba8.resize(10);  // wrong size
    EXPECT_THROW(encode_image(frame, ImageFormat::png), Error);
    // EXR needs only the linear buffer.
    EXPECT_NO_THROW(encode_image(frame, ImageFormat::exr));
}

TEST(ImageCodec, EncodeEmptyFrameThrows) {
    const Frame frame;
    EXPECT_THROW(encode_image(frame, ImageFormat::exr), Error);
    EXPECT_THROW(encode_image(frame, ImageFormat::png), Error);
}

// The same bounds as JPEG's: the preview stream trades either for bytes the same way.
TEST(ImageCodec, WebpDecodesWithSmallErrorAndQualityMatters) {
    const Frame frame = gradient_frame(64, 48);
    const double error_95 = lossy_mean_error(frame, 95, ImageFormat::webp);
    const double error_20 = lossy_mean_error(frame, 20, ImageFormat::webp);
    EXPECT_LT(error_95, 1.5);
    EXPECT_LT(error_20, 8.0);
    EXPECT_LT(error_95, error_20);
    EncodeOptions low, high;
    low.jpeg_quality = 20;
    high.jpeg_quality = 95;
    EXPECT_LT(encode_image(frame, ImageFormat::webp, low).size(), encode_image(frame, ImageFormat::webp, high).size());
}

TEST(ImageCodec, ParseImageFormat) {
    EXPECT_EQ(parse_image_format("png"), ImageFormat::png);
    EXPECT_EQ(parse_image_format("PNG"), ImageFormat::png);
    EXPECT_EQ(parse_image_format("jpeg"), ImageFormat::jpeg);
    EXPECT_EQ(parse_image_format("jpg"), ImageFormat::jpeg);
    EXPECT_EQ(parse_image_format("Exr"), ImageFormat::exr);
    EXPECT_EQ(parse_image_format("webp"), ImageFormat::webp);
    EXPECT_THROW(parse_image_format("tiff"), InputError);
    EXPECT_THROW(parse_image_format(""), InputError);
    try {
        parse_image_format("bmp");
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bmp"), std::string::npos) << e.what();
    }
    for (ImageFormat f : {ImageFormat::png, ImageFormat::jpeg, ImageFormat::webp, ImageFormat::exr}) {
        EXPECT_EQ(parse_image_format(image_format_name(f)), f);
    }
}

TEST(ImageCodec, ImageFormatFromPath) {
    EXPECT_EQ(image_format_from_path("out/frame.png"), ImageFormat::png);
    EXPECT_EQ(image_format_from_path("frame.JPG"), ImageFormat::jpeg);
    EXPECT_EQ(image_format_from_path("frame.jpeg"), ImageFormat::jpeg);
    EXPECT_EQ(image_format_from_path("/tmp/a.b/frame.exr"), ImageFormat::exr);
    EXPECT_EQ(image_format_from_path("frame.webp"), ImageFormat::webp);
    EXPECT_THROW(image_format_from_path("frame.tif"), InputError);
    EXPECT_THROW(image_format_from_path("frame"), InputError);
}

TEST(ImageCodec, WriteFileAtomicWritesBytesAndLeavesNoTemp) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("bounce_codec_test_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const auto path = dir / "out.bin";
    const std::vector<std::uint8_t> first = {1, 2, 3, 0, 255};
    write_file_atomic(path, first);
    const std::vector<std::uint8_t> second = {9, 8, 7};
    write_file_atomic(path, second);  // replaces the existing file

    std::ifstream in(path, std::ios::binary);
    const std::vector<std::uint8_t> read((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
    EXPECT_EQ(read, second);
    int entries = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        ++entries;
        EXPECT_EQ(entry.path().filename(), "out.bin");
    }
    EXPECT_EQ(entries, 1);

    // A missing folder fails with an Error naming the path, and leaves nothing behind.
    const auto bad = dir / "missing" / "out.bin";
    try {
        write_file_atomic(bad, first);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
    }
    std::filesystem::remove_all(dir);
}

TEST(Frame, NonFiniteCountCountsPixels) {
    Frame frame = make_frame(4, 3);
    EXPECT_EQ(frame.non_finite_count(), 0u);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    // Pixel 0: NaN in every channel still counts once.
    for (int c = 0; c < 4; ++c) frame.rgba[c] = nan;
    // Pixel 5: +Inf in green only.
    frame.rgba[5 * 4 + 1] = inf;
    // Pixel 11: -Inf in alpha only.
    frame.rgba[11 * 4 + 3] = -inf;
    // Large but finite values do not count.
    frame.rgba[7 * 4] = std::numeric_limits<float>::max();
    EXPECT_EQ(frame.non_finite_count(), 3u);
}

}  // namespace
}  // namespace bounce::image
