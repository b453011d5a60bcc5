#include "renderer/methods/cssm/atlas_traversal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace bounce::methods::cssm {
namespace {

glm::vec3 world_position(const scene::Scene& scene, std::uint32_t object, const glm::vec3& p) {
    return glm::vec3(scene.objects[object].transform * glm::vec4(p, 1.0f));
}

void zigzag_chart(const SurfaceAtlas& atlas, std::uint32_t chart, std::vector<std::uint32_t>& order) {
    const AtlasChart& c = atlas.charts[chart];
    for (int y = c.min.y; y < c.max.y; ++y) {
        const bool forward = ((y - c.min.y) & 1) == 0;
        for (int i = 0; i < c.max.x - c.min.x; ++i) {
            const int x = forward ? c.min.x + i : c.max.x - 1 - i;
            const std::int32_t t = atlas.at(x, y);
            if (t >= 0 && atlas.texels[t].chart == chart) order.push_back(static_cast<std::uint32_t>(t));
        }
    }
}

// Walks with the outside (or visited texels) on the left: tries left, straight, right, back of the
// current heading; when no neighbour is free, steps back along the path until one has a free
// neighbour.
void spiral_chart(const SurfaceAtlas& atlas, std::uint32_t chart, std::vector<std::uint32_t>& order,
                  std::vector<std::uint8_t>& visited) {
    static constexpr std::array<glm::ivec2, 4> kHeading = {glm::ivec2{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    const AtlasChart& c = atlas.charts[chart];
    auto free_at = [&](glm::ivec2 p) {
        const std::int32_t t = atlas.at(p.x, p.y);
        return t >= 0 && atlas.texels[t].chart == chart && !visited[t];
    };
    std::vector<std::pair<glm::ivec2, int>> path;  // position, heading on arrival
    auto visit = [&](glm::ivec2 p, int heading) {
        const std::int32_t t = atlas.at(p.x, p.y);
        visited[t] = 1;
        order.push_back(static_cast<std::uint32_t>(t));
        path.emplace_back(p, heading);
    };
    // Start at the chart's first free texel in scan order (a border texel); again for every piece
    // the texel grid splits the chart into.
    for (int y = c.min.y; y < c.max.y; ++y) {
        for (int x = c.min.x; x < c.max.x; ++x) {
            if (!free_at({x, y})) continue;
            visit({x, y}, 0);
            while (!path.empty()) {
                const auto [p, heading] = path.back();
                bool moved = false;
                // Left of the heading in atlas coordinates (rows grow downwards) is heading - 1.
                for (int turn : {3, 0, 1, 2}) {
                    const int next = (heading + turn) % 4;
                    const glm::ivec2 q = p + kHeading[next];
                    if (free_at(q)) {
                        visit(q, next);
                        moved = true;
                        break;
                    }
                }
                if (!moved) path.pop_back();
            }
        }
    }
}

}  // namespace

// Nearest unvisited texel by a uniform grid over world positions, searched in growing shells.
std::vector<std::uint32_t> greedy_walk(const std::vector<glm::vec3>& positions) {
    std::vector<std::uint32_t> order;
    if (positions.empty()) return order;
    scene::Aabb bounds;
    for (const glm::vec3& p : positions) bounds.extend(p);
    const glm::vec3 extent = glm::max(bounds.extent(), glm::vec3(1e-12f));
    const float cell = std::cbrt(extent.x * extent.y * extent.z / static_cast<float>(positions.size())) * 2.0f;
    const glm::ivec3 cells = glm::clamp(glm::ivec3(glm::ceil(extent / std::max(cell, 1e-12f))), glm::ivec3(1), glm::ivec3(512));
    const glm::vec3 cell_size = extent / glm::vec3(cells);
    auto cell_of = [&](const glm::vec3& p) {
        return glm::clamp(glm::ivec3((p - bounds.min) / cell_size), glm::ivec3(0), cells - 1);
    };
    auto key = [&](glm::ivec3 c) { return (static_cast<std::size_t>(c.z) * cells.y + c.y) * cells.x + c.x; };
    std::unordered_map<std::size_t, std::vector<std::uint32_t>> grid;
    for (std::uint32_t i = 0; i < positions.size(); ++i) grid[key(cell_of(positions[i]))].push_back(i);
    std::vector<std::uint8_t> visited(positions.size(), 0);
    std::uint32_t current = 0;
    for (std::size_t step = 0; step < positions.size(); ++step) {
        visited[current] = 1;
        order.push_back(current);
        auto& bucket = grid[key(cell_of(positions[current]))];
        bucket.erase(std::find(bucket.begin(), bucket.end(), current));
        if (order.size() == positions.size()) break;
        const glm::ivec3 centre = cell_of(positions[current]);
        float best = std::numeric_limits<float>::max();
        std::int64_t best_index = -1;
        const int max_shell = std::max(cells.x, std::max(cells.y, cells.z));
        for (int shell = 0; shell <= max_shell; ++shell) {
            // A texel in shell s is at least (s - 1) cells away: stop once that exceeds the best.
            const float reach = static_cast<float>(shell - 1) * std::min(cell_size.x, std::min(cell_size.y, cell_size.z));
            if (best_index >= 0 && reach > 0.0f && reach * reach > best) break;
            for (int z = centre.z - shell; z <= centre.z + shell; ++z)
                for (int y = centre.y - shell; y <= centre.y + shell; ++y)
                    for (int x = centre.x - shell; x <= centre.x + shell; ++x) {
                        const glm::ivec3 c(x, y, z);
                        if (glm::any(glm::lessThan(c, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(c, cells))) continue;
                        if (std::max(std::abs(x - centre.x), std::max(std::abs(y - centre.y), std::abs(z - centre.z))) != shell) continue;
                        const auto it = grid.find(key(c));
                        if (it == grid.end()) continue;
                        for (std::uint32_t candidate : it->second) {
                            const glm::vec3 d = positions[candidate] - positions[current];
                            const float distance = glm::dot(d, d);
                            if (distance < best) {
                                best = distance;
                                best_index = candidate;
                            }
                        }
                    }
        }
        current = static_cast<std::uint32_t>(best_index);
    }
    return order;
}

std::string_view traversal_name(Traversal traversal) {
    switch (traversal) {
        case Traversal::greedy: return "greedy";
        case Traversal::zigzag: return "zig-zag";
        case Traversal::spiral: return "spiral";
    }
    return "?";
}

std::vector<std::uint32_t> traverse_atlas(const scene::Scene& scene, const SurfaceAtlas& atlas, Traversal traversal) {
    std::vector<glm::vec3> positions(atlas.texels.size());
    for (std::size_t i = 0; i < atlas.texels.size(); ++i)
        positions[i] = world_position(scene, atlas.texels[i].object, atlas.texels[i].position);
    if (traversal == Traversal::greedy) return greedy_walk(positions);

    std::vector<std::uint32_t> order;
    order.reserve(atlas.texels.size());
    std::vector<std::uint8_t> visited(atlas.texels.size(), 0), chart_done(atlas.charts.size(), 0);
    std::vector<glm::vec3> centroids(atlas.charts.size());
    std::vector<std::uint8_t> chart_empty(atlas.charts.size(), 1);
    for (const AtlasTexel& t : atlas.texels) chart_empty[t.chart] = 0;
    for (std::size_t c = 0; c < atlas.charts.size(); ++c)
        centroids[c] = world_position(scene, atlas.charts[c].object, atlas.charts[c].centroid);
    scene::Aabb bounds;
    for (const glm::vec3& p : positions) bounds.extend(p);
    const float grid = 4096.0f / std::max(glm::length(bounds.extent()), 1e-30f);
    glm::vec3 last = positions.empty() ? glm::vec3(0.0f) : positions[0];
    std::int64_t chart = atlas.texels.empty() ? -1 : static_cast<std::int64_t>(atlas.texels[0].chart);
    while (chart >= 0) {
        chart_done[chart] = 1;
        const std::size_t before = order.size();
        if (traversal == Traversal::zigzag) {
            zigzag_chart(atlas, static_cast<std::uint32_t>(chart), order);
        } else {
            spiral_chart(atlas, static_cast<std::uint32_t>(chart), order, visited);
        }
        if (order.size() > before) last = positions[order.back()];
        chart = -1;
        float best = std::numeric_limits<float>::max();
        for (std::size_t c = 0; c < atlas.charts.size(); ++c) {
            if (chart_done[c] || chart_empty[c]) continue;
            // Distances on a grid of 1/4096 of the atlas's extent, ties to the lower index: the same
            // chain at any scale (symmetric scenes have equidistant charts).
            const float d = std::floor(glm::length(centroids[c] - last) * grid);
            if (d < best) {
                best = d;
                chart = static_cast<std::int64_t>(c);
            }
        }
    }
    return order;
}

}  // namespace bounce::methods::cssm
