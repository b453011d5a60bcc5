#include "renderer/scene/gltf_budget.hpp"

#include "renderer/base/bytes.hpp"

#include "renderer/scene/gltf_images.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace bounce::scene::gltf {
namespace {

// Saturating arithmetic: hostile counts must not wrap the sum around to something small.
std::uint64_t times(std::uint64_t a, std::uint64_t b) {
    std::uint64_t product = 0;
    return __builtin_mul_overflow(a, b, &product) ? std::numeric_limits<std::uint64_t>::max() : product;
}

std::uint64_t plus(std::uint64_t a, std::uint64_t b) {
    std::uint64_t sum = 0;
    return __builtin_add_overflow(a, b, &sum) ? std::numeric_limits<std::uint64_t>::max() : sum;
}

// ---- images

// Where the decoder's input comes from: read again from a file or a data: URI, or in place in a
// buffer.
enum class ImageSource : std::uint8_t { buffer_view, data_uri, file };

// What decoding one image allocates, from its header, as stb_image 2.27 through tinygltf's
// LoadImageData (four channels requested) does it. Images are decoded one after another.
struct ImageBytes {
    std::uint64_t kept = 0;       // tinygltf's copy of the pixels, held until the conversion ends
    std::uint64_t transient = 0;  // how far decoding it rises above `kept` at its peak
};

std::uint64_t ceil_div(std::uint64_t a, std::uint64_t b) { return a / b + (a % b != 0 ? 1 : 0); }

// The most stb_image's buffers for a PNG hold at once before its result is copied. In order: the
// IDAT chunks read into one buffer and inflated into the filtered rows (the file's channels at its
// bit depth, a filter byte a row); the rows unfiltered into an image of the file's channels (one
// byte a sample up to 8 bits, two at 16; an alpha channel is added to RGB and where a tRNS chunk
// gives transparency; Adam7 de-interlaces into a second image); a palette's indices expanded to
// RGBA; a grey one converted to 4 channels. It assumes the image data inflates to no more than its
// rows, as a valid PNG's does (stb_image grows its buffer for more: gltf_budget.hpp).
std::uint64_t png_decoder_bytes(const ImageHeader& header) {
    const std::uint64_t pixels = times(header.width, header.height);
    const std::uint64_t sample = header.bit_depth == 16 ? 2 : 1;
    const auto channels = static_cast<std::uint64_t>(header.channels);
    const auto depth = static_cast<std::uint64_t>(header.bit_depth);
    const std::uint64_t row_bytes = ceil_div(times(times(header.width, channels), depth), 8);
    const std::uint64_t rows = times(header.height, plus(row_bytes, 1));
    // With four channels asked for, RGB is unfiltered straight into RGBA.
    const std::uint64_t out_channels =
        header.palette ? 1 : std::min<std::uint64_t>(4, channels + (channels == 3 || header.transparency ? 1 : 0));
    const std::uint64_t out = times(pixels, out_channels * sample);
    std::uint64_t most = plus(header.idat_buffer_bytes, rows);
    most = std::max(most, plus(rows, times(out, header.interlaced ? 2 : 1)));
    if (header.palette) most = std::max(most, plus(plus(rows, out), times(pixels, 4)));
    if (!header.palette && out_channels != 4) most = std::max(most, plus(out, times(pixels, 4 * sample)));
    return most;
}

// The same for a JPEG: each component's plane, padded to whole MCUs (and for a progressive JPEG
// its coefficients, 2 bytes a sample), a line buffer per component, and the 4-channel result.
std::uint64_t jpeg_decoder_bytes(const ImageHeader& header) {
    std::uint64_t h_max = 1;
    std::uint64_t v_max = 1;
    for (const std::uint8_t factors : header.sampling) {
        h_max = std::max<std::uint64_t>(h_max, factors >> 4);
        v_max = std::max<std::uint64_t>(v_max, factors & 15);
    }
    const std::uint64_t mcu_columns = ceil_div(header.width, 8 * h_max);
    const std::uint64_t mcu_rows = ceil_div(header.height, 8 * v_max);
    std::uint64_t bytes = plus(times(times(header.width, header.height), 4), 1);
    for (const std::uint8_t factors : header.sampling) {
        const auto h = static_cast<std::uint64_t>(factors >> 4);
        const auto v = static_cast<std::uint64_t>(factors & 15);
        const std::uint64_t plane = times(times(mcu_columns, 8 * h), times(mcu_rows, 8 * v));
        bytes = plus(bytes, plus(plane, 15));
        if (header.progressive) bytes = plus(bytes, plus(times(plane, 2), 15));
        bytes = plus(bytes, plus(header.width, 3));
    }
    return bytes;
}

ImageBytes image_bytes(const ImageHeader& header, ImageSource source) {
    const std::uint64_t sample = header.format == ImageHeader::Format::png && header.bit_depth == 16 ? 2 : 1;
    const std::uint64_t four = times(times(header.width, header.height), 4 * sample);
    const std::uint64_t decoder =
        header.format == ImageHeader::Format::png ? png_decoder_bytes(header) : jpeg_decoder_bytes(header);
    // The decoder's buffers, then its result while tinygltf copies it into what it keeps; bytes read
    // again (gltf_images.cpp, encoded_image) stay meanwhile. Reading a data: URI again copies its
    // base64 text (4/3 of the bytes) and decodes it into a string that grows by doubling, which is
    // then copied.
    const std::uint64_t encoded = header.encoded_bytes;
    const std::uint64_t held = source == ImageSource::buffer_view ? 0 : encoded;
    std::uint64_t peak = plus(held, std::max(decoder, times(four, 2)));
    if (source == ImageSource::data_uri) {
        peak = std::max(peak, plus(times(ceil_div(encoded, 3), 4), times(encoded, 3)));
    }
    return {four, peak - four};
}

// A GL texture of 4 bytes a texel with its full mip chain (renderer/gpu/gpu_scene.cpp, upload).
std::uint64_t mip_chain_bytes(std::uint64_t width, std::uint64_t height) {
    std::uint64_t bytes = 0;
    for (;;) {
        bytes = plus(bytes, times(times(width, height), 4));
        if (width <= 1 && height <= 1) return bytes;
        width = std::max<std::uint64_t>(width / 2, 1);
        height = std::max<std::uint64_t>(height / 2, 1);
    }
}

struct Part {
    std::string what;
    std::uint64_t bytes = 0;
};

// One accessor's share: its bytes over all the primitives that read it, and in which roles.
struct AccessorShare {
    std::uint64_t bytes = 0;
    std::map<std::string, int> roles;  // "POSITION" -> how many primitives read it so
};

class SceneSize {
public:
    explicit SceneSize(const tinygltf::Model& model) : model_(model), accessors_(model.accessors.size()) {}

