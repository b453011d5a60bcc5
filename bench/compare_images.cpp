// Compares two linear images (EXR): prints one JSON line with the error metrics of docs/references.md
// D1 and the ratio of their mean radiance, over the whole frame or, with --centre F, over the
// centred square of F times the frame's side (a spot light's cone, say).
// usage: bounce_compare_images TEST.exr REFERENCE.exr [--centre F]
#include "renderer/image/codec.hpp"
#include "renderer/image/metrics.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

namespace {

bounce::image::Frame read_frame(const std::string& path, float centre) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const auto image = bounce::image::decode_image(bytes);
    const int side = std::max(1, static_cast<int>(std::min(image.width, image.height) * centre));
    const int x0 = (image.width - side) / 2, y0 = (image.height - side) / 2;
    const int width = centre < 1.0f ? side : image.width, height = centre < 1.0f ? side : image.height;
    bounce::image::Frame frame;
    frame.width = width;
    frame.height = height;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const int sx = centre < 1.0f ? x0 + x : x, sy = centre < 1.0f ? y0 + y : y;
            for (int c = 0; c < 3; ++c) frame.rgba.push_back(c < image.channels ? image.at(sx, sy, c) : 0.0f);
            frame.rgba.push_back(1.0f);
        }
    }
    return frame;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 && argc != 5) {
        std::cerr << "usage: bounce_compare_images TEST.exr REFERENCE.exr [--centre F]\n";
        return 2;
    }
    try {
        const float centre = argc == 5 ? std::stof(argv[4]) : 1.0f;
        const auto test = read_frame(argv[1], centre), reference = read_frame(argv[2], centre);
        const auto metrics = bounce::image::compare(test, reference);
        std::cout << nlohmann::json{{"rel_mse", metrics.rel_mse},
                                    {"mean_test", metrics.mean_test},
                                    {"mean_reference", metrics.mean_reference},
                                    {"mean_ratio", metrics.mean_reference > 0 ? metrics.mean_test / metrics.mean_reference : 0.0}}
                         .dump()
                  << "\n";
        return 0;
    } catch (const std::exception& error) {
        std::cerr << "bounce_compare_images: " << error.what() << "\n";
        return 1;
    }
}
