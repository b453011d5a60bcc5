#include "renderer/scene/gltf_images.hpp"

#include "renderer/base/error.hpp"
#include "renderer/scene/gltf_validation.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cstring>
#include <span>

namespace bounce::scene::gltf {
namespace {

std::uint64_t be16(std::span<const unsigned char> bytes, std::size_t at) {
    return std::uint64_t{bytes[at]} << 8 | bytes[at + 1];
}

std::uint64_t be32(std::span<const unsigned char> bytes, std::size_t at) {
    return be16(bytes, at) << 16 | be16(bytes, at + 2);
}

// The bytes of image `index` as tinygltf had them: its bufferView's, or its URI's decoded again.
// Empty when they cannot be had again.
struct EncodedImage {
    std::span<const unsigned char> bytes;
    std::vector<unsigned char> owned;
};

EncodedImage encoded_image(const tinygltf::Model& model, const Json& document, int index,
                           const LoadContext& context) {
    EncodedImage encoded;
    const tinygltf::Image& image = model.images[static_cast<std::size_t>(index)];
    if (image.bufferView >= 0) {
        const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(image.bufferView));
        const std::vector<unsigned char>& data = model.buffers.at(static_cast<std::size_t>(view.buffer)).data;
        if (view.byteOffset <= data.size() && view.byteLength <= data.size() - view.byteOffset) {
            encoded.bytes = std::span(data).subspan(view.byteOffset, view.byteLength);
        }
        return encoded;
    }
    const std::string& uri =
        document.at("images").at(static_cast<std::size_t>(index)).at("uri").get_ref<const std::string&>();
    if (tinygltf::IsDataURI(uri)) {
        std::string mime_type;
        if (!tinygltf::DecodeDataURI(&encoded.owned, mime_type, uri, 0, false)) encoded.owned.clear();
    } else if (auto file = read_uri_file(uri, context)) {
        encoded.owned = std::move(*file);
    }
    encoded.bytes = encoded.owned;
    return encoded;
}

// Whether every chunk of a PNG lies inside its bytes. stb_image grows its buffer for the image data
// to each chunk's declared length before reading the chunk, so a few bytes declaring a chunk of
// 1 GiB would allocate that much, outside any budget.
bool png_chunks_inside(std::span<const unsigned char> bytes) {
    if (bytes.size() < 8 || bytes[0] != 0x89) return true;  // not a PNG
    std::size_t at = 8;                                       // past the signature
    while (bytes.size() - at >= 8) {
        const std::uint64_t length = std::uint64_t{bytes[at]} << 24 | std::uint64_t{bytes[at + 1]} << 16 |
                                     std::uint64_t{bytes[at + 2]} << 8 | bytes[at + 3];
        if (length + 4 > bytes.size() - at - 8) return false;  // data and CRC
        if (std::memcmp(bytes.data() + at + 4, "IEND", 4) == 0) return true;
        at += 12 + length;
    }
    return true;  // a cut-off chunk header: the decoder fails on it without allocating
}

// What a PNG's image data may inflate to: a filter byte and the packed samples of every row. Adam7
// passes hold the pixels once between them and add a filter byte and at most one partial byte to
// each of their rows, fewer than 2 height + 7 rows in all.
std::uint64_t png_inflated_limit(const ImageHeader& header) {
    const std::uint64_t row_bytes = (header.width * static_cast<std::uint64_t>(header.channels * header.bit_depth) + 7) / 8;
    const std::uint64_t rows = header.height * (1 + row_bytes);
    return header.interlaced ? rows + 2 * (2 * header.height + 7) : rows;
}

// Whether the IDAT chunks inflate to no more than the rows need. stb_image grows its buffer by
// doubling until all of the data fits, so a small file whose data inflates far past its declared
// rows would allocate outside the budget (up to 4 GiB); inflating into a small scratch buffer
// first costs time, no memory. Chunks are inside the bytes (png_chunks_inside).
bool png_inflates_within(std::span<const unsigned char> bytes, const ImageHeader& header) {
    const std::uint64_t limit = png_inflated_limit(header);
    z_stream stream{};
    if (inflateInit(&stream) != Z_OK) return false;
    std::array<unsigned char, 1 << 16> scratch{};
    std::uint64_t inflated = 0;
    bool within = true, ended = false;
    for (std::size_t at = 8; within && !ended && bytes.size() - at >= 12;) {
        const std::uint64_t length = be32(bytes, at);
        const bool image_data = std::memcmp(bytes.data() + at + 4, "IDAT", 4) == 0;
        if (std::memcmp(bytes.data() + at + 4, "IEND", 4) == 0) break;
        if (image_data) {
            stream.next_in = const_cast<unsigned char*>(bytes.data() + at + 8);
            stream.avail_in = static_cast<uInt>(length);
            while (stream.avail_in > 0 && within) {
                stream.next_out = scratch.data();
                stream.avail_out = static_cast<uInt>(scratch.size());
                const int status = inflate(&stream, Z_NO_FLUSH);
                inflated += scratch.size() - stream.avail_out;
                within = inflated <= limit;
                if (status == Z_STREAM_END) {
                    ended = true;
                    break;
                }
                if (status != Z_OK) break;  // corrupt data: the decoder fails on it
            }
        }
        at += 12 + static_cast<std::size_t>(length);
    }
    inflateEnd(&stream);
    return within;
}

// Decodes one image into `image` (tinygltf's defaults: every image expanded to four channels); the
// reason it has no pixels otherwise.
std::optional<std::string> decode(tinygltf::Image& image, int index, const ImageHeader& header,
                                  std::span<const unsigned char> bytes) {
    if (bytes.empty()) return "the image file could not be read again";
    // The decoder takes the length as an int.
    if (bytes.size() > static_cast<std::size_t>(INT_MAX)) return "the encoded image is over 2 GiB";
    if (!png_chunks_inside(bytes)) return "a PNG chunk runs past the end of the image";
    if (header.format == ImageHeader::Format::png && !png_inflates_within(bytes, header)) {
        return fmt::format("its image data inflates past the {} bytes its {}x{} pixels need", png_inflated_limit(header),
                           header.width, header.height);
    }
    // The budget counted what decoding the header it read costs; a file read again may have
    // changed since.
    std::string why;
    if (read_image_header(bytes, why) != header) {
        return "its header is not the one read when the scene's size was counted (the file changed)";
    }
    std::string error;
    std::string warning;
    if (!tinygltf::LoadImageData(&image, index, &error, &warning, 0, 0, bytes.data(),
                                 static_cast<int>(bytes.size()), nullptr)) {
        while (!error.empty() && error.back() == '\n') error.pop_back();
        return error.empty() ? "it could not be decoded" : error;
    }
    if (static_cast<std::uint64_t>(image.width) != header.width ||
        static_cast<std::uint64_t>(image.height) != header.height) {
        const std::string reason =
            fmt::format("it decodes to {}x{} pixels, not the {}x{} its header declares", image.width,
                        image.height, header.width, header.height);
        image.image = {};
        image.width = image.height = 0;
        return reason;
    }
    return std::nullopt;
}

}  // namespace

