#include "renderer/scene/gltf_budget.hpp"

#include "renderer/scene/gltf_images.hpp"

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

std::string bytes_text(std::uint64_t bytes) {
    const auto value = static_cast<double>(bytes);
    constexpr double kib = 1024.0;
    if (value >= kib * kib * kib) return fmt::format("{:.1f} GiB", value / (kib * kib * kib));
    if (value >= kib * kib) return fmt::format("{:.1f} MiB", value / (kib * kib));
    if (value >= kib) return fmt::format("{:.1f} KiB", value / kib);
    return fmt::format("{} bytes", bytes);
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

    void count_images(const LoadContext& context) {
        const std::vector<bool> used = images_in_use(model_);
        for (const auto& [index, header] : context.image_headers) {
            if (!used.at(static_cast<std::size_t>(index))) continue;  // never decoded
            const tinygltf::Image& image = model_.images[static_cast<std::size_t>(index)];
            const std::string& label = !image.uri.empty() ? image.uri : image.name;
            const std::string named = label.empty() ? "" : fmt::format(" '{}'", label);
            const std::uint64_t bytes = times(times(header.width, header.height), 4 * 4) / 3;
            parts_.push_back(
                {fmt::format("image {}{} ({}x{})", index, named, header.width, header.height), bytes});
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
