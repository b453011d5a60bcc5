#include "renderer/image/codec.hpp"

#include "renderer/base/error.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace bounce::image {

namespace {

std::string lowercase(std::string_view text) {
    std::string out(text);
    std::transform(out.begin(), out.end(), out.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return out;
}

// OIIO picks its plugin from the file name's extension; nothing is ever read from or written to
// these names because every transfer goes through an in-memory IOProxy.
const char* dummy_filename(ImageFormat format) {
    switch (format) {
        case ImageFormat::png: return "memory.png";
        case ImageFormat::jpeg: return "memory.jpg";
        case ImageFormat::webp: return "memory.webp";
        case ImageFormat::exr: return "memory.exr";
    }
    return "memory.png";
}

bool starts_with(std::span<const std::uint8_t> bytes, std::initializer_list<std::uint8_t> magic) {
    return bytes.size() >= magic.size() && std::equal(magic.begin(), magic.end(), bytes.begin());
}

// The bytes, not a name, decide the format: callers hand us uploads whose names cannot be trusted.
bool sniff_format(std::span<const std::uint8_t> bytes, ImageFormat& format) {
    if (starts_with(bytes, {0x89, 'P', 'N', 'G'})) {
        format = ImageFormat::png;
    } else if (starts_with(bytes, {0xFF, 0xD8, 0xFF})) {
        format = ImageFormat::jpeg;
    } else if (bytes.size() >= 12 && starts_with(bytes, {'R', 'I', 'F', 'F'}) && bytes[8] == 'W' && bytes[9] == 'E' &&
               bytes[10] == 'B' && bytes[11] == 'P') {
        format = ImageFormat::webp;
    } else if (starts_with(bytes, {0x76, 0x2F, 0x31, 0x01})) {
        format = ImageFormat::exr;
    } else {
        return false;
    }
    return true;
}

// OIIO keeps a per-thread global error for failures before an ImageInput/ImageOutput exists;
// fetching it also clears it so a stale message never leaks into a later, unrelated error.
std::string global_oiio_error() {
    std::string message = OIIO::geterror();
    return message.empty() ? std::string("no details from OpenImageIO") : message;
}

std::string object_error(const std::string& message) {
    return message.empty() ? global_oiio_error() : message;
}

}  // namespace

ImageFormat parse_image_format(std::string_view name) {
    const std::string lower = lowercase(name);
    if (lower == "png") return ImageFormat::png;
    if (lower == "jpeg" || lower == "jpg") return ImageFormat::jpeg;
    if (lower == "webp") return ImageFormat::webp;
    if (lower == "exr") return ImageFormat::exr;
    throw InputError(fmt::format("unknown image format '{}' (expected png, jpeg, webp or exr)", name));
}

ImageFormat image_format_from_path(const std::filesystem::path& path) {
    const std::string ext = lowercase(path.extension().string());
    if (ext == ".png") return ImageFormat::png;
    if (ext == ".jpg" || ext == ".jpeg") return ImageFormat::jpeg;
    if (ext == ".webp") return ImageFormat::webp;
    if (ext == ".exr") return ImageFormat::exr;
    throw InputError(fmt::format("cannot tell the image format of '{}' (expected .png, .jpg, .jpeg, .webp or .exr)",
                                 path.string()));
}

std::string_view image_format_name(ImageFormat format) {
    switch (format) {
        case ImageFormat::png: return "png";
        case ImageFormat::jpeg: return "jpeg";
        case ImageFormat::webp: return "webp";
        case ImageFormat::exr: return "exr";
    }
    return "png";
}

std::vector<std::uint8_t> encode_image(const Frame& frame, ImageFormat format, const EncodeOptions& options) {
    const std::string_view name = image_format_name(format);
    if (frame.width <= 0 || frame.height <= 0) {
        BOUNCE_FAIL("cannot encode {}: frame has no pixels ({}x{})", name, frame.width, frame.height);
    }
    const std::size_t values = static_cast<std::size_t>(frame.width) * frame.height * 4;

    OIIO::ImageSpec spec;
    const void* data = nullptr;
    OIIO::stride_t xstride = OIIO::AutoStride;
    OIIO::TypeDesc source_type;
    if (format == ImageFormat::exr) {
        if (frame.rgba.size() != values) {
            BOUNCE_FAIL("cannot encode exr: linear rgba has {} values, expected {} for {}x{}",
                        frame.rgba.size(), values, frame.width, frame.height);
        }
        spec = OIIO::ImageSpec(frame.width, frame.height, 4,
                               options.exr_half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
        // zip is lossless, so a float EXR round-trips bit for bit.
        spec.attribute("compression", "zip");
        data = frame.rgba.data();
        source_type = OIIO::TypeDesc::FLOAT;
    } else {
        if (frame.display_rgba8.empty()) {
            BOUNCE_FAIL("cannot encode {}: frame has no display image (display_rgba8 is empty)", name);
        }
        if (frame.display_rgba8.size() != values) {
            BOUNCE_FAIL("cannot encode {}: display_rgba8 has {} bytes, expected {} for {}x{}", name,
                        frame.display_rgba8.size(), values, frame.width, frame.height);
        }
        const bool lossy = format == ImageFormat::jpeg || format == ImageFormat::webp;
        spec = OIIO::ImageSpec(frame.width, frame.height, lossy ? 3 : 4, OIIO::TypeDesc::UINT8);
        if (lossy) {
            if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
                throw InputError(fmt::format("{} quality {} is out of range (expected 1..100)", name,
                                             options.jpeg_quality));
            }
            spec.attribute("Compression", fmt::format("{}:{}", name, options.jpeg_quality));
            // No alpha in a preview frame: a 4-byte pixel stride over 3 channels drops it without a copy.
            xstride = 4;
        } else {
            spec.alpha_channel = 3;
            // The display pixels carry straight alpha, as PNG stores it; without this OIIO assumes
            // premultiplied input and divides the colour by alpha on the way out.
            spec.attribute("oiio:UnassociatedAlpha", 1);
        }
        data = frame.display_rgba8.data();
        source_type = OIIO::TypeDesc::UINT8;
    }

    std::vector<unsigned char> buffer;
    OIIO::Filesystem::IOVecOutput proxy(buffer);
    const std::string filename = dummy_filename(format);
    auto out = OIIO::ImageOutput::create(filename);
    if (!out) BOUNCE_FAIL("cannot encode {}: no OpenImageIO writer: {}", name, global_oiio_error());
    if (!out->supports("ioproxy")) {
        BOUNCE_FAIL("cannot encode {}: OpenImageIO writer '{}' cannot write to memory", name,
                    out->format_name());
    }
    if (!out->set_ioproxy(&proxy)) {
        BOUNCE_FAIL("cannot encode {}: {}", name, object_error(out->geterror()));
    }
    if (!out->open(filename, spec)) {
        BOUNCE_FAIL("cannot encode {}: open failed: {}", name, object_error(out->geterror()));
    }
    if (!out->write_image(source_type, data, xstride)) {
        const std::string message = object_error(out->geterror());
        out->close();
        BOUNCE_FAIL("cannot encode {}: write failed: {}", name, message);
    }
    // close() flushes the encoder's trailing data (PNG IEND, EXR offsets) into the buffer.
    if (!out->close()) {
        BOUNCE_FAIL("cannot encode {}: close failed: {}", name, object_error(out->geterror()));
    }
    out.reset();
    return {buffer.begin(), buffer.end()};
}

DecodedImage decode_image(std::span<const std::uint8_t> bytes) {
    ImageFormat format{};
    if (!sniff_format(bytes, format)) {
        throw InputError(fmt::format("cannot decode image: {} bytes are not PNG, JPEG, WebP or EXR data",
                                     bytes.size()));
    }
    const std::string filename = dummy_filename(format);
    const std::string_view name = image_format_name(format);
    // Only the reader of the sniffed format sees the bytes: where it refuses them, OpenImageIO would
    // otherwise hand a client's bytes to every reader it has (DICOM, camera raw, ffmpeg, OpenVDB),
    // parsers Bounce never needs. scripts/check-pack-binaries fails if any of them is reached.
    static const bool sniffed_reader_only = OIIO::attribute("try_all_readers", 0);
    (void)sniffed_reader_only;

    OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
    // Keep stored values as they are: by default OIIO premultiplies PNG colour by alpha on read.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    // In OIIO 2.4 a reader opened with a config takes its proxy from the config's "oiio:ioproxy"
    // entry and drops any proxy it was given when that entry is missing, so name it there too.
    OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
    auto in = OIIO::ImageInput::create(filename, false, &config, &proxy);
    if (!in) {
        throw InputError(fmt::format("cannot decode {} image: {}", name, global_oiio_error()));
    }
    if (!in->supports("ioproxy") || !in->set_ioproxy(&proxy)) {
        BOUNCE_FAIL("cannot decode {}: OpenImageIO reader '{}' cannot read from memory", name,
                    in->format_name());
    }
    OIIO::ImageSpec spec;
    if (!in->open(filename, spec, config)) {
        throw InputError(fmt::format("cannot decode {} image: {}", name, object_error(in->geterror())));
    }
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
        throw InputError(fmt::format("cannot decode {} image: empty image ({}x{}, {} channels)", name,
                                     spec.width, spec.height, spec.nchannels));
    }