namespace {


// The IHDR chunk, which must come first, and of the chunks after it what the decoder's allocations
// depend on: the IDAT chunks' lengths and whether there is a tRNS chunk. Only what stb_image
// decodes is accepted: bit depths 1, 2, 4, 8 and 16, colour types 0, 2, 3, 4 and 6 (no 16-bit
// palette), deflate, the one filter method, no or Adam7 interlacing.
std::optional<ImageHeader> png_header(std::span<const unsigned char> bytes, std::string& why) {
    if (bytes.size() < 29 || be32(bytes, 8) != 13 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
        why = "a PNG whose first chunk is not a whole IHDR";
        return std::nullopt;
    }
    ImageHeader header;
    header.format = ImageHeader::Format::png;
    header.width = be32(bytes, 16);
    header.height = be32(bytes, 20);
    header.bit_depth = bytes[24];
    const int colour_type = bytes[25];
    header.palette = colour_type == 3;
    header.interlaced = bytes[28] == 1;
    header.encoded_bytes = bytes.size();
    const bool depth_ok = header.bit_depth == 1 || header.bit_depth == 2 || header.bit_depth == 4 ||
                          header.bit_depth == 8 || header.bit_depth == 16;
    static constexpr int channels_of_type[7] = {1, 0, 3, 1, 2, 0, 4};
    const int channels = colour_type <= 6 ? channels_of_type[colour_type] : 0;
    if (!depth_ok || channels == 0 || (header.palette && header.bit_depth == 16) || bytes[26] != 0 ||
        bytes[27] != 0 || bytes[28] > 1) {
        why = fmt::format("a PNG of bit depth {}, colour type {}, compression {}, filter {} and interlace {} "
                          "cannot be decoded",
                          header.bit_depth, colour_type, bytes[26], bytes[27], bytes[28]);
        return std::nullopt;
    }
    header.channels = channels;
    // stb_image reads the IDAT chunks into one buffer: at least 4 KiB or the first chunk's length,
    // doubled until the next chunk fits.
    std::uint64_t read = 0;
    std::size_t at = 8;
    while (bytes.size() - at >= 8) {
        const std::uint64_t length = be32(bytes, at);
        const unsigned char* type = bytes.data() + at + 4;
        if (std::memcmp(type, "IEND", 4) == 0) break;
        if (std::memcmp(type, "tRNS", 4) == 0) header.transparency = true;
        if (std::memcmp(type, "IDAT", 4) == 0) {
            std::uint64_t& capacity = header.idat_buffer_bytes;
            if (capacity == 0) capacity = std::max<std::uint64_t>(length, 4096);
            while (read + length > capacity) capacity *= 2;
            read += length;
        }
        if (length + 12 > bytes.size() - at) break;  // past the end: not decoded (png_chunks_inside)
        at += 12 + static_cast<std::size_t>(length);
    }
    return header;
}

// The first frame header (SOF) of a JPEG, found as stb_image finds it: past the segments before
// it, each skipped by its length. Only what stb_image decodes is accepted: baseline and extended
// (SOF0, SOF1) or progressive (SOF2) Huffman coding, 8 bits, 1, 3 or 4 components whose sampling
// factors (1 to 4) divide the largest.
std::optional<ImageHeader> jpeg_header(std::span<const unsigned char> bytes, std::string& why) {
    why = "a JPEG without a whole frame header";
    std::size_t at = 2;
    while (bytes.size() - at >= 4) {
        if (bytes[at] != 0xFF) return std::nullopt;
        const unsigned char marker = bytes[at + 1];
        if (marker == 0xFF) {
            ++at;  // fill byte
            continue;
        }
        const std::size_t length = static_cast<std::size_t>(be16(bytes, at + 2));
        const bool start_of_frame =
            marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (!start_of_frame) {
            at += 2 + length;
            if (at > bytes.size()) return std::nullopt;
            continue;
        }
        if (length < 8 || bytes.size() - at < 2 + length) return std::nullopt;
        ImageHeader header;
        header.format = ImageHeader::Format::jpeg;
        header.bit_depth = bytes[at + 4];
        header.height = be16(bytes, at + 5);
        header.width = be16(bytes, at + 7);
        header.channels = bytes[at + 9];
        header.progressive = marker == 0xC2;
        header.encoded_bytes = bytes.size();
        if (marker > 0xC2) {
            why = fmt::format("a JPEG coded as SOF{} (lossless, hierarchical or arithmetic) cannot be decoded",
                              marker - 0xC0);
            return std::nullopt;
        }
        if (header.bit_depth != 8 || (header.channels != 1 && header.channels != 3 && header.channels != 4) ||
            length != 8 + 3 * static_cast<std::size_t>(header.channels)) {
            why = fmt::format("a {}-bit JPEG of {} components cannot be decoded", header.bit_depth,
                              header.channels);
            return std::nullopt;
        }
        int h_max = 1;
        int v_max = 1;
        for (int c = 0; c < header.channels; ++c) {
            const unsigned char factors = bytes[at + 11 + 3 * static_cast<std::size_t>(c)];
            header.sampling.push_back(factors);
            h_max = std::max(h_max, factors >> 4);
            v_max = std::max(v_max, factors & 15);
        }
        for (const std::uint8_t factors : header.sampling) {
            const int h = factors >> 4;
            const int v = factors & 15;
            if (h < 1 || h > 4 || v < 1 || v > 4 || h_max % h != 0 || v_max % v != 0) {
                why = fmt::format("a JPEG with the sampling factors {}x{} cannot be decoded", h, v);
                return std::nullopt;
            }
        }
        return header;
    }
    return std::nullopt;
}

}  // namespace

