// `cssm` bakes on disk (--cache-dir): one file per bake, named by a content key of everything the
// bake depends on (each object's geometry and transform, the bake parameters, the format), so a
// restarted daemon reuses it and a changed scene never reads a stale one. Files are written to a
// temporary name, synced and renamed into place: a bake killed midway leaves no file behind, only
// complete ones. A file that fails its length or checksum is ignored (and rebaked), never trusted.
#pragma once

#include "renderer/methods/cssm/cssm_bake.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace bounce::methods::cssm {

std::string bake_key(const scene::Scene& scene, const BakeParameters& parameters);
std::filesystem::path bake_path(const std::filesystem::path& dir, const std::string& key);

// The cached bake for `key`, completed for `scene` (albedo, tree); nullopt when there is none or it
// is damaged (logged).
std::optional<CssmBake> load_cached_bake(const std::filesystem::path& dir, const std::string& key,
                                         const scene::Scene& scene);
// Writes atomically; throws Error naming the path when the directory cannot be written.
void store_cached_bake(const std::filesystem::path& dir, const std::string& key, const CssmBake& bake);

}  // namespace bounce::methods::cssm