    DecodedImage image;
    image.width = spec.width;
    image.height = spec.height;
    image.channels = spec.nchannels;
    image.format = in->format_name();
    image.pixels.resize(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        const std::string message = object_error(in->geterror());
        in->close();
        throw InputError(fmt::format("cannot decode {} image: {}", name, message));
    }
    in->close();
    return image;
}

void write_file_atomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
    // Same directory as the target so the rename stays on one filesystem and is atomic; the pid keeps
    // concurrent writers of the same path from sharing a temporary.
    std::filesystem::path temp = path;
    temp += fmt::format(".tmp-{}", static_cast<long>(::getpid()));

    auto fail_with = [&](const std::string& what, const std::string& reason) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        BOUNCE_FAIL("cannot write '{}': {}: {}", path.string(), what, reason);
    };

    {
        errno = 0;
        std::ofstream file(temp, std::ios::binary | std::ios::trunc);
        if (!file) fail_with("cannot create " + temp.string(), std::strerror(errno));
        file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        file.flush();
        if (!file) fail_with("write to " + temp.string() + " failed", std::strerror(errno));
        file.close();
        if (file.fail()) fail_with("closing " + temp.string() + " failed", std::strerror(errno));
    }

    std::error_code ec;
    std::filesystem::rename(temp, path, ec);
    if (ec) fail_with("rename from " + temp.string() + " failed", ec.message());
}

}  // namespace bounce::image
