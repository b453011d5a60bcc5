#include "renderer/methods/cssm/bake_cache.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <type_traits>
#include <sys/stat.h>
#include <unistd.h>

namespace bounce::methods::cssm {
namespace {

// Format 09: cube-map depths stay their bias short of second hits (biased_interval); 08: texels a
// chart covers in part carry that part's area, at its middle (surface_atlas.cpp);
// 07: texels partly inside a solid stand on the rest of their patch (buried_texels.hpp); 06:
// each texel carries its direct light's sample points, and double-sided surfaces their backs (05);
// 04: XXH3 checksums and keys (03 had FNV-1a). Files of another format are stale.
constexpr char kMagic[8] = {'B', 'N', 'C', 'S', 'S', 'M', '0', '9'};

class Writer {
public:
    template <typename T>
    void value(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* p = reinterpret_cast<const char*>(&v);
        bytes.insert(bytes.end(), p, p + sizeof(T));
    }
    template <typename T>
    void array(const std::vector<T>& values) {
        value(static_cast<std::uint64_t>(values.size()));
        const auto* p = reinterpret_cast<const char*>(values.data());
        bytes.insert(bytes.end(), p, p + values.size() * sizeof(T));
    }
    void text(const std::string& s) { array(std::vector<char>(s.begin(), s.end())); }
    std::vector<char> bytes;
};

class Reader {
public:
    explicit Reader(const std::vector<char>& data) : data_(data) {}
    template <typename T>
    T value() {
        T v;
        take(&v, sizeof(T));
        return v;
    }
    template <typename T>
    std::vector<T> array() {
        const auto count = value<std::uint64_t>();
        if (count > (data_.size() - offset_) / std::max<std::size_t>(sizeof(T), 1)) throw Error("array longer than the file");
        std::vector<T> values(count);
        take(values.data(), count * sizeof(T));
        return values;
    }
    std::string text() {
        const auto chars = array<char>();
        return std::string(chars.begin(), chars.end());
    }
    bool at_end() const { return offset_ == data_.size(); }

private:
    void take(void* out, std::size_t bytes) {
        if (bytes > data_.size() - offset_) throw Error("file ends early");
        std::memcpy(out, data_.data() + offset_, bytes);
        offset_ += bytes;
    }
    const std::vector<char>& data_;
    std::size_t offset_ = 0;
};

void write_depth(Writer& w, const CompressedDepthMaps& depth) {
    w.value(depth.maps);
    w.value(depth.pixels);
    w.array(depth.pixel_runs);
    w.array(depth.run_start);
    w.array(depth.run_depth);
}

CompressedDepthMaps read_depth(Reader& r) {
    CompressedDepthMaps depth;
    depth.maps = r.value<std::uint32_t>();
    depth.pixels = r.value<std::uint32_t>();
    depth.pixel_runs = r.array<std::uint32_t>();
    depth.run_start = r.array<std::uint32_t>();
    depth.run_depth = r.array<std::uint16_t>();
    // What the GPU indexes must be in range.
    if (depth.pixel_runs.size() != static_cast<std::size_t>(depth.pixels) + 1 || depth.run_start.size() != depth.run_depth.size() ||
        (depth.pixels > 0 && depth.pixel_runs.back() != depth.run_start.size())) {
        throw Error("inconsistent run tables");
    }
    for (std::uint32_t p = 0; p < depth.pixels; ++p)
        if (depth.pixel_runs[p] >= depth.pixel_runs[p + 1]) throw Error("a pixel without runs");
    for (std::uint32_t start : depth.run_start)
        if (start >= depth.maps) throw Error("a run past the last map");
    return depth;
}

// Face sides the bake knobs allow, with room: their pixel counts fit 32 bits.
bool valid_face_size(int face_size) { return face_size > 0 && face_size <= 4096; }

std::uint32_t face_pixels(int face_size, std::uint32_t faces) {
    return faces * static_cast<std::uint32_t>(face_size) * static_cast<std::uint32_t>(face_size);
}

// Every index the atlas holds names something in it, and its texels only the group's `objects`.
void check_atlas(const SurfaceAtlas& atlas, const std::vector<std::uint32_t>& objects) {
    if (atlas.objects != objects) throw Error("written for other objects");
    if (atlas.width < 0 || atlas.height < 0 ||
        atlas.texel_at.size() != static_cast<std::size_t>(atlas.width) * static_cast<std::size_t>(atlas.height)) {
        throw Error("inconsistent atlas size");
    }
    const std::size_t texels = atlas.texels.size();
    for (std::int32_t t : atlas.texel_at)
        if (t < -1 || (t >= 0 && static_cast<std::size_t>(t) >= texels)) throw Error("atlas texel index out of range");
    for (std::size_t t = 0; t < texels; ++t) {
        const AtlasTexel& texel = atlas.texels[t];
        if (!std::binary_search(objects.begin(), objects.end(), texel.object)) throw Error("texel object out of range");
        if (texel.chart >= atlas.charts.size() || atlas.charts[texel.chart].object != texel.object) {
            throw Error("texel chart out of range");
        }
        if (atlas.at(texel.x, texel.y) != static_cast<std::int32_t>(t)) throw Error("texel position out of range");
    }
}

void check_maps(const SurfaceShadowMaps& maps, std::size_t texels) {
    if (!valid_face_size(maps.settings.face_size) || maps.order.size() != texels || maps.map_of_texel.size() != texels ||
        maps.origins.size() != texels || maps.depth.maps != texels || maps.depth.pixels != face_pixels(maps.settings.face_size, 6)) {
        throw Error("inconsistent sizes");
    }
    std::vector<std::uint8_t> ordered(texels, 0);
    for (std::uint32_t t : maps.order) {
        if (t >= texels || ordered[t] != 0) throw Error("traversal order index out of range");
        ordered[t] = 1;
    }
    for (std::uint32_t m : maps.map_of_texel)
        if (m >= texels) throw Error("map index out of range");
}

std::vector<char> serialize(const BakeGroup& group) {
    Writer w;
    w.text(group.key);
    const SurfaceAtlas& atlas = group.atlas;
    w.value(atlas.width);
    w.value(atlas.height);
    w.value(atlas.surface_area);
    w.array(atlas.texels);
    w.array(atlas.charts);
    w.array(atlas.texel_at);
    w.array(atlas.objects);
    w.value(static_cast<std::uint64_t>(atlas.uv1_objects.size()));
    for (const std::string& name : atlas.uv1_objects) w.text(name);
    const SurfaceShadowMaps& maps = group.maps;
    w.value(maps.settings);
    w.array(maps.order);
    w.array(maps.map_of_texel);
    w.array(maps.origins);
    w.value(maps.bake_seconds);
    write_depth(w, maps.depth);
    w.value(static_cast<std::uint8_t>(group.csm ? 1 : 0));
    if (group.csm) {
        w.value(group.csm->face_size);
        w.value(group.csm->centre);
        w.value(group.csm->radius);
        w.array(group.csm->directions);
        w.array(group.csm->nearest_map);
        w.value(group.csm->bake_seconds);
        write_depth(w, group.csm->depth);
    }
    return std::move(w.bytes);
}

BakeGroup deserialize(const std::vector<char>& payload, const std::string& key, const std::vector<std::uint32_t>& objects) {
    Reader r(payload);
    BakeGroup group;
    group.key = r.text();
    if (group.key != key) throw Error("written for another key");
    SurfaceAtlas& atlas = group.atlas;
    atlas.width = r.value<int>();
    atlas.height = r.value<int>();
    atlas.surface_area = r.value<float>();
    atlas.texels = r.array<AtlasTexel>();
    atlas.charts = r.array<AtlasChart>();
    atlas.texel_at = r.array<std::int32_t>();
    atlas.objects = r.array<std::uint32_t>();
    const auto names = r.value<std::uint64_t>();
    for (std::uint64_t i = 0; i < names && i < 1u << 20; ++i) atlas.uv1_objects.push_back(r.text());
    SurfaceShadowMaps& maps = group.maps;
    maps.settings = r.value<CubeMapSettings>();
    maps.order = r.array<std::uint32_t>();
    maps.map_of_texel = r.array<std::uint32_t>();
    maps.origins = r.array<glm::vec3>();
    maps.bake_seconds = r.value<double>();
    maps.depth = read_depth(r);
    if (r.value<std::uint8_t>() != 0) {
        CoherentShadowMaps csm;
        csm.face_size = r.value<int>();
        csm.centre = r.value<glm::vec3>();
        csm.radius = r.value<float>();
        csm.directions = r.array<glm::vec4>();
        csm.nearest_map = r.array<std::uint32_t>();
        csm.bake_seconds = r.value<double>();
        csm.depth = read_depth(r);
        if (!valid_face_size(csm.face_size) || csm.depth.maps != csm.directions.size() ||
            csm.depth.pixels != face_pixels(csm.face_size, 1) || csm.nearest_map.size() != face_pixels(kCsmTableFace, 6)) {
            throw Error("inconsistent coherent shadow maps");
        }
        for (std::uint32_t k : csm.nearest_map)
            if (k >= csm.directions.size()) throw Error("a direction past the last map");
        group.csm = std::move(csm);
    }
    if (!r.at_end()) throw Error("trailing bytes");
    check_atlas(atlas, objects);
    check_maps(maps, atlas.texels.size());
    return group;
}

}  // namespace

std::string group_key(const scene::Scene& scene, const std::vector<std::uint32_t>& objects, bool moving,
                      const BakeParameters& parameters, float texel_size) {
    Hasher hash;
    hash.add_bytes(kMagic, sizeof(kMagic));
    hash.add(parameters.face_size);
    hash.add(static_cast<int>(parameters.traversal));
    hash.add(texel_size);
    hash.add(static_cast<std::uint8_t>(moving ? 1 : 0));
    if (moving) hash.add(parameters.csm_directions);
    for (std::uint32_t o : objects) {
        const scene::Object& object = scene.objects[o];
        if (!moving) hash.add(object.transform);  // a moving group is baked in its own space
        for (const scene::Primitive& primitive : scene.meshes[object.mesh].primitives) {
            hash.add_span<glm::vec3>(primitive.positions);
            hash.add_span<glm::vec3>(primitive.normals);
            hash.add_span<glm::vec2>(primitive.uv0);
            hash.add_span<glm::vec2>(primitive.uv1);
            hash.add_span<std::uint32_t>(primitive.indices);
            hash.add(primitive.material);
            hash.add(static_cast<std::uint8_t>(scene.material(primitive.material).double_sided ? 1 : 0));  // its back's texels
        }
    }
    return fmt::format("{:016x}", hash.value());
}

std::filesystem::path bake_path(const std::filesystem::path& dir, const std::string& key) {
    return dir / fmt::format("cssm-{}.bake", key);
}

std::optional<BakeGroup> load_cached_group(const std::filesystem::path& dir, const std::string& key,
                                          const std::vector<std::uint32_t>& objects) {
    const std::filesystem::path path = bake_path(dir, key);
    std::ifstream file(path, std::ios::binary);
    if (!file) return std::nullopt;
    try {
        char magic[sizeof(kMagic)];
        std::uint64_t size = 0, checksum = 0;
        file.read(magic, sizeof(magic));
        file.read(reinterpret_cast<char*>(&size), sizeof(size));
        file.read(reinterpret_cast<char*>(&checksum), sizeof(checksum));
        if (!file || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) throw Error("not a bake of this format");
        const auto file_size = std::filesystem::file_size(path);
        if (size != file_size - sizeof(kMagic) - 2 * sizeof(std::uint64_t)) throw Error("length does not match");
        std::vector<char> payload(size);
        file.read(payload.data(), static_cast<std::streamsize>(size));
        if (!file) throw Error("file ends early");
        if (hash_bytes(payload.data(), payload.size()) != checksum) throw Error("checksum does not match");
        return deserialize(payload, key, objects);
    } catch (const std::exception& error) {
        log::warn("cssm", "ignoring cached bake {}: {}", path.string(), error.what());
        return std::nullopt;
    }
}

namespace {

// Temporary files are named ".cssm-<key>.bake.tmp-<pid>-<random>": the pid says whether the writer
// still lives, so a writer that died mid-write (killed, power lost) leaves nothing behind for long.
// Only this cache's own temporaries are touched, and only those an hour old: a writer in another
// pid namespace (a container sharing the directory) may show as dead, but no bake takes an hour
// to write.
constexpr std::string_view kTemporaryMark = ".tmp-";

void remove_leftovers_once(const std::filesystem::path& dir) {
    static std::mutex mutex;
    static std::set<std::filesystem::path> cleaned;
    std::lock_guard lock(mutex);
    if (!cleaned.insert(dir).second) return;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
        const std::string name = entry.path().filename().string();
        const auto mark = name.find(kTemporaryMark);
        if (!name.starts_with(".cssm-") || mark == std::string::npos) continue;
        const long pid = std::strtol(name.c_str() + mark + kTemporaryMark.size(), nullptr, 10);
        std::error_code age_error;
        const auto age = std::filesystem::file_time_type::clock::now() - entry.last_write_time(age_error);
        if (pid <= 0 || age_error || age < std::chrono::hours(1)) continue;
        if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
            std::error_code ignored;
            if (std::filesystem::remove(entry.path(), ignored)) {
                log::info("cssm", "removed {}, left by a bake writer that is gone", entry.path().string());
            }
        }
    }
}

}  // namespace

