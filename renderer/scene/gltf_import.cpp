// glTF 2.0 import through tinygltf.
//
// The input is untrusted (uploads reach import_glb_memory), so the importer does not rely on
// tinygltf's own validation: before tinygltf sees the document, the JSON's nesting depth is bounded,
// it is type-checked, every bufferView is checked against its buffer and every URI against where
// files may be read (gltf_validation). tinygltf then loads without decoding images, only reading
// their headers (gltf_images). Every accessor is checked against its bufferView (gltf_accessors) and
// the scene's size against its budget (gltf_budget); only then are the images decoded and the model
// converted, every index checked against the vertex count before anything is read (gltf_convert).
// This file runs those steps in order for both entry points.
#include "renderer/scene/gltf_import.hpp"

#include "renderer/scene/gltf_accessors.hpp"
#include "renderer/scene/gltf_budget.hpp"
#include "renderer/scene/gltf_convert.hpp"
#include "renderer/scene/gltf_images.hpp"
#include "renderer/scene/gltf_validation.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>

namespace bounce::scene::gltf {
namespace {

// ------------------------------------------------------------------------------------------------
// The pipeline shared by both entry points.

struct Source {
    std::span<const std::uint8_t> bytes;
    std::string scene_name;
    std::filesystem::path folder;  // the file's canonical folder: external files lie inside (files only)
    bool embedded_only = false;    // an upload: no file access at all
    ImportLimits limits;
};

void log_tinygltf_warnings(const std::string& label, const std::string& text) {
    std::size_t start = 0;
    while (start < text.size()) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        if (end > start) log::warn("gltf", "{}: tinygltf: {}", label, text.substr(start, end - start));
        start = end + 1;
    }
}

std::string trimmed(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

Scene import_bytes(const Source& source, const std::string& label) {
    if (source.bytes.empty()) reject("the file is empty");
    if (source.bytes.size() > max_input_bytes) {
        reject(fmt::format("{} bytes is more than the limit of {}", source.bytes.size(), max_input_bytes));
    }
    Warnings warnings(label);
    const bool binary = has_glb_magic(source.bytes);
    const std::string_view json_text =
        binary ? glb_json_chunk(source.bytes)
               : std::string_view(reinterpret_cast<const char*>(source.bytes.data()), source.bytes.size());
    const Json document = parse_json(json_text);
    check_structure(document, warnings);
    check_extensions(document, warnings);
    if (source.embedded_only) {
        refuse_external_uris(document);
    } else {
        confine_uris(document, source.folder);
    }

    LoadContext context;
    context.folder = source.folder;
    tinygltf::TinyGLTF loader;
    install_callbacks(loader, context, source.embedded_only);
    tinygltf::Model model;
    std::string error;
    std::string warning;
    const auto length = static_cast<unsigned int>(source.bytes.size());
    const std::string base_dir = source.folder.string();
    const bool loaded = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning, source.bytes.data(),
                                                             length, base_dir)
                               : loader.LoadASCIIFromString(&model, &error, &warning, json_text.data(),
                                                            length, base_dir);
    if (!context.refused_paths.empty()) {
        reject(fmt::format("refers to the external file '{}'; an uploaded GLB must embed all its data",
                           context.refused_paths.front()));
    }
    if (!loaded) {
        reject(fmt::format("tinygltf could not load it: {}{}", trimmed(error),
                           warning.empty() ? "" : fmt::format(" (warnings: {})", trimmed(warning))));
    }
    log_tinygltf_warnings(label, warning);
    if (!error.empty()) log_tinygltf_warnings(label, error);  // non-fatal complaints

    check_accessor_bounds(model);
    check_scene_size(model, context, source.limits.max_scene_bytes);
    decode_images(model, document, context);
    Scene scene = convert_model(model, context, warnings, source.scene_name);
    scene.warnings = warnings.take();
    validate_finite(scene);
    check_world_extent(scene);
    return scene;
}

// Runs `import` and prefixes every InputError with the name of what was loaded, keeping its type.
template <typename Import>
Scene naming_faults(const std::string& label, Import&& import) {
    try {
        return import();
    } catch (const ResourceExhausted& error) {
        throw ResourceExhausted(fmt::format("{}: {}", label, error.what()));
    } catch (const InputError& error) {
        throw InputError(fmt::format("{}: {}", label, error.what()));
    }
}

}  // namespace
}  // namespace bounce::scene::gltf

namespace bounce::scene {

using namespace gltf;

Scene import_gltf_file(const std::filesystem::path& path, const ImportLimits& limits) {
    const std::string label = path.filename().string();
    return naming_faults(label, [&] {
        std::error_code code;
        const std::uintmax_t size = std::filesystem::file_size(path, code);
        if (code) reject(fmt::format("cannot read {}: {}", path.string(), code.message()));
        if (size > max_input_bytes) {
            reject(fmt::format("{} bytes is more than the limit of {}", size, max_input_bytes));
        }
        std::ifstream stream(path, std::ios::binary);
        std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
        if (!stream ||
            !stream.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
            reject(fmt::format("cannot read {}", path.string()));
        }
        std::string extension = path.extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (extension == ".glb" && !has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
        Source source;
        source.bytes = bytes;
        source.scene_name = path.stem().string();
        const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
        source.folder = std::filesystem::canonical(folder, code);
        if (code) reject(fmt::format("cannot resolve the folder of {}: {}", path.string(), code.message()));
        source.limits = limits;
        return import_bytes(source, label);
    });
}

Scene import_glb_memory(std::span<const std::uint8_t> bytes, const std::string& name,
                        const ImportLimits& limits) {
    return naming_faults(name, [&] {
        if (!has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
        Source source;
        source.bytes = bytes;
        source.scene_name = name;
        source.embedded_only = true;
        source.limits = limits;
        return import_bytes(source, name);
    });
}

}  // namespace bounce::scene
