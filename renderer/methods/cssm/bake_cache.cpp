#include "renderer/methods/cssm/bake_cache.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <type_traits>
#include <unistd.h>

namespace bounce::methods::cssm {
namespace {

constexpr char kMagic[8] = {'B', 'N', 'C', 'S', 'S', 'M', '0', '1'};

struct Fnv {
    std::uint64_t hash = 1469598103934665603ull;
    void add(const void* data, std::size_t bytes) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
    }
    template <typename T>
    void add(const std::vector<T>& values) {
        const std::uint64_t count = values.size();
        add(&count, sizeof(count));
        if (!values.empty()) add(values.data(), values.size() * sizeof(T));
    }
};

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

std::vector<char> serialize(const CssmBake& bake) {
    Writer w;
    w.value(bake.parameters.atlas_resolution);
    w.value(bake.parameters.face_size);
    w.value(static_cast<int>(bake.parameters.traversal));
    const SurfaceAtlas& atlas = bake.atlas;
    w.value(atlas.width);
    w.value(atlas.height);
    w.value(atlas.surface_area);
    w.array(atlas.texels);
    w.array(atlas.charts);
    w.array(atlas.texel_at);
    w.array(atlas.objects);
    w.value(static_cast<std::uint64_t>(atlas.uv1_objects.size()));
    for (const std::string& name : atlas.uv1_objects) w.text(name);
    const SurfaceShadowMaps& maps = bake.maps;
    w.value(maps.settings);
    w.array(maps.order);
    w.array(maps.map_of_texel);
    w.array(maps.origins);
    w.value(maps.bake_seconds);
    w.value(maps.depth.maps);
    w.value(maps.depth.pixels);
    w.array(maps.depth.pixel_runs);
    w.array(maps.depth.run_start);
    w.array(maps.depth.run_depth);
    return std::move(w.bytes);
}

CssmBake deserialize(const std::vector<char>& payload) {
    Reader r(payload);
    CssmBake bake;
    bake.parameters.atlas_resolution = r.value<float>();
    bake.parameters.face_size = r.value<int>();
    bake.parameters.traversal = static_cast<Traversal>(r.value<int>());
    SurfaceAtlas& atlas = bake.atlas;
    atlas.width = r.value<int>();
    atlas.height = r.value<int>();
    atlas.surface_area = r.value<float>();
    atlas.texels = r.array<AtlasTexel>();
    atlas.charts = r.array<AtlasChart>();
    atlas.texel_at = r.array<std::int32_t>();
    atlas.objects = r.array<std::uint32_t>();
    const auto names = r.value<std::uint64_t>();
    for (std::uint64_t i = 0; i < names && i < 1u << 20; ++i) atlas.uv1_objects.push_back(r.text());
    SurfaceShadowMaps& maps = bake.maps;
    maps.settings = r.value<CubeMapSettings>();
    maps.order = r.array<std::uint32_t>();
    maps.map_of_texel = r.array<std::uint32_t>();
    maps.origins = r.array<glm::vec3>();
    maps.bake_seconds = r.value<double>();
    maps.depth.maps = r.value<std::uint32_t>();
    maps.depth.pixels = r.value<std::uint32_t>();
    maps.depth.pixel_runs = r.array<std::uint32_t>();
    maps.depth.run_start = r.array<std::uint32_t>();
    maps.depth.run_depth = r.array<std::uint16_t>();
    if (!r.at_end()) throw Error("trailing bytes");
    // Structural checks: what the GPU indexes must be in range.
    const std::size_t texels = atlas.texels.size();
    if (maps.order.size() != texels || maps.map_of_texel.size() != texels || maps.origins.size() != texels ||
        maps.depth.maps != texels || maps.depth.pixel_runs.size() != static_cast<std::size_t>(maps.depth.pixels) + 1 ||
        maps.depth.run_start.size() != maps.depth.run_depth.size() ||
        (maps.depth.pixels > 0 && maps.depth.pixel_runs.back() != maps.depth.run_start.size()) ||
        maps.depth.pixels != static_cast<std::uint32_t>(6 * maps.settings.face_size * maps.settings.face_size)) {
        throw Error("inconsistent sizes");
    }
    for (std::uint32_t m : maps.map_of_texel)
        if (m >= texels) throw Error("map index out of range");
    for (std::uint32_t p = 0; p < maps.depth.pixels; ++p)
        if (maps.depth.pixel_runs[p] >= maps.depth.pixel_runs[p + 1]) throw Error("a pixel without runs");
    return bake;
}

}  // namespace