void store_cached_group(const std::filesystem::path& dir, const BakeGroup& group) {
    std::error_code ignored;
    std::filesystem::create_directories(dir, ignored);
    remove_leftovers_once(dir);
    const std::vector<char> payload = serialize(group);
    const std::uint64_t checksum = hash_bytes(payload.data(), payload.size());
    const std::filesystem::path final_path = bake_path(dir, group.key);
    // Created exclusively with an unpredictable name (mkstemp), never opened over someone's file.
    std::string name = (dir / fmt::format(".{}{}{}-XXXXXX", final_path.filename().string(), kTemporaryMark, ::getpid()))
                           .string();
    const int descriptor = ::mkstemp(name.data());
    if (descriptor < 0) BOUNCE_FAIL("cssm: cannot create a file in the bake cache {}: {}", dir.string(), std::strerror(errno));
    const std::filesystem::path temporary(name);
    // mkstemp makes the file owner-only; a cache may be shared with other users (a CLI, the bench).
    ::fchmod(descriptor, 0644);
    std::FILE* file = ::fdopen(descriptor, "wb");
    if (!file) {
        ::close(descriptor);
        std::filesystem::remove(temporary, ignored);
        BOUNCE_FAIL("cssm: cannot write the bake cache {}: {}", temporary.string(), std::strerror(errno));
    }
    const std::uint64_t size = payload.size();
    bool ok = std::fwrite(kMagic, 1, sizeof(kMagic), file) == sizeof(kMagic) &&
              std::fwrite(&size, sizeof(size), 1, file) == 1 && std::fwrite(&checksum, sizeof(checksum), 1, file) == 1 &&
              std::fwrite(payload.data(), 1, payload.size(), file) == payload.size();
    ok = std::fflush(file) == 0 && ok;
    ok = ::fsync(::fileno(file)) == 0 && ok;
    ok = std::fclose(file) == 0 && ok;
    if (!ok) {
        std::filesystem::remove(temporary, ignored);
        BOUNCE_FAIL("cssm: writing the bake cache {} failed: {}", temporary.string(), std::strerror(errno));
    }
    std::error_code renamed;
    std::filesystem::rename(temporary, final_path, renamed);  // atomic within one file system
    if (renamed) {
        std::filesystem::remove(temporary, ignored);
        BOUNCE_FAIL("cssm: cannot move the bake into place as {}: {}", final_path.string(), renamed.message());
    }
}

}  // namespace bounce::methods::cssm
