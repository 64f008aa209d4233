#include "ffcube/viewer/display.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "ffcube/core/error.hpp"

namespace ffcube {

DisplayMesh build_display_mesh(const Scene& scene, std::span<const std::uint32_t> origin) {
    DisplayMesh m;
    const std::size_t n = scene.size();
    FFCUBE_CHECK_MSG(origin.empty() || origin.size() == n, "one origin per patch");
    m.first_vertex.reserve(n + 1);
    m.first_line.reserve(n + 1);
    for (std::uint32_t p = 0; p < n; ++p) {
        const Patch& patch = scene.patches[p];
        const auto base = static_cast<std::uint32_t>(m.patch.size());
        m.first_vertex.push_back(base);
        m.first_line.push_back(static_cast<std::uint32_t>(m.lines.size()));
        for (std::uint32_t k = 0; k < patch.count; ++k) {
            const Vec3& v = scene.positions[patch.v[k]];
            m.positions.insert(m.positions.end(), {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
            m.patch.push_back(p);
            m.lines.insert(m.lines.end(), {base + k, base + (k + 1) % patch.count});
        }
        // A convex quad splits along either diagonal; a triangle is itself.
        m.triangles.insert(m.triangles.end(), {base, base + 1, base + 2});
        if (patch.count == 4) m.triangles.insert(m.triangles.end(), {base, base + 2, base + 3});
    }
    m.first_vertex.push_back(static_cast<std::uint32_t>(m.patch.size()));
    m.first_line.push_back(static_cast<std::uint32_t>(m.lines.size()));

    // Corners meet at the same point up to rounding: the mesher makes each piece's grid points
    // itself, so neighbouring pieces have their own copies. Quantise to 1e-7 of the extent.
    const double q = std::max(scene.extent(), 1e-300) * 1e-7;
    using Key = std::tuple<long long, long long, long long>;
    std::map<Key, std::vector<std::uint32_t>> at_point;  // vertex indices meeting at a point
    const auto key = [&](std::uint32_t v) {
        return Key{std::llround(m.positions[3 * v] / q), std::llround(m.positions[3 * v + 1] / q),
                   std::llround(m.positions[3 * v + 2] / q)};
    };
    for (std::uint32_t v = 0; v < m.vertex_count(); ++v) at_point[key(v)].push_back(v);

    // An element's edge lies inside its starting patch when another element of that patch has an
    // edge with the same two end points (either way round): the splits of scene/refine.hpp put
    // children's corners on the parent's grid, so inner edges are shared whole.
    using Edge = std::tuple<std::uint32_t, Key, Key>;
    const auto edge_key = [&](std::size_t line) {
        const std::uint32_t a = m.lines[line], b = m.lines[line + 1];
        const Key ka = key(a), kb = key(b);
        return Edge{origin.empty() ? m.patch[a] : origin[m.patch[a]], std::min(ka, kb), std::max(ka, kb)};
    };
    std::map<Edge, std::uint32_t> edge_count;
    if (!origin.empty())
        for (std::size_t l = 0; l < m.lines.size(); l += 2) ++edge_count[edge_key(l)];
    for (std::size_t l = 0; l < m.lines.size(); l += 2) {
        const bool inner = !origin.empty() && edge_count[edge_key(l)] >= 2;
        auto& out = inner ? m.element_lines : m.patch_lines;
        out.insert(out.end(), {m.lines[l], m.lines[l + 1]});
    }

    const double cos_crease = std::cos(10.0 * 3.14159265358979323846 / 180.0);
    m.smooth_first.reserve(m.vertex_count() + 1);
    for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
        m.smooth_first.push_back(static_cast<std::uint32_t>(m.smooth_patch.size()));
        const Patch& a = scene.patches[m.patch[v]];
        const std::size_t start = m.smooth_patch.size();
        for (std::uint32_t w : at_point[key(v)]) {
            const Patch& b = scene.patches[m.patch[w]];
            if (b.object != a.object || b.material != a.material || glm::dot(a.normal, b.normal) < cos_crease) continue;
            m.smooth_patch.push_back(m.patch[w]);
        }
        // A patch touches a point with one corner, but a degenerate input could repeat it.
        std::sort(m.smooth_patch.begin() + static_cast<std::ptrdiff_t>(start), m.smooth_patch.end());
        m.smooth_patch.erase(std::unique(m.smooth_patch.begin() + static_cast<std::ptrdiff_t>(start), m.smooth_patch.end()),
                             m.smooth_patch.end());
    }
    m.smooth_first.push_back(static_cast<std::uint32_t>(m.smooth_patch.size()));
    return m;
}

ObstructionMesh build_obstruction_mesh(const Scene& scene) {
    ObstructionMesh m;
    if (!scene.drawn) return m;
    const Scene& drawn = *scene.drawn;
    // The .vs3 reader makes each O surface two faces back to back (it blocks from both sides):
    // draw one of them, without culling, so that the glass is one layer seen from either side.
    // The two faces are meshed each from its own corner order, so their grid points agree only up
    // to rounding: corners are compared quantised to 1e-7 of the extent (as build_display_mesh's).
    const double q = std::max(drawn.extent(), 1e-300) * 1e-7;
    std::set<std::vector<std::array<long long, 3>>> seen;
    for (std::uint32_t p = drawn.obstruction_first; p < drawn.size(); ++p) {
        const Patch& patch = drawn.patches[p];
        std::vector<std::array<long long, 3>> corners;
        for (std::uint32_t k = 0; k < patch.count; ++k) {
            const Vec3& v = drawn.positions[patch.v[k]];
            corners.push_back({std::llround(v.x / q), std::llround(v.y / q), std::llround(v.z / q)});
        }
        std::sort(corners.begin(), corners.end());
        if (!seen.insert(std::move(corners)).second) continue;
        const auto base = static_cast<std::uint32_t>(m.positions.size() / 3);
        for (std::uint32_t k = 0; k < patch.count; ++k) {
            const Vec3& v = drawn.positions[patch.v[k]];
            m.positions.insert(m.positions.end(), {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
            m.lines.insert(m.lines.end(), {base + k, base + (k + 1) % patch.count});
        }
        m.triangles.insert(m.triangles.end(), {base, base + 1, base + 2});
        if (patch.count == 4) m.triangles.insert(m.triangles.end(), {base, base + 2, base + 3});
        ++m.patches;
    }
    return m;
}

void flat_colors(const DisplayMesh& mesh, std::span<const Vec3> per_patch, std::vector<float>& out) {
    FFCUBE_CHECK_MSG(per_patch.size() + 1 == mesh.first_vertex.size(), "one value per patch");
    out.resize(3 * mesh.vertex_count());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        const Vec3& c = per_patch[mesh.patch[v]];
        out[3 * v] = static_cast<float>(c.r), out[3 * v + 1] = static_cast<float>(c.g), out[3 * v + 2] = static_cast<float>(c.b);
    }
}

void smooth_colors(const DisplayMesh& mesh, const Scene& scene, std::span<const Vec3> per_patch, std::vector<float>& out) {
    FFCUBE_CHECK_MSG(per_patch.size() == scene.size() && per_patch.size() + 1 == mesh.first_vertex.size(), "one value per patch");
    out.resize(3 * mesh.vertex_count());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        Vec3 sum(0.0);
        double area = 0.0;
        for (std::uint32_t k = mesh.smooth_first[v]; k < mesh.smooth_first[v + 1]; ++k) {
            const std::uint32_t p = mesh.smooth_patch[k];
            sum += scene.patches[p].area * per_patch[p];
            area += scene.patches[p].area;
        }
        const Vec3 c = area > 0.0 ? sum / area : per_patch[mesh.patch[v]];
        out[3 * v] = static_cast<float>(c.r), out[3 * v + 1] = static_cast<float>(c.g), out[3 * v + 2] = static_cast<float>(c.b);
    }
}

Vec3 heat_color(double t) {
    static const std::array<Vec3, 4> ramp = {Vec3(0.15, 0.0, 0.3), Vec3(0.6, 0.05, 0.4), Vec3(0.95, 0.45, 0.1),
                                             Vec3(1.0, 0.95, 0.6)};
    const double x = std::clamp(t, 0.0, 1.0) * static_cast<double>(ramp.size() - 1);
    const std::size_t k = std::min(static_cast<std::size_t>(x), ramp.size() - 2);
    const double f = x - static_cast<double>(k);
    return (1.0 - f) * ramp[k] + f * ramp[k + 1];
}

std::vector<Vec3> row_heat_map(const Scene& scene, std::uint32_t i, const SparseRow& row) {
    FFCUBE_CHECK_MSG(i < scene.size(), "patch index in range");
    std::vector<Vec3> out(scene.size(), kNoContribution);
    double max_density = 0.0;
    for (std::size_t k = 0; k < row.nnz(); ++k)
        max_density = std::max(max_density, row.val[k] / scene.patches[row.col[k]].area);
    for (std::size_t k = 0; k < row.nnz(); ++k) {
        const double rel = row.val[k] / scene.patches[row.col[k]].area / max_density;  // in (0, 1]
        out[row.col[k]] = heat_color(1.0 + std::log10(rel) / 3.0);
    }
    out[i] = kPicked;
    return out;
}

std::uint32_t item_color(std::uint32_t item) {
    if (item == 0) return 0xFF000000u;
    if (item == 0xFFFFFFFFu) return 0xFF404040u;
    // A 32-bit mix (the murmur3 finaliser), then each channel lifted into [96, 255] so that no
    // patch looks like the black background or the grey back faces.
    std::uint32_t h = item;
    h ^= h >> 16, h *= 0x85ebca6bu, h ^= h >> 13, h *= 0xc2b2ae35u, h ^= h >> 16;
    std::uint32_t rgba = 0xFF000000u;
    for (int c = 0; c < 3; ++c) rgba |= (96u + ((h >> (8 * c)) & 0xFFu) * 159u / 255u) << (8 * c);
    return rgba;
}

}  // namespace ffcube
