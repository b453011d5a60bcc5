#include "renderer/methods/cssm/surface_atlas.hpp"

#include "renderer/base/error.hpp"
#include "renderer/scene/mesh_utils.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <tuple>

namespace bounce::methods::cssm {
namespace {

struct TriangleRef {
    const scene::Primitive* primitive;
    std::uint32_t index;  // triangle index within the primitive
    std::uint32_t vertex(int corner) const { return primitive->indices[3 * index + corner]; }
};

// A chart before packing: its texels on a local grid of w x h.
struct PackItem {
    int width = 0, height = 0;
    std::vector<AtlasTexel> texels;  // x, y local; chart local to this item
    std::uint32_t charts = 0;
    std::vector<glm::vec3> centroids;     // per local chart, object space
    std::vector<float> centroid_weights;  // per local chart
};

float edge_function(const glm::vec2& a, const glm::vec2& b, const glm::vec2& p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Texel centres inside the 2D triangle `q` (texel units), with barycentrics. `strict` leaves out
// centres on an edge (for overlap checks).
template <typename Visit>
void rasterize(const glm::vec2 (&q)[3], bool strict, Visit&& visit) {
    const float area = edge_function(q[0], q[1], q[2]);
    if (!(std::abs(area) > 1e-12f)) return;
    const glm::vec2 lo = glm::min(q[0], glm::min(q[1], q[2])), hi = glm::max(q[0], glm::max(q[1], q[2]));
    const float tolerance = strict ? 1e-4f * std::abs(area) : -1e-5f * std::abs(area);
    for (int y = static_cast<int>(std::floor(lo.y)); y <= static_cast<int>(std::ceil(hi.y)); ++y) {
        for (int x = static_cast<int>(std::floor(lo.x)); x <= static_cast<int>(std::ceil(hi.x)); ++x) {
            const glm::vec2 p(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
            const float w0 = edge_function(q[1], q[2], p) / area, w1 = edge_function(q[2], q[0], p) / area,
                        w2 = edge_function(q[0], q[1], p) / area;
            const float t = tolerance / std::abs(area);
            if (w0 > t && w1 > t && w2 > t) visit(x, y, glm::vec3(w0, w1, w2));
        }
    }
}

AtlasTexel texel_from(const TriangleRef& triangle, const glm::vec3& barycentric, std::uint32_t object, std::uint32_t chart,
                      int x, int y) {
    const scene::Primitive& primitive = *triangle.primitive;
    AtlasTexel texel;
    glm::vec3 normal(0.0f);
    for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = triangle.vertex(c);
        texel.position += barycentric[c] * primitive.positions[v];
        normal += barycentric[c] * primitive.normals[v];
        if (!primitive.uv0.empty()) texel.uv0 += barycentric[c] * primitive.uv0[v];
        if (!primitive.uv1.empty()) texel.uv1 += barycentric[c] * primitive.uv1[v];
    }
    const glm::vec3 p0 = primitive.positions[triangle.vertex(0)], p1 = primitive.positions[triangle.vertex(1)],
                    p2 = primitive.positions[triangle.vertex(2)];
    const glm::vec3 face = glm::cross(p1 - p0, p2 - p0);
    texel.normal = glm::length(normal) > 1e-20f ? glm::normalize(normal) : glm::normalize(face);
    if (primitive.uv1.empty()) texel.uv1 = texel.uv0;
    texel.object = object;
    texel.chart = chart;
    texel.material = primitive.material;
    texel.x = x;
    texel.y = y;
    texel.samples.fill(texel.position);
    return texel;
}

glm::vec3 surface_point(const TriangleRef& triangle, const glm::vec3& barycentric) {
    glm::vec3 point(0.0f);
    for (int c = 0; c < 3; ++c) point += barycentric[c] * triangle.primitive->positions[triangle.vertex(c)];
    return point;
}

// A texel's sub-cells found so far: bit i for sub-cell i (x + kTexelSamplesPerSide y within the texel).
using SubCells = std::vector<std::uint16_t>;
static_assert(kTexelSamples <= 16);

// Rasterizes `triangle` (at `q`, texel units of its chart) at kTexelSamplesPerSide times the
// resolution: each sub-cell centre it covers becomes a sample of the texel whose cell holds it
// (`texel_at`: its index in `texels`, or -1), once.
template <typename TexelAt>
void sample_sub_cells(const TriangleRef& triangle, const glm::vec2 (&q)[3], std::vector<AtlasTexel>& texels,
                      SubCells& found, TexelAt&& texel_at) {
    constexpr int kSide = kTexelSamplesPerSide;
    const glm::vec2 finer[3] = {static_cast<float>(kSide) * q[0], static_cast<float>(kSide) * q[1], static_cast<float>(kSide) * q[2]};
    rasterize(finer, false, [&](int x, int y, const glm::vec3& barycentric) {
        if (x < 0 || y < 0) return;
        const std::int32_t t = texel_at(x / kSide, y / kSide);
        if (t < 0) return;
        const auto bit = static_cast<std::uint16_t>(1u << ((y % kSide) * kSide + x % kSide));
        if (found[static_cast<std::size_t>(t)] & bit) return;
        found[static_cast<std::size_t>(t)] |= bit;
        const int slot = std::popcount(static_cast<unsigned>(found[static_cast<std::size_t>(t)])) - 1;
        texels[static_cast<std::size_t>(t)].samples[static_cast<std::size_t>(slot)] = surface_point(triangle, barycentric);
    });
}

// A texel standing for a whole chart of `members`: its samples at four points of each triangle (its
// centroid and its three corner sub-triangles' centroids), spread evenly where there are more.
void spread_samples(AtlasTexel& texel, const scene::Primitive& primitive, const std::vector<std::uint32_t>& members) {
    static constexpr glm::vec3 kPoints[4] = {{1.0f / 3.0f, 1.0f / 3.0f, 1.0f / 3.0f},
                                             {2.0f / 3.0f, 1.0f / 6.0f, 1.0f / 6.0f},
                                             {1.0f / 6.0f, 2.0f / 3.0f, 1.0f / 6.0f},
                                             {1.0f / 6.0f, 1.0f / 6.0f, 2.0f / 3.0f}};
    const std::size_t candidates = 4 * members.size();
    for (std::size_t slot = 0; slot < static_cast<std::size_t>(kTexelSamples); ++slot) {
        const std::size_t c = slot * candidates / kTexelSamples;  // evenly over them, in order
        texel.samples[slot] = surface_point(TriangleRef{&primitive, members[c / 4]}, kPoints[c % 4]);
    }
}

// Texels with fewer than kTexelSamples sub-cells on their surface repeat the ones they have (their
// centre where none: a chart narrower than half a texel).
void complete_samples(std::vector<AtlasTexel>& texels, const SubCells& found) {
    for (std::size_t t = 0; t < texels.size(); ++t) {
        const int count = std::popcount(static_cast<unsigned>(found[t]));
        if (count == 0) {
            texels[t].samples.fill(texels[t].position);
            continue;
        }
        for (int slot = count; slot < kTexelSamples; ++slot) texels[t].samples[static_cast<std::size_t>(slot)] = texels[t].samples[static_cast<std::size_t>(slot % count)];
    }
}

// A texel that its chart covers in part carries that part's share of the area, and stands at its
// sample nearest the part's centroid (a sample lies on the surface; the centroid of a curved chart's
// part may not). Beside a junction, a texel centred on its grid cell with a whole cell's share put
// its light where the surface is not, and dimmed the rest: a floor by a wall read 0.89 of its light.
void weigh_by_coverage(std::vector<AtlasTexel>& texels, const SubCells& found) {
    for (std::size_t t = 0; t < texels.size(); ++t) {
        const int count = std::popcount(static_cast<unsigned>(found[t]));
        if (count >= kTexelSamples) continue;
        AtlasTexel& texel = texels[t];
        texel.area *= static_cast<float>(std::max(count, 1)) / static_cast<float>(kTexelSamples);
        if (count == 0) continue;
        texel.position = point_nearest_centroid(std::span<const glm::vec3>(texel.samples.data(), static_cast<std::size_t>(count)));
    }
}

// Every texel of a chart keeps its share of the chart's true area (its cell's part of the surface:
// weigh_by_coverage; in UV charts, times its triangle's world area per texel), scaled so that the
// atlas's area equals the surface's.
void normalize_chart_areas(PackItem& item, const std::vector<float>& chart_area) {
    std::vector<float> sum(item.charts, 0.0f);
    for (const AtlasTexel& t : item.texels) sum[t.chart] += t.area;
    for (AtlasTexel& t : item.texels) {
        if (sum[t.chart] > 0.0f) t.area *= chart_area[t.chart] / sum[t.chart];
    }
}

// The second UV set as a parametrization, or an empty item when it is not a valid one.
PackItem charts_from_uv1(const scene::Scene& scene, std::uint32_t object_index, float texel_size) {
    const scene::Object& object = scene.objects[object_index];
    const scene::Mesh& mesh = scene.meshes[object.mesh];
    float area = 0.0f, uv_area = 0.0f;
    for (const scene::Primitive& primitive : mesh.primitives) {
        if (primitive.uv1.size() != primitive.positions.size() || primitive.positions.empty()) return {};
        for (const glm::vec2& uv : primitive.uv1) {
            if (!(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f)) return {};
        }
        for (std::uint32_t t = 0; t < primitive.triangle_count(); ++t) {
            area += scene::world_triangle_area(object.transform, primitive, t);
            const glm::vec2 a = primitive.uv1[primitive.indices[3 * t]], b = primitive.uv1[primitive.indices[3 * t + 1]],
                            c = primitive.uv1[primitive.indices[3 * t + 2]];
            uv_area += 0.5f * std::abs(edge_function(a, b, c));
        }
    }
    if (!(uv_area > 1e-6f) || !(area > 0.0f)) return {};
    const int side = std::max(2, static_cast<int>(std::ceil(std::sqrt(area / uv_area) / texel_size)));
    if (static_cast<double>(side) * side > 6.7e7) return {};

    PackItem item;
    item.width = item.height = side;
    std::vector<std::int32_t> claimed(static_cast<std::size_t>(side) * side, -1);
    std::vector<std::uint8_t> strictly_inside(claimed.size(), 0);
    std::vector<float> chart_area;
    std::vector<std::pair<const scene::Primitive*, std::vector<std::uint32_t>>> chart_triangles;  // per chart
    std::uint32_t chart_base = 0;
    for (const scene::Primitive& primitive : mesh.primitives) {
        // Charts: triangles connected through shared vertices (shared vertices share their UV).
        std::vector<std::uint32_t> parent(primitive.positions.size());
        std::iota(parent.begin(), parent.end(), 0u);
        auto find = [&](std::uint32_t v) {
            while (parent[v] != v) v = parent[v] = parent[parent[v]];
            return v;
        };
        for (std::uint32_t t = 0; t < primitive.triangle_count(); ++t) {
            const std::uint32_t a = find(primitive.indices[3 * t]);
            parent[find(primitive.indices[3 * t + 1])] = a;
            parent[find(primitive.indices[3 * t + 2])] = a;
        }
        std::map<std::uint32_t, std::uint32_t> chart_of_root;
        for (std::uint32_t t = 0; t < primitive.triangle_count(); ++t) {
            const std::uint32_t root = find(primitive.indices[3 * t]);
            const auto [it, added] = chart_of_root.emplace(root, chart_base + static_cast<std::uint32_t>(chart_of_root.size()));
            const std::uint32_t chart = it->second;
            if (added) {
                chart_area.push_back(0.0f);
                chart_triangles.push_back({&primitive, {}});
            }
            chart_triangles[chart].second.push_back(t);
            const TriangleRef triangle{&primitive, t};
            const float triangle_area = scene::world_triangle_area(object.transform, primitive, t);
            chart_area[chart] += triangle_area;
            glm::vec2 q[3];
            for (int c = 0; c < 3; ++c) q[c] = primitive.uv1[triangle.vertex(c)] * static_cast<float>(side);
            const float texel_area = triangle_area / std::max(0.5f * std::abs(edge_function(q[0], q[1], q[2])), 1e-12f);
            bool overlap = false;
            rasterize(q, false, [&](int x, int y, const glm::vec3& barycentric) {
                if (x < 0 || y < 0 || x >= side || y >= side) return;
                const std::size_t cell = static_cast<std::size_t>(y) * side + x;
                // Shared edges may claim a centre twice; a centre strictly inside two triangles is
                // an overlap.
                const bool inside = glm::all(glm::greaterThan(barycentric, glm::vec3(1e-3f)));
                if (claimed[cell] >= 0) {
                    if (inside && strictly_inside[cell]) overlap = true;
                    return;
                }
                claimed[cell] = static_cast<std::int32_t>(item.texels.size());
                strictly_inside[cell] = inside ? 1 : 0;
                AtlasTexel texel = texel_from(triangle, barycentric, object_index, chart, x, y);
                texel.area = texel_area;
                item.texels.push_back(texel);
            });
            if (overlap) return {};
        }
        chart_base += static_cast<std::uint32_t>(chart_of_root.size());
    }
    item.charts = chart_base;
    // A chart that no texel centre falls in still gets one texel, in the free cell nearest its first
    // triangle's UV centroid, carrying its whole area, its samples spread over its triangles (as the
    // atlas's own charts do): no surface stops sending light.
    std::vector<std::uint8_t> has_texel(chart_base, 0);
    for (const AtlasTexel& texel : item.texels) has_texel[texel.chart] = 1;
    std::vector<std::size_t> whole_chart_texels;
    std::size_t next_free = 0;  // no cell before it is free
    for (std::uint32_t chart = 0; chart < chart_base; ++chart) {
        if (has_texel[chart]) continue;
        const auto& [primitive, members] = chart_triangles[chart];
        const TriangleRef first{primitive, members.front()};
        const glm::vec2 centroid = (primitive->uv1[first.vertex(0)] + primitive->uv1[first.vertex(1)] + primitive->uv1[first.vertex(2)]) *
                                   (static_cast<float>(side) / 3.0f);
        const glm::ivec2 home = glm::clamp(glm::ivec2(glm::floor(centroid)), glm::ivec2(0), glm::ivec2(side - 1));
        std::optional<glm::ivec2> cell;
        // The square rings around `home`, nearest first, a few of them; past those, the first free
        // cell of the grid: many islands at one place (a hostile file's) cost a scan of the grid in
        // all, not one per island.
        constexpr int kNearRings = 4;
        for (int ring = 0; ring <= kNearRings && !cell; ++ring) {
            for (int dy = -ring; dy <= ring && !cell; ++dy) {
                for (int dx = -ring; dx <= ring && !cell; ++dx) {
                    if (std::max(std::abs(dx), std::abs(dy)) != ring) continue;
                    const glm::ivec2 at = home + glm::ivec2(dx, dy);
                    if (at.x >= 0 && at.y >= 0 && at.x < side && at.y < side && claimed[static_cast<std::size_t>(at.y) * side + at.x] < 0) cell = at;
                }
            }
        }
        while (!cell && next_free < claimed.size()) {
            if (claimed[next_free] < 0) cell = glm::ivec2(static_cast<int>(next_free % side), static_cast<int>(next_free / side));
            else ++next_free;
        }
        if (!cell) continue;  // every cell taken: no room for it
        AtlasTexel texel = texel_from(first, glm::vec3(1.0f / 3.0f), object_index, chart, cell->x, cell->y);
        texel.area = 1.0f;  // the chart's whole area, below
        spread_samples(texel, *primitive, members);
        claimed[static_cast<std::size_t>(cell->y) * side + cell->x] = static_cast<std::int32_t>(item.texels.size());
        whole_chart_texels.push_back(item.texels.size());
        item.texels.push_back(texel);
    }
    SubCells found(item.texels.size(), 0);
    for (std::size_t t : whole_chart_texels) found[t] = 0xFFFF;  // sampled over their charts already
    const auto texel_at = [&](int x, int y) { return x < side && y < side ? claimed[static_cast<std::size_t>(y) * side + x] : -1; };
    for (const scene::Primitive& primitive : mesh.primitives) {
        for (std::uint32_t t = 0; t < primitive.triangle_count(); ++t) {
            const TriangleRef triangle{&primitive, t};
            glm::vec2 q[3];
            for (int c = 0; c < 3; ++c) q[c] = primitive.uv1[triangle.vertex(c)] * static_cast<float>(side);
            sample_sub_cells(triangle, q, item.texels, found, texel_at);
        }
    }
    complete_samples(item.texels, found);
    weigh_by_coverage(item.texels, found);
    normalize_chart_areas(item, chart_area);
    return item;
}

// Our own charts: planar-ish patches grown over shared edges, projected onto the seed's plane.
std::vector<PackItem> automatic_charts(const scene::Scene& scene, std::uint32_t object_index,
                                       const AtlasSettings& settings) {
    const scene::Object& object = scene.objects[object_index];
    const scene::Mesh& mesh = scene.meshes[object.mesh];
    const float cone = std::cos(glm::radians(settings.chart_cone_degrees));
    std::vector<PackItem> items;
    for (const scene::Primitive& primitive : mesh.primitives) {
        const std::uint32_t triangles = static_cast<std::uint32_t>(primitive.triangle_count());
        std::vector<glm::vec3> world(primitive.positions.size());
        for (std::size_t v = 0; v < world.size(); ++v) world[v] = glm::vec3(object.transform * glm::vec4(primitive.positions[v], 1.0f));
        std::vector<glm::vec3> face_normal(triangles);
        std::vector<float> face_area(triangles);
        for (std::uint32_t t = 0; t < triangles; ++t) {
            const glm::vec3 n = glm::cross(world[primitive.indices[3 * t + 1]] - world[primitive.indices[3 * t]],
                                           world[primitive.indices[3 * t + 2]] - world[primitive.indices[3 * t]]);
            face_area[t] = 0.5f * glm::length(n);
            face_normal[t] = face_area[t] > 0.0f ? n / (2.0f * face_area[t]) : glm::vec3(0.0f);
        }
        // Edges by welded positions, so split vertices (hard normals, UV seams) still connect.
        std::map<std::tuple<float, float, float>, std::uint32_t> weld;
        std::vector<std::uint32_t> welded(world.size());
        for (std::size_t v = 0; v < world.size(); ++v)
            welded[v] = weld.emplace(std::make_tuple(world[v].x, world[v].y, world[v].z), static_cast<std::uint32_t>(weld.size()))
                            .first->second;
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edge_triangles;
        for (std::uint32_t t = 0; t < triangles; ++t)
            for (int c = 0; c < 3; ++c) {
                std::uint32_t a = welded[primitive.indices[3 * t + c]], b = welded[primitive.indices[3 * t + (c + 1) % 3]];
                edge_triangles[{std::min(a, b), std::max(a, b)}].push_back(t);
            }
        std::vector<std::int32_t> chart_of(triangles, -1);
        for (std::uint32_t seed = 0; seed < triangles; ++seed) {
            if (chart_of[seed] >= 0 || !(face_area[seed] > 0.0f)) continue;
            const glm::vec3 n = face_normal[seed];
            const glm::vec3 tangent = glm::normalize(world[primitive.indices[3 * seed + 1]] - world[primitive.indices[3 * seed]]);
            const glm::vec3 bitangent = glm::cross(n, tangent);
            std::vector<std::uint32_t> members{seed}, frontier{seed};
            chart_of[seed] = 0;
            while (!frontier.empty()) {
                const std::uint32_t t = frontier.back();
                frontier.pop_back();
                for (int c = 0; c < 3; ++c) {
                    std::uint32_t a = welded[primitive.indices[3 * t + c]], b = welded[primitive.indices[3 * t + (c + 1) % 3]];
                    for (std::uint32_t other : edge_triangles[{std::min(a, b), std::max(a, b)}]) {
                        if (chart_of[other] >= 0 || !(face_area[other] > 0.0f) || glm::dot(face_normal[other], n) < cone) continue;
                        chart_of[other] = 0;
                        members.push_back(other);
                        frontier.push_back(other);
                    }
                }
            }
            // Project onto the seed's plane, in texel units, with a one-texel gutter.
            glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
            auto project = [&](std::uint32_t v) {
                return glm::vec2(glm::dot(world[v], tangent), glm::dot(world[v], bitangent)) / settings.texel_size;
            };
            for (std::uint32_t t : members)
                for (int c = 0; c < 3; ++c) {
                    lo = glm::min(lo, project(primitive.indices[3 * t + c]));
                    hi = glm::max(hi, project(primitive.indices[3 * t + c]));
                }
            PackItem item;
            item.width = static_cast<int>(std::ceil(hi.x - lo.x)) + 1;
            item.height = static_cast<int>(std::ceil(hi.y - lo.y)) + 1;
            if (static_cast<double>(item.width) * item.height > 6.7e7) {
                throw InputError(fmt::format("cssm: a chart of object '{}' would span {}x{} texels; raise the texel size",
                                             object.name, item.width, item.height));
            }
            item.charts = 1;
            std::vector<std::int32_t> claimed(static_cast<std::size_t>(item.width) * item.height, -1);
            float area = 0.0f;
            for (std::uint32_t t : members) {
                const TriangleRef triangle{&primitive, t};
                glm::vec2 q[3];
                for (int c = 0; c < 3; ++c) q[c] = project(triangle.vertex(c)) - lo;
                area += face_area[t];
                rasterize(q, false, [&](int x, int y, const glm::vec3& barycentric) {
                    if (x < 0 || y < 0 || x >= item.width || y >= item.height) return;
                    std::int32_t& taken = claimed[static_cast<std::size_t>(y) * item.width + x];
                    if (taken >= 0) return;
                    taken = static_cast<std::int32_t>(item.texels.size());
                    AtlasTexel texel = texel_from(triangle, barycentric, object_index, 0, x, y);
                    texel.area = 1.0f;
                    item.texels.push_back(texel);
                });
            }
            SubCells found(item.texels.size(), 0);
            const auto texel_at = [&](int x, int y) {
                return x < item.width && y < item.height ? claimed[static_cast<std::size_t>(y) * item.width + x] : -1;
            };
            for (std::uint32_t t : members) {
                const TriangleRef triangle{&primitive, t};
                glm::vec2 q[3];
                for (int c = 0; c < 3; ++c) q[c] = project(triangle.vertex(c)) - lo;
                sample_sub_cells(triangle, q, item.texels, found, texel_at);
            }
            complete_samples(item.texels, found);
            weigh_by_coverage(item.texels, found);
            if (item.texels.empty()) {
                // A chart smaller than a texel still gets one, at its seed's centroid, so no surface is
                // lost; its samples spread over all its triangles (a lamp shade's narrow strip: the
                // seed's centroid alone sat below the bulb, in the pole's shadow, all of it lit above).
                const TriangleRef triangle{&primitive, seed};
                AtlasTexel texel = texel_from(triangle, glm::vec3(1.0f / 3.0f), object_index, 0, 0, 0);
                texel.area = 1.0f;  // the chart's whole area, below
                spread_samples(texel, primitive, members);
                item.width = item.height = 1;
                item.texels.push_back(texel);
            }
            normalize_chart_areas(item, {area});
            items.push_back(std::move(item));
        }
    }
    return items;
}

// The back of `item`'s double-sided charts: each texel copied, facing the other way, in charts of
// its own (numbered anew from 0) at the same places.
PackItem back_of(const scene::Scene& scene, const PackItem& item) {
    PackItem back;
    back.width = item.width;
    back.height = item.height;
    std::map<std::uint32_t, std::uint32_t> chart_of;  // the item's chart -> the back's
    for (const AtlasTexel& texel : item.texels) {
        if (!scene.material(texel.material).double_sided) continue;
        AtlasTexel flipped = texel;
        flipped.normal = -texel.normal;
        flipped.chart = chart_of.emplace(texel.chart, static_cast<std::uint32_t>(chart_of.size())).first->second;
        back.texels.push_back(flipped);
    }
    back.charts = static_cast<std::uint32_t>(chart_of.size());
    return back;
}

// The area of the triangles of `objects` whose material passes `counts`.
template <typename Counts>
float area_where(const scene::Scene& scene, const std::vector<std::uint32_t>& objects, Counts&& counts) {
    float area = 0.0f;
    for (std::uint32_t o : objects) {
        const scene::Object& object = scene.objects[o];
        if (object.mesh < 0) continue;
        for (const scene::Primitive& primitive : scene.meshes[object.mesh].primitives) {
            if (!counts(scene.material(primitive.material))) continue;
            for (std::uint32_t t = 0; t < primitive.triangle_count(); ++t) area += scene::world_triangle_area(object.transform, primitive, t);
        }
    }
    return area;
}

}  // namespace

float texel_size_for(float area, float texels_per_side) {
    return std::sqrt(std::max(area, 0.0f)) / std::max(texels_per_side, 1e-6f);
}

float surface_area(const scene::Scene& scene, const std::vector<std::uint32_t>& objects) {
    return area_where(scene, objects, [](const scene::Material&) { return true; });
}

float double_sided_area(const scene::Scene& scene, const std::vector<std::uint32_t>& objects) {
    return area_where(scene, objects, [](const scene::Material& material) { return material.double_sided; });
}

SurfaceAtlas build_surface_atlas(const scene::Scene& scene, const std::vector<std::uint32_t>& objects,
                                 const AtlasSettings& settings, std::size_t max_texels) {
    if (!(settings.texel_size > 0.0f) || !std::isfinite(settings.texel_size)) {
        throw InputError(fmt::format("cssm: atlas texel size must be positive, got {}", settings.texel_size));
    }
    SurfaceAtlas atlas;
    atlas.objects = objects;
    atlas.surface_area = surface_area(scene, objects);
    const double covered = static_cast<double>(atlas.surface_area) + double_sided_area(scene, objects);
    if (covered / (static_cast<double>(settings.texel_size) * settings.texel_size) > static_cast<double>(max_texels)) {
        throw InputError(fmt::format("cssm: an atlas of texel size {:g} over {:g} m^2 would exceed {} texels",
                                     settings.texel_size, atlas.surface_area, max_texels));
    }
    std::vector<PackItem> items;
    for (std::uint32_t o : objects) {
        if (scene.objects[o].mesh < 0) continue;
        if (settings.use_uv1) {
            PackItem item = charts_from_uv1(scene, o, settings.texel_size);
            if (!item.texels.empty()) {
                atlas.uv1_objects.push_back(scene.objects[o].name);
                items.push_back(std::move(item));
                continue;
            }
        }
        for (PackItem& item : automatic_charts(scene, o, settings)) items.push_back(std::move(item));
    }
    for (std::size_t i = 0, fronts = items.size(); i < fronts; ++i) {
        PackItem back = back_of(scene, items[i]);
        if (!back.texels.empty()) items.push_back(std::move(back));
    }

    // Shelf packing, tallest first, into a width near the square root of the texels needed.
    std::vector<std::size_t> order(items.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return items[a].height > items[b].height; });
    double needed = 0.0;
    int widest = 1;
    for (const PackItem& item : items) {
        needed += static_cast<double>(item.width + 1) * (item.height + 1);
        widest = std::max(widest, item.width + 1);
    }
    atlas.width = std::max(widest, static_cast<int>(std::ceil(std::sqrt(needed * 1.1))));
    std::vector<glm::ivec2> origin(items.size());
    int x = 0, y = 0, shelf = 0;
    for (std::size_t i : order) {
        if (x + items[i].width > atlas.width) {
            x = 0;
            y += shelf + 1;
            shelf = 0;
        }
        origin[i] = {x, y};
        x += items[i].width + 1;
        shelf = std::max(shelf, items[i].height);
    }
    atlas.height = y + shelf;
    atlas.texel_at.assign(static_cast<std::size_t>(atlas.width) * atlas.height, -1);