std::string bake_key(const scene::Scene& scene, const BakeParameters& parameters) {
    Fnv fnv;
    fnv.add(kMagic, sizeof(kMagic));
    fnv.add(&parameters.atlas_resolution, sizeof(float));
    fnv.add(&parameters.face_size, sizeof(int));
    const int traversal = static_cast<int>(parameters.traversal);
    fnv.add(&traversal, sizeof(int));
    for (const scene::Object& object : scene.objects) {
        fnv.add(&object.mesh, sizeof(int));
        fnv.add(&object.transform, sizeof(glm::mat4));
        if (object.mesh < 0) continue;
        for (const scene::Primitive& primitive : scene.meshes[object.mesh].primitives) {
            fnv.add(primitive.positions);
            fnv.add(primitive.normals);
            fnv.add(primitive.uv0);
            fnv.add(primitive.uv1);
            fnv.add(primitive.indices);
            fnv.add(&primitive.material, sizeof(int));
        }
    }
    return fmt::format("{:016x}", fnv.hash);
}

std::filesystem::path bake_path(const std::filesystem::path& dir, const std::string& key) {
    return dir / fmt::format("cssm-{}.bake", key);
}

std::optional<CssmBake> load_cached_bake(const std::filesystem::path& dir, const std::string& key,
                                         const scene::Scene& scene) {
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
        Fnv fnv;
        fnv.add(payload.data(), payload.size());
        if (fnv.hash != checksum) throw Error("checksum does not match");
        CssmBake bake = deserialize(payload);
        complete_bake(scene, bake);
        return bake;
    } catch (const std::exception& error) {
        log::warn("cssm", "ignoring cached bake {}: {}", path.string(), error.what());
        return std::nullopt;
    }
}

void store_cached_bake(const std::filesystem::path& dir, const std::string& key, const CssmBake& bake) {
    static std::atomic<std::uint64_t> counter{0};
    std::error_code ignored;
    std::filesystem::create_directories(dir, ignored);
    const std::vector<char> payload = serialize(bake);
    Fnv fnv;
    fnv.add(payload.data(), payload.size());
    const std::filesystem::path final_path = bake_path(dir, key);
    const std::filesystem::path temporary =
        dir / fmt::format(".{}.tmp-{}-{}", final_path.filename().string(), ::getpid(), counter.fetch_add(1));
    std::FILE* file = std::fopen(temporary.c_str(), "wb");
    if (!file) BOUNCE_FAIL("cssm: cannot write the bake cache {}: {}", temporary.string(), std::strerror(errno));
    const std::uint64_t size = payload.size();
    bool ok = std::fwrite(kMagic, 1, sizeof(kMagic), file) == sizeof(kMagic) &&
              std::fwrite(&size, sizeof(size), 1, file) == 1 && std::fwrite(&fnv.hash, sizeof(fnv.hash), 1, file) == 1 &&
              std::fwrite(payload.data(), 1, payload.size(), file) == payload.size();
    ok = std::fflush(file) == 0 && ok;
    ok = ::fsync(::fileno(file)) == 0 && ok;
    ok = std::fclose(file) == 0 && ok;
    if (!ok) {
        std::filesystem::remove(temporary, ignored);
        BOUNCE_FAIL("cssm: writing the bake cache {} failed: {}", temporary.string(), std::strerror(errno));
    }
    std::filesystem::rename(temporary, final_path);  // atomic within one file system
}

}  // namespace bounce::methods::cssm
