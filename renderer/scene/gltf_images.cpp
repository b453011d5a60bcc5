#include "renderer/scene/gltf_images.hpp"

#include "renderer/scene/gltf_validation.hpp"

#include <climits>
#include <cstring>
#include <span>

namespace bounce::scene::gltf {
namespace {

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

// Decodes one image into `image` (tinygltf's defaults: every image expanded to four channels); the
// reason it has no pixels otherwise.
std::optional<std::string> decode(tinygltf::Image& image, int index, const ImageHeader& header,
                                  std::span<const unsigned char> bytes) {
    if (bytes.empty()) return "the image file could not be read again";
    // The decoder takes the length as an int.
    if (bytes.size() > static_cast<std::size_t>(INT_MAX)) return "the encoded image is over 2 GiB";
    if (!png_chunks_inside(bytes)) return "a PNG chunk runs past the end of the image";
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

std::optional<ImageHeader> peek_image_size(const unsigned char* bytes, std::size_t size) {
    static constexpr unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    auto be16 = [&](std::size_t at) { return std::uint64_t{bytes[at]} << 8 | bytes[at + 1]; };
    auto be32 = [&](std::size_t at) { return be16(at) << 16 | be16(at + 2); };
    if (size >= 24 && std::memcmp(bytes, png_signature, 8) == 0) {
        if (std::memcmp(bytes + 12, "IHDR", 4) != 0) return std::nullopt;  // the first chunk must be IHDR
        return ImageHeader{be32(16), be32(20)};
    }
    if (size >= 4 && bytes[0] == 0xFF && bytes[1] == 0xD8) {
        std::size_t at = 2;
        while (at + 9 < size) {
            if (bytes[at] != 0xFF) return std::nullopt;
            const unsigned char marker = bytes[at + 1];
            if (marker == 0xFF) {
                ++at;  // fill byte
                continue;
            }
            const bool start_of_frame =
                marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
            if (start_of_frame) return ImageHeader{be16(at + 7), be16(at + 5)};
            at += 2 + be16(at + 2);
        }
    }
    return std::nullopt;
}

bool record_image_header(tinygltf::Image* /*image*/, int image_index, std::string* /*err*/,
                         std::string* /*warn*/, int /*required_width*/, int /*required_height*/,
                         const unsigned char* bytes, int size, void* user_data) {
    auto& context = *static_cast<LoadContext*>(user_data);
    // tinygltf passes lengths as int: one past 2 GiB arrives negative and is not an image we can read.
    const std::optional<ImageHeader> header =
        size > 0 ? peek_image_size(bytes, static_cast<std::size_t>(size)) : std::nullopt;
    if (!header || header->width == 0 || header->height == 0) {
        context.image_failures[image_index] = "cannot decode it: it is not a PNG or JPEG image";
    } else if (header->width > max_image_side || header->height > max_image_side) {
        context.image_failures[image_index] = fmt::format("{}x{} pixels exceeds the limit of {} per side",
                                                          header->width, header->height, max_image_side);
    } else {
        context.image_headers[image_index] = *header;
    }
    return true;
}

std::vector<bool> images_in_use(const tinygltf::Model& model) {
    std::vector<bool> used(model.images.size(), false);
    auto use = [&](const auto& info) {
        if (info.index < 0 || static_cast<std::size_t>(info.index) >= model.textures.size()) return;
        if (info.texCoord > 1) return;  // the converter ignores it
        const int source = model.textures[static_cast<std::size_t>(info.index)].source;
        if (source >= 0 && static_cast<std::size_t>(source) < used.size()) {
            used[static_cast<std::size_t>(source)] = true;
        }
    };
    for (const tinygltf::Material& material : model.materials) {
        use(material.pbrMetallicRoughness.baseColorTexture);
        use(material.pbrMetallicRoughness.metallicRoughnessTexture);
        use(material.normalTexture);
        use(material.emissiveTexture);
    }
    return used;
}

void decode_images(tinygltf::Model& model, const Json& document, LoadContext& context) {
    const std::vector<bool> used = images_in_use(model);
    for (const auto& [index, header] : context.image_headers) {
        if (!used.at(static_cast<std::size_t>(index))) continue;
        tinygltf::Image& image = model.images[static_cast<std::size_t>(index)];
        const EncodedImage encoded = encoded_image(model, document, index, context);
        if (std::optional<std::string> failure = decode(image, index, header, encoded.bytes)) {
            context.image_failures[index] = std::move(*failure);
        }
    }
}

}  // namespace bounce::scene::gltf