std::optional<ImageHeader> read_image_header(std::span<const unsigned char> bytes, std::string& why) {
    static constexpr unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), png_signature, 8) == 0) return png_header(bytes, why);
    if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) return jpeg_header(bytes, why);
    why = "it is not a PNG or JPEG image";
    return std::nullopt;
}

std::string describe(const ImageHeader& header) {
    if (header.format == ImageHeader::Format::jpeg) {
        return fmt::format("{}-component {}JPEG", header.channels, header.progressive ? "progressive " : "");
    }
    static constexpr const char* layouts[5] = {"", "grey", "grey+alpha", "RGB", "RGBA"};
    return fmt::format("{}-bit {}{} PNG", header.bit_depth,
                       header.palette ? "palette" : layouts[std::clamp(header.channels, 0, 4)],
                       header.interlaced ? " interlaced" : "");
}

bool record_image_header(tinygltf::Image* /*image*/, int image_index, std::string* /*err*/,
                         std::string* /*warn*/, int /*required_width*/, int /*required_height*/,
                         const unsigned char* bytes, int size, void* user_data) {
    auto& context = *static_cast<LoadContext*>(user_data);
    // tinygltf passes lengths as int: one past 2 GiB arrives negative and is not an image we can read.
    std::string why = "it is not a PNG or JPEG image";
    const std::optional<ImageHeader> header =
        size > 0 ? read_image_header({bytes, static_cast<std::size_t>(size)}, why) : std::nullopt;
    if (!header || header->width == 0 || header->height == 0) {
        context.image_failures[image_index] =
            fmt::format("cannot decode it: {}", header ? "it declares no pixels" : why);
    } else if (header->width > max_image_side || header->height > max_image_side) {
        context.image_failures[image_index] = fmt::format("{}x{} pixels exceeds the limit of {} per side",
                                                          header->width, header->height, max_image_side);
    } else {
        context.image_headers[image_index] = *header;
    }
    return true;
}

