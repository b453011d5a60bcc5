// What the parts of the glTF importer share (renderer/scene/gltf_*.cpp; the API is gltf_import.hpp):
// the limits on untrusted input, faults and warnings, and what tinygltf's callbacks record while it
// loads.
#pragma once

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace bounce::scene::gltf {

using Json = nlohmann::json;

// Limits that keep a hostile file from asking for unbounded memory.
inline constexpr std::uint64_t max_accessor_count = std::uint64_t{1} << 28;
inline constexpr int max_image_side = 16384;
inline constexpr std::uint64_t max_input_bytes = 0xFFFFFFFFull;  // tinygltf takes lengths as unsigned int
// JSON nested deeper than this is refused before any parser sees it: nlohmann and tinygltf recurse.
inline constexpr int max_json_depth = 128;
// A light's colour components and intensity: the ranges light.set allows (docs/protocol.md,
// "Numbers"), which keep their product finite.
inline constexpr double max_light_color = 1e6;
inline constexpr double max_light_intensity = 1e12;

// A fault in the input: throws InputError with `message`.
[[noreturn]] inline void reject(const std::string& message) { throw InputError(message); }

// Warnings go to the log and to Scene::warnings.
class Warnings {
public:
    explicit Warnings(std::string source) : source_(std::move(source)) {}
    void add(const std::string& message) {
        log::warn("gltf", "{}: {}", source_, message);
        list_.push_back(message);
    }
    std::vector<std::string> take() { return std::move(list_); }

private:
    std::string source_;
    std::vector<std::string> list_;
};

// What an image's header declares, read before anything is decoded: all that the decoder's
// allocations depend on (gltf_budget.cpp counts them from it).
struct ImageHeader {
    enum class Format : std::uint8_t { png, jpeg };
    Format format = Format::png;
    std::uint64_t width = 0;
    std::uint64_t height = 0;
    int channels = 0;            // samples per pixel as stored: PNG 1 to 4 (a palette index is 1), JPEG 1, 3 or 4
    int bit_depth = 8;           // bits per sample: PNG 1, 2, 4, 8 or 16; JPEG 8
    std::uint64_t encoded_bytes = 0;  // the image file's length
    // PNG
    bool palette = false;        // colour type 3: indices expanded to RGBA
    bool transparency = false;   // a tRNS chunk: the decoder adds an alpha channel
    bool interlaced = false;     // Adam7: the decoder de-interlaces into a second image
    std::uint64_t idat_buffer_bytes = 0;  // what the decoder's buffer for the IDAT chunks grows to
    // JPEG
    bool progressive = false;                // SOF2: the decoder keeps every coefficient
    std::vector<std::uint8_t> sampling;      // per component, horizontal << 4 | vertical sampling factor

    bool operator==(const ImageHeader&) const = default;
};

// What the callbacks installed by install_callbacks (gltf_validation.hpp) record during a load.
// tinygltf decodes no image: its image callback only reads headers, and the images a material uses
// are decoded after the scene's size was checked (gltf_images.hpp).
struct LoadContext {
    std::filesystem::path folder;                // a file's canonical folder: file access stays inside
    std::map<int, ImageHeader> image_headers;    // image index -> its header, for those to decode
    std::map<int, std::string> image_failures;   // image index -> why it has no pixels
    std::vector<std::string> refused_paths;      // file reads refused for an upload
};

}  // namespace bounce::scene::gltf
