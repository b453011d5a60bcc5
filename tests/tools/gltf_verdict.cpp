// Prints, for each glTF file given, whether Bounce's importer loads it: one JSON line per file,
// {"file", "loaded", "error" (when refused), "warnings"}. scripts/check-gltf-validator compares it
// with the Khronos glTF-Validator's findings.
#include "renderer/base/log.hpp"
#include "renderer/scene/gltf_import.hpp"

#include <nlohmann/json.hpp>

#include <iostream>

int main(int argc, char** argv) {
    bounce::log::set_level(bounce::log::Level::error);  // warnings go into the verdict, not stderr
    for (int i = 1; i < argc; ++i) {
        nlohmann::json verdict = {{"file", argv[i]}};
        try {
            const bounce::scene::Scene scene = bounce::scene::import_gltf_file(argv[i]);
            verdict["loaded"] = true;
            verdict["warnings"] = scene.warnings;
        } catch (const std::exception& error) {
            verdict["loaded"] = false;
            verdict["error"] = error.what();
        }
        std::cout << verdict.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    }
    return 0;
}