    void count_meshes() {
        for (std::size_t m = 0; m < model_.meshes.size(); ++m) {
            const std::vector<tinygltf::Primitive>& primitives = model_.meshes[m].primitives;
            for (std::size_t p = 0; p < primitives.size(); ++p) count_primitive(primitives[p], m, p);
        }
    }

    // The images' share of the peak (gltf_budget.hpp): the phase of the load that holds the most,
    // and each image's part what it holds then.
    void count_images(const LoadContext& context) {
        const std::vector<unsigned> uses = texture_uses(model_);
        struct Counted {
            std::string what;
            ImageBytes decode;
            std::uint64_t rgba8 = 0;  // the Textures made from it, one per colour space it is used in
            std::uint64_t gpu = 0;    // their GL textures
        };
        std::vector<Counted> images;
        std::uint64_t kept = 0;
        std::uint64_t rgba8 = 0;
        std::uint64_t gpu = 0;
        std::size_t most_transient = 0;
        for (const auto& [index, header] : context.image_headers) {
            const unsigned use = uses.at(static_cast<std::size_t>(index));
            if (use == 0) continue;  // never decoded
            const tinygltf::Image& image = model_.images[static_cast<std::size_t>(index)];
            const std::string& label = !image.uri.empty() ? image.uri : image.name;
            const std::string named = label.empty() ? "" : fmt::format(" '{}'", label);
            // tinygltf keeps the URI of an external file only.
            const ImageSource source = image.bufferView >= 0 ? ImageSource::buffer_view
                                       : image.uri.empty()   ? ImageSource::data_uri
                                                             : ImageSource::file;
            Counted counted{fmt::format("image {}{} ({}x{}, {})", index, named, header.width, header.height,
                                        describe(header)),
                            image_bytes(header, source)};
            const auto textures = static_cast<std::uint64_t>(std::popcount(use));
            counted.rgba8 = times(textures, times(times(header.width, header.height), 4));
            counted.gpu = times(textures, mip_chain_bytes(header.width, header.height));
            kept = plus(kept, counted.decode.kept);
            rgba8 = plus(rgba8, counted.rgba8);
            gpu = plus(gpu, counted.gpu);
            if (!images.empty() && counted.decode.transient > images[most_transient].decode.transient) {
                most_transient = images.size();
            }
            images.push_back(std::move(counted));
        }
        if (images.empty()) return;
        const std::uint64_t decoding = plus(kept, images[most_transient].decode.transient);
        const std::uint64_t converting = plus(kept, rgba8);
        const std::uint64_t uploading = plus(rgba8, gpu);
        for (std::size_t i = 0; i < images.size(); ++i) {
            const Counted& image = images[i];
            std::uint64_t bytes = plus(image.rgba8, image.gpu);
            if (decoding >= converting && decoding >= uploading) {
                bytes = plus(image.decode.kept, i == most_transient ? image.decode.transient : 0);
            } else if (converting >= uploading) {
                bytes = plus(image.decode.kept, image.rgba8);
            }
            parts_.push_back({image.what, bytes});
        }
    }

