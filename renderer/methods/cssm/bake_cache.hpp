// `cssm` bakes on disk (--cache-dir): one file per bake group, named by a content key of everything
// the group depends on (its objects' geometry, the static group's transforms, the bake parameters,
// the format), so a restarted daemon reuses it and a changed scene never reads a stale one. Files
// are written to a temporary name, synced and renamed into place: a bake killed midway leaves no
// file behind, only complete ones. A file that fails its length, checksum or structure checks is
// ignored (and rebaked), never trusted.
#pragma once

#include "renderer/methods/cssm/cssm_bake.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace bounce::methods::cssm {

// The key of a group of `objects`: a moving group's does not depend on where it stands.
std::string group_key(const scene::Scene& scene, const std::vector<std::uint32_t>& objects, bool moving,
                      const BakeParameters& parameters, float texel_size);
std::filesystem::path bake_path(const std::filesystem::path& dir, const std::string& key);

// The cached group for `key`, baked for `objects` (sorted indices into the scene); nullopt when
// there is none, it is of another format, or it is damaged: a wrong length or checksum, or any
// index out of range (logged).
std::optional<BakeGroup> load_cached_group(const std::filesystem::path& dir, const std::string& key,
                                           const std::vector<std::uint32_t>& objects);
// Writes atomically; throws Error naming the path when the directory cannot be written.
void store_cached_group(const std::filesystem::path& dir, const BakeGroup& group);

}  // namespace bounce::methods::cssm