std::vector<unsigned> texture_uses(const tinygltf::Model& model) {
    std::vector<unsigned> uses(model.images.size(), 0);
    auto use = [&](const auto& info, unsigned colour_space) {
        if (info.index < 0 || static_cast<std::size_t>(info.index) >= model.textures.size()) return;
        if (info.texCoord > 1) return;  // the converter ignores it
        const int source = model.textures[static_cast<std::size_t>(info.index)].source;
        if (source >= 0 && static_cast<std::size_t>(source) < uses.size()) {
            uses[static_cast<std::size_t>(source)] |= colour_space;
        }
    };
    for (const tinygltf::Material& material : model.materials) {
        use(material.pbrMetallicRoughness.baseColorTexture, used_as_srgb);
        use(material.pbrMetallicRoughness.metallicRoughnessTexture, used_as_linear);
        use(material.normalTexture, used_as_linear);
        use(material.emissiveTexture, used_as_srgb);
    }
    return uses;
}

void decode_images(tinygltf::Model& model, const Json& document, LoadContext& context) {
    const std::vector<unsigned> uses = texture_uses(model);
    for (const auto& [index, header] : context.image_headers) {
        if (uses.at(static_cast<std::size_t>(index)) == 0) continue;
        tinygltf::Image& image = model.images[static_cast<std::size_t>(index)];
        const EncodedImage encoded = encoded_image(model, document, index, context);
        if (std::optional<std::string> failure = decode(image, index, header, encoded.bytes)) {
            context.image_failures[index] = std::move(*failure);
        }
    }
}

TextureSampler texture_sampler(const tinygltf::Model& model, int index, const std::string& where) {
    TextureSampler sampler;
    if (index < 0) return sampler;
    if (static_cast<std::size_t>(index) >= model.samplers.size()) {
        throw InputError(fmt::format("{} refers to sampler {} (there are {})", where, index, model.samplers.size()));
    }
    const tinygltf::Sampler& source = model.samplers[static_cast<std::size_t>(index)];
    const auto wrap = [&](int value, const char* member) {
        switch (value) {
        case 10497: return TextureSampler::Wrap::repeat;
        case 33071: return TextureSampler::Wrap::clamp_to_edge;
        case 33648: return TextureSampler::Wrap::mirrored_repeat;
        default:
            throw InputError(fmt::format("{}: sampler {} {} is {}, none of 10497 (REPEAT), 33071 (CLAMP_TO_EDGE), "
                                         "33648 (MIRRORED_REPEAT)",
                                         where, index, member, value));
        }
    };
    sampler.wrap_s = wrap(source.wrapS, "wrapS");
    sampler.wrap_t = wrap(source.wrapT, "wrapT");
    switch (source.magFilter) {
    case -1: case 9729: break;  // absent or LINEAR
    case 9728: sampler.mag_nearest = true; break;
    default:
        throw InputError(fmt::format("{}: sampler {} magFilter is {}, neither 9728 (NEAREST) nor 9729 (LINEAR)", where,
                                     index, source.magFilter));
    }
    using Min = TextureSampler::MinFilter;
    switch (source.minFilter) {
    case -1: case 9987: sampler.min_filter = Min::linear_mipmap_linear; break;
    case 9728: sampler.min_filter = Min::nearest; break;
    case 9729: sampler.min_filter = Min::linear; break;
    case 9984: sampler.min_filter = Min::nearest_mipmap_nearest; break;
    case 9985: sampler.min_filter = Min::linear_mipmap_nearest; break;
    case 9986: sampler.min_filter = Min::nearest_mipmap_linear; break;
    default:
        throw InputError(fmt::format("{}: sampler {} minFilter is {}, not a glTF filter (9728, 9729, 9984 to 9987)",
                                     where, index, source.minFilter));
    }
    return sampler;
}

}  // namespace bounce::scene::gltf