    std::uint32_t chart_base = 0;
    for (std::size_t i = 0; i < items.size(); ++i) {
        PackItem& item = items[i];
        std::vector<AtlasChart> charts(item.charts);
        std::vector<float> weights(item.charts, 0.0f);
        for (AtlasChart& chart : charts) {
            chart.min = glm::ivec2(std::numeric_limits<int>::max());
            chart.max = glm::ivec2(std::numeric_limits<int>::min());
        }
        for (AtlasTexel texel : item.texels) {
            texel.x += origin[i].x;
            texel.y += origin[i].y;
            AtlasChart& chart = charts[texel.chart];
            chart.object = texel.object;
            chart.min = glm::min(chart.min, glm::ivec2(texel.x, texel.y));
            chart.max = glm::max(chart.max, glm::ivec2(texel.x + 1, texel.y + 1));
            chart.centroid += texel.area * texel.position;
            weights[texel.chart] += texel.area;
            texel.chart += chart_base;
            atlas.texel_at[static_cast<std::size_t>(texel.y) * atlas.width + texel.x] = static_cast<std::int32_t>(atlas.texels.size());
            atlas.texels.push_back(texel);
        }
        for (std::uint32_t c = 0; c < item.charts; ++c) {
            if (weights[c] > 0.0f) charts[c].centroid /= weights[c];
            atlas.charts.push_back(charts[c]);
        }
        chart_base += item.charts;
    }
    return atlas;
}

glm::vec3 point_nearest_centroid(std::span<const glm::vec3> points) {
    if (points.empty()) return glm::vec3(0.0f);
    glm::vec3 centroid(0.0f);
    for (const glm::vec3& point : points) centroid += point;
    centroid /= static_cast<float>(points.size());
    float spread = 0.0f;
    for (const glm::vec3& point : points) spread = std::max(spread, glm::distance(point, centroid));
    std::size_t nearest = 0;
    float nearest_distance = glm::distance(points[0], centroid);
    for (std::size_t i = 1; i < points.size(); ++i) {
        const float distance = glm::distance(points[i], centroid);
        if (distance < nearest_distance - 1e-3f * spread) {
            nearest = i;
            nearest_distance = distance;
        }
    }
    return points[nearest];
}

}  // namespace bounce::methods::cssm