    void check(std::uint64_t budget) const {
        std::uint64_t total = 0;
        Part largest;
        auto consider = [&](const Part& part) {
            total = plus(total, part.bytes);
            if (part.bytes > largest.bytes) largest = part;
        };
        for (std::size_t a = 0; a < accessors_.size(); ++a) {
            if (accessors_[a].bytes == 0) continue;
            std::string roles;
            for (const auto& [role, primitives] : accessors_[a].roles) {
                roles += fmt::format("{}{} of {} primitive{}", roles.empty() ? "" : ", ", role, primitives,
                                     primitives == 1 ? "" : "s");
            }
            consider({fmt::format("accessor {} ({})", a, roles), accessors_[a].bytes});
        }
        for (const Part& part : parts_) consider(part);
        if (total <= budget) return;
        throw ResourceExhausted(fmt::format(
            "the scene decodes to {}, more than its budget of {} (--max-scene-bytes); the largest part is {} "
            "at {}",
            bytes_text(total), bytes_text(budget), largest.what, bytes_text(largest.bytes)));
    }

private:
    // The elements of accessor `index`; 0 when there is none (the converter refuses the reference).
    std::uint64_t elements(int index) const {
        if (index < 0 || static_cast<std::size_t>(index) >= model_.accessors.size()) return 0;
        return model_.accessors[static_cast<std::size_t>(index)].count;
    }

    void read(int index, const std::string& role, std::uint64_t element_bytes) {
        if (index < 0 || static_cast<std::size_t>(index) >= accessors_.size()) return;
        AccessorShare& share = accessors_[static_cast<std::size_t>(index)];
        share.bytes = plus(share.bytes, times(elements(index), element_bytes));
        ++share.roles[role];
    }

    static int attribute(const tinygltf::Primitive& primitive, const char* name) {
        const auto it = primitive.attributes.find(name);
        return it == primitive.attributes.end() ? -1 : it->second;
    }

    // What the converter allocates for one primitive (gltf_convert.cpp, convert_primitive).
    void count_primitive(const tinygltf::Primitive& primitive, std::size_t mesh, std::size_t index) {
        const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            return;  // points and lines are skipped, other modes refused: nothing is read
        }
        const int position = attribute(primitive, "POSITION");
        const std::uint64_t vertices = elements(position);
        read(position, "POSITION", 12);
        read(attribute(primitive, "NORMAL"), "NORMAL", 12);
        read(attribute(primitive, "TANGENT"), "TANGENT", 16);
        read(attribute(primitive, "TEXCOORD_0"), "TEXCOORD_0", 8);
        read(attribute(primitive, "TEXCOORD_1"), "TEXCOORD_1", 8);
        std::uint64_t made = times(vertices, 12 + 16);  // normals and tangents
        std::uint64_t indices = vertices;
        std::string what = "normals and tangents";
        if (primitive.indices >= 0) {
            read(primitive.indices, "indices", 4);
            indices = elements(primitive.indices);
        } else {
            made = plus(made, times(vertices, 4));
            what = "normals, tangents and indices";
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && indices > 2) made = plus(made, times(indices - 2, 3 * 4));
        parts_.push_back({fmt::format("the {} made for mesh {} primitive {}", what, mesh, index), made});
    }

    const tinygltf::Model& model_;
    std::vector<AccessorShare> accessors_;
    std::vector<Part> parts_;  // what primitives make beyond their accessors, and images
};

}  // namespace

void check_scene_size(const tinygltf::Model& model, const LoadContext& context,
                      std::uint64_t max_scene_bytes) {
    SceneSize size(model);
    size.count_meshes();
    size.count_images(context);
    size.check(max_scene_bytes);
}

}  // namespace bounce::scene::gltf
