#include "renderer/methods/isr/imperfect_shadow_maps.hpp"

#include "renderer/scene/mesh_utils.hpp"

#include <algorithm>
#include <random>
#include <vector>

namespace bounce::methods::isr {
namespace {

constexpr std::size_t kPointBytes = 16;   // vec4
constexpr std::size_t kFrameBytes = 32;   // a map's centre and pole
constexpr std::size_t kTexelBytes = 4;  // the splatted bits; the filled pyramid, pyramid_texels()
// Threads per splat dispatch: bounded work per dispatch (GPU watchdogs), a cancel seen between.
constexpr std::uint64_t kSplatsPerDispatch = std::uint64_t{1} << 22;

std::uint64_t map_count(std::uint64_t views, int rsm_size, int level) {
    const auto side = static_cast<std::uint64_t>(rsm_size >> level);
    return views * side * side;
}

// Levels of a map's pull-push pyramid, down to one texel, and the texels of all of them.
int pyramid_levels(int size) {
    int levels = 1;
    while ((size >> levels) >= 1) ++levels;
    return levels;
}
std::uint64_t pyramid_texels(int size) {
    std::uint64_t texels = 0;
    for (int level = 0; level < pyramid_levels(size); ++level) {
        texels += static_cast<std::uint64_t>(size >> level) * static_cast<std::uint64_t>(size >> level);
    }
    return texels;
}

int top_level_of(int rsm_size) {
    int top_level = 0;
    while ((rsm_size >> top_level) > ISR_TOP_PATCHES && top_level + 1 < ISR_MAX_TREE_LEVELS) ++top_level;
    return top_level;
}

}  // namespace

int ImperfectShadowMaps::map_level(int tree_top_level, const IsmSettings& settings) {
    return std::max(0, tree_top_level - settings.levels_below_top);
}

std::uint64_t ImperfectShadowMaps::bytes_for(std::uint64_t views, int rsm_size, const IsmSettings& settings,
                                             std::uint64_t objects) {
    if (settings.size <= 0) return 0;
    const std::uint64_t maps = map_count(views, rsm_size, map_level(top_level_of(rsm_size), settings));
    std::uint64_t tree_nodes = 0;  // the coarse-map index has one entry per node of the VPL tree
    for (int level = 0; level <= top_level_of(rsm_size); ++level) tree_nodes += map_count(views, rsm_size, level);
    return maps * (static_cast<std::uint64_t>(settings.size) * static_cast<std::uint64_t>(settings.size) +
                   pyramid_texels(settings.size)) * kTexelBytes +
           maps * kFrameBytes + tree_nodes * 4 + std::uint64_t{kCloudPoints} * kPointBytes +
           std::max<std::uint64_t>(objects, 1) * sizeof(glm::mat4);
}

// kCloudPoints points spread over the scene's surfaces by world area, each kept in its object's
// space (so that a moved object carries its points), in random order: a map's run of consecutive
// points is a random sample. Alpha masks are not read: a masked card occludes as a whole card.
void ImperfectShadowMaps::make_cloud(const scene::Scene& scene) {
    const scene::AreaWeightedTriangles triangles(scene);
    std::vector<glm::vec4> cloud;
    if (!triangles.empty()) {
        cloud.reserve(kCloudPoints);
        std::mt19937 random(0x15Eu);
        std::uniform_real_distribution<double> uniform(0.0, 1.0);
        for (std::uint32_t i = 0; i < kCloudPoints; ++i) {
            const scene::AreaWeightedTriangles::Triangle& t = triangles.pick(uniform(random));
            const scene::Primitive& primitive =
                scene.meshes[static_cast<std::size_t>(scene.objects[t.object].mesh)].primitives[t.primitive];
            const std::uint32_t* corner = &primitive.indices[3 * static_cast<std::size_t>(t.triangle)];
            double u = uniform(random), v = uniform(random);
            if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
            const glm::vec3 a = primitive.positions[corner[0]], b = primitive.positions[corner[1]],
                            c = primitive.positions[corner[2]];
            cloud.emplace_back(a + static_cast<float>(u) * (b - a) + static_cast<float>(v) * (c - a),
                               static_cast<float>(t.object));
        }
    }
    cloud_points_ = static_cast<std::uint32_t>(cloud.size());
    cloud_ = gpu::storage_of(cloud);
}

bool ImperfectShadowMaps::build(const passes::PassContext& context, const VplTree& tree, const IsmSettings& settings,
                                std::uint64_t patches, const std::function<void()>& interruption) {
    if (patches == patches_ && settings == settings_ && filled_) return false;
    gpu::GpuTimers::Scope timing(context.timers, "isr_imperfect_shadow_maps");
    settings_ = settings;
    patches_ = patches;
    ++builds_;
    if (!cloud_) make_cloud(context.scene);
    level_ = map_level(tree.top_level(), settings);
    maps_ = map_count(static_cast<std::uint64_t>(tree.views()), tree.size(), level_);
    scene_radius_ = std::max(0.5f * glm::length(context.scene.world_bounds().extent()), 1e-30f);

    std::vector<glm::mat4> transforms;
    for (const scene::Object& object : context.scene.objects) transforms.push_back(object.transform);
    transforms_ = gpu::storage_of(transforms);

    const std::uint64_t texels = maps_ * static_cast<std::uint64_t>(settings.size) * static_cast<std::uint64_t>(settings.size);
    const std::size_t texel_bytes = std::max<std::size_t>(static_cast<std::size_t>(texels), 1) * 4;
    const std::size_t pyramid_bytes =
        std::max<std::size_t>(static_cast<std::size_t>(maps_ * pyramid_texels(settings.size)), 1) * 4;
    if (depth_.bytes() != texel_bytes) depth_ = gpu::Buffer(texel_bytes, nullptr);
    if (filled_.bytes() != pyramid_bytes) filled_ = gpu::Buffer(pyramid_bytes, nullptr);
    const GLuint empty = 0xFFFFFFFFu;
    glClearNamedBufferData(depth_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty);
    if (maps_ == 0 || cloud_points_ == 0) {
        glClearNamedBufferData(filled_.id(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
        return true;
    }
    const std::size_t frame_bytes = std::max<std::size_t>(static_cast<std::size_t>(maps_), 1) * kFrameBytes;
    if (frames_.bytes() != frame_bytes) frames_ = gpu::Buffer(frame_bytes, nullptr);
    const std::size_t coarse_bytes = std::max<std::size_t>(tree.nodes(), 1) * 4;
    if (coarse_.bytes() != coarse_bytes) coarse_ = gpu::Buffer(coarse_bytes, nullptr);
    gpu::bind_storage(ISR_BINDING_ISM_FRAMES, frames_);
    gpu::bind_storage(ISR_BINDING_ISM_COARSE, coarse_);
    const gpu::ShaderProgram& frames = context.shaders.get(gpu::ProgramSource::compute_shader("isr/ism_frames.comp"));
    tree.bind(frames);
    set_uniforms(frames);
    frames.set("u_views", tree.views());
    frames.set("u_pass", 0);
    frames.dispatch_threads(maps_);
    frames.set("u_pass", 1);
    for (int level = level_ + 1; level <= tree.top_level(); ++level) {
        const auto side = static_cast<std::size_t>(tree.size() >> level);
        frames.set("u_level", level);
        frames.dispatch_threads(static_cast<std::size_t>(tree.views()) * side * side);
    }
    gpu::storage_barrier();

    gpu::bind_storage(ISR_BINDING_ISM_POINTS, cloud_);
    gpu::bind_storage(ISR_BINDING_ISM_TRANSFORMS, transforms_);
    gpu::bind_storage(ISR_BINDING_ISM_DEPTH, depth_);
    gpu::bind_storage(ISR_BINDING_ISM_FILLED, filled_);

    const gpu::ShaderProgram& splat = context.shaders.get(gpu::ProgramSource::compute_shader("isr/ism_splat.comp"));
    tree.bind(splat);
    set_uniforms(splat);
    const auto points = static_cast<std::uint64_t>(settings.points_per_map);
    const std::uint64_t maps_per_dispatch = std::max<std::uint64_t>(1, kSplatsPerDispatch / points);
    splat.set("u_points_per_map", static_cast<unsigned>(points));
    splat.set("u_cloud_size", cloud_points_);
    for (std::uint64_t first = 0; first < maps_; first += maps_per_dispatch) {
        const std::uint64_t count = std::min(maps_per_dispatch, maps_ - first);
        splat.set("u_first_map", static_cast<unsigned>(first));
        splat.set("u_maps", static_cast<unsigned>(count));
        splat.dispatch_threads(count * points);
        if (interruption) interruption();
    }
    gpu::storage_barrier();

    // Pull-push: the pyramid's levels up from the splat, then back down.
    const gpu::ShaderProgram& pull = context.shaders.get(gpu::ProgramSource::compute_shader("isr/ism_pull.comp"));
    const gpu::ShaderProgram& push = context.shaders.get(gpu::ProgramSource::compute_shader("isr/ism_push.comp"));
    for (const gpu::ShaderProgram* program : {&pull, &push}) {
        tree.bind(*program);
        set_uniforms(*program);
    }
    push.set("u_dilation_levels", settings.dilation_levels);
    const auto level_texels = [&](int level) {
        const auto side = static_cast<std::uint64_t>(settings.size >> level);
        return maps_ * side * side;
    };
    const int top = pyramid_levels(settings.size) - 1;
    for (int level = 0; level <= top; ++level) {
        pull.set("u_level", level);
        pull.dispatch_threads(level_texels(level));
        gpu::storage_barrier();
    }
    for (int level = top - 1; level >= 0; --level) {
        push.set("u_level", level);
        push.dispatch_threads(level_texels(level));
        gpu::storage_barrier();
    }
    return true;
}

void ImperfectShadowMaps::set_uniforms(const gpu::ShaderProgram& program) const {
    program.set("u_ism_size", settings_.size);
    program.set("u_ism_maps", static_cast<unsigned>(maps_));
    program.set("u_ism_level", level_);
    // A texel covers 4 / size radians at a map's centre (the paraboloid's disk is tan(theta / 2)).
    program.set("u_ism_texel_angle", 4.0f / static_cast<float>(std::max(settings_.size, 1)));
    program.set("u_ism_bias_absolute", 1e-3f * scene_radius_);
}

void ImperfectShadowMaps::release() {
    const std::size_t builds = builds_;
    *this = ImperfectShadowMaps();
    builds_ = builds;
}

void ImperfectShadowMaps::bind(const gpu::ShaderProgram& program) const {
    gpu::bind_storage(ISR_BINDING_ISM_FILLED, filled_);
    gpu::bind_storage(ISR_BINDING_ISM_FRAMES, frames_);
    gpu::bind_storage(ISR_BINDING_ISM_COARSE, coarse_);
    set_uniforms(program);
}

}  // namespace bounce::methods::isr
