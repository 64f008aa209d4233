// The refinement indicator and marking of adaptive meshing (solver/refinement.hpp).
#include "ffcube/solver/refinement.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/surface_vertices.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube {
namespace {

// cos 25°: the smooth-shading rule of render/solved_scene (same surface).
constexpr double kSameSurfaceCos = 0.9063077870366499;

// Centroids hashed into cubes of side `cell` (the largest patch size × 1.5, so that every
// neighbour within 0.75 (size_i + size_j) is in the 27 cubes around a patch).
struct CentroidHash {
    double cell = 1.0;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cubes;

    static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
        const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1fffff; };
        return u(x) | (u(y) << 21) | (u(z) << 42);
    }
    std::array<std::int64_t, 3> at(const Vec3& p) const {
        return {static_cast<std::int64_t>(std::floor(p.x / cell)), static_cast<std::int64_t>(std::floor(p.y / cell)),
                static_cast<std::int64_t>(std::floor(p.z / cell))};
    }
};

}  // namespace

double radiosity_luminance(const Vec3& b) { return 0.2126 * b.r + 0.7152 * b.g + 0.0722 * b.b; }

namespace {

// Patches of the same surface as i (same object, normals within 25°) whose centroids are within
// reach × (size_i + size_j) of i's: with reach 0.75 the edge and corner neighbours of the mesher's
// grids and of elements; with 1.6 the second ring too.
class SurfaceNeighbours {
public:
    explicit SurfaceNeighbours(const Scene& scene, double reach = 0.75) : scene_(scene), reach_(reach) {
        double largest = 0.0;
        for (const Patch& p : scene.patches) largest = std::max(largest, p.size);
        // Cubes of at least 2^-20 of the scene's extent keep the 21-bit keys within range.
        hash_.cell = std::max(2.0 * reach * largest, scene.extent() * std::ldexp(1.0, -19));
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            const auto c = hash_.at(scene.patches[i].centroid);
            hash_.cubes[CentroidHash::key(c[0], c[1], c[2])].push_back(i);
        }
    }
    template <class F>
    void for_each(std::uint32_t i, F&& f) const {
        const Patch& p = scene_.patches[i];
        const auto c = hash_.at(p.centroid);
        for (std::int64_t dz = -1; dz <= 1; ++dz)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dx = -1; dx <= 1; ++dx) {
                    const auto it = hash_.cubes.find(CentroidHash::key(c[0] + dx, c[1] + dy, c[2] + dz));
                    if (it == hash_.cubes.end()) continue;
                    for (const std::uint32_t j : it->second) {
                        const Patch& q = scene_.patches[j];
                        if (j == i || q.object != p.object || glm::dot(p.normal, q.normal) < kSameSurfaceCos) continue;
                        if (glm::length(p.centroid - q.centroid) > reach_ * (p.size + q.size)) continue;
                        f(j);
                    }
                }
    }

private:
    const Scene& scene_;
    double reach_;
    CentroidHash hash_;
};

}  // namespace

std::vector<double> radiosity_variation(const Scene& scene, std::span<const Vec3> radiosity) {
    FFCUBE_CHECK_MSG(radiosity.size() == scene.size(), "one radiosity per patch");
    const std::size_t n = scene.size();
    std::vector<double> out(n, 0.0);
    if (n == 0) return out;
    const SurfaceNeighbours neighbours(scene);
    for (std::uint32_t i = 0; i < n; ++i) {
        const double yi = radiosity_luminance(radiosity[i]);
        double jump = 0.0;
        neighbours.for_each(i, [&](std::uint32_t j) { jump = std::max(jump, std::abs(yi - radiosity_luminance(radiosity[j]))); });
        out[i] = 0.5 * jump;
    }
    return out;
}

std::vector<Vec3> centroid_defect(const Scene& scene, std::span<const Vec3> radiosity, std::size_t* fitted) {
    FFCUBE_CHECK_MSG(radiosity.size() == scene.size(), "one radiosity per patch");
    const std::size_t n = scene.size();
    std::vector<Vec3> out(n, Vec3(0.0));
    if (fitted) *fitted = 0;
    if (n == 0) return out;
    const SurfaceNeighbours neighbours(scene), wider(scene, 1.6);
    std::vector<std::uint32_t> near;
    for (std::uint32_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        // Tangent frame, lengths in units of the patch's size (conditioning).
        const Vec3 t0 = std::abs(p.normal.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        const Vec3 u = glm::normalize(glm::cross(p.normal, t0)), v = glm::cross(p.normal, u);
        const double h = p.size;
        double X[5][3];
        // Least squares B_j − B_i = g·d + ½ dᵀHd over the neighbours, unknowns (g_u, g_v, H_uu, H_uv,
        // H_vv); false when the neighbours do not determine them (fewer than 5, or all on a line in
        // one direction: a patch on the border of its surface sees one ring on one side only).
        const auto fit = [&]() {
            if (near.size() < 5) return false;
            double A[5][5] = {}, R[5][3] = {};
            for (const std::uint32_t j : near) {
                const Vec3 d = scene.patches[j].centroid - p.centroid;
                const double x = glm::dot(d, u) / h, y = glm::dot(d, v) / h;
                const double phi[5] = {x, y, 0.5 * x * x, x * y, 0.5 * y * y};
                const Vec3 db = radiosity[j] - radiosity[i];
                for (int r = 0; r < 5; ++r) {
                    for (int c = 0; c < 5; ++c) A[r][c] += phi[r] * phi[c];
                    for (int k = 0; k < 3; ++k) R[r][k] += phi[r] * db[k];
                }
            }
            // Gaussian elimination with partial pivoting.
            const double scale = A[0][0] + A[1][1] + A[2][2] + A[3][3] + A[4][4];
            for (int c = 0; c < 5; ++c) {
                int piv = c;
                for (int r = c + 1; r < 5; ++r)
                    if (std::abs(A[r][c]) > std::abs(A[piv][c])) piv = r;
                if (std::abs(A[piv][c]) < 1e-9 * scale) return false;
                std::swap(A[c], A[piv]);
                std::swap(R[c], R[piv]);
                for (int r = c + 1; r < 5; ++r) {
                    const double f = A[r][c] / A[c][c];
                    for (int k = c; k < 5; ++k) A[r][k] -= f * A[c][k];
                    for (int k = 0; k < 3; ++k) R[r][k] -= f * R[c][k];
                }
            }
            for (int r = 4; r >= 0; --r)
                for (int k = 0; k < 3; ++k) {
                    double acc = R[r][k];
                    for (int c = r + 1; c < 5; ++c) acc -= A[r][c] * X[c][k];
                    X[r][k] = acc / A[r][r];
                }
            return true;
        };
        near.clear();
        neighbours.for_each(i, [&](std::uint32_t j) { near.push_back(j); });
        if (!fit()) {  // the second ring: a border patch
            near.clear();
            wider.for_each(i, [&](std::uint32_t j) { near.push_back(j); });
            if (!fit()) continue;
        }
        // Second moments of the patch about its centroid (in units of h²): each triangle of the fan
        // (a, b, c) about the origin has ∫ x xᵀ dA = A/12 (Σ v vᵀ + (Σ v)(Σ v)ᵀ).
        const std::array<Vec3, 4> corner = scene.patch_vertices(i);
        double Muu = 0.0, Muv = 0.0, Mvv = 0.0;
        const auto add_triangle = [&](const Vec3& a3, const Vec3& b3, const Vec3& c3) {
            const double ax = glm::dot(a3 - p.centroid, u) / h, ay = glm::dot(a3 - p.centroid, v) / h;
            const double bx = glm::dot(b3 - p.centroid, u) / h, by = glm::dot(b3 - p.centroid, v) / h;
            const double cx = glm::dot(c3 - p.centroid, u) / h, cy = glm::dot(c3 - p.centroid, v) / h;
            const double area = 0.5 * std::abs((bx - ax) * (cy - ay) - (cx - ax) * (by - ay));
            const double sx = ax + bx + cx, sy = ay + by + cy;
            Muu += area / 12.0 * (ax * ax + bx * bx + cx * cx + sx * sx);
            Muv += area / 12.0 * (ax * ay + bx * by + cx * cy + sx * sy);
            Mvv += area / 12.0 * (ay * ay + by * by + cy * cy + sy * sy);
        };
        add_triangle(corner[0], corner[1], corner[2]);
        if (p.count == 4) add_triangle(corner[0], corner[2], corner[3]);
        const double area_h = p.area / (h * h);
        // mean − B_i = ½ tr(H M) / area: the quadratic's mean over the patch minus its centre value.
        for (int k = 0; k < 3; ++k)
            out[i][k] = -0.5 * (X[2][k] * Muu + 2.0 * X[3][k] * Muv + X[4][k] * Mvv) / area_h;
        if (fitted) ++*fitted;
    }
    return out;
}

std::vector<Vec3> reconstruction_defect(const Scene& scene, std::span<const Vec3> radiosity) {
    FFCUBE_CHECK_MSG(radiosity.size() == scene.size(), "one radiosity per patch");
    const SurfaceVertices vertices = surface_vertices(scene, kSameSurfaceCos);
    const std::vector<Vec3> at_vertex = vertex_average(scene, vertices, radiosity);
    std::vector<Vec3> out(scene.size(), Vec3(0.0));
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        Vec3 mean(0.0);
        for (std::uint32_t c = 0; c < p.count; ++c) mean += at_vertex[vertices.corner_vertex[vertices.first_corner[i] + c]];
        out[i] = mean / static_cast<double>(p.count) - radiosity[i];
    }
    return out;
}

RefinementChoice choose_refinement(const Scene& scene, std::span<const Vec3> radiosity, double target,
                                   std::size_t max_elements, std::uint32_t factor, double fraction,
                                   const std::vector<bool>& objects) {
    FFCUBE_CHECK_MSG(fraction > 0.0 && fraction <= 1.0, "the marked fraction is in (0, 1]");
    FFCUBE_CHECK_MSG(factor >= 2, "a split factor is at least 2");
    FFCUBE_CHECK_MSG(target >= 0.0, "the target error is not negative");
    FFCUBE_CHECK_MSG(objects.empty() || objects.size() == scene.objects.size(), "one flag per object");
    const std::size_t n = scene.size();
    const std::vector<double> variation = radiosity_variation(scene, radiosity);
    const std::vector<ObjectRadiosity> object_b = object_radiosity(scene, radiosity);
    RefinementChoice choice;
    choice.split.assign(n, 1);
    choice.elements_after = n;
    std::vector<std::uint32_t> candidates;
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t o = scene.patches[i].object;
        if (!objects.empty() && !objects[o]) continue;
        const double mean = radiosity_luminance(object_b[o].radiosity);
        if (variation[i] > target * mean && variation[i] > 0.0) candidates.push_back(i);
    }
    choice.candidates = candidates.size();
    const auto eta = [&](std::uint32_t i) { return variation[i] * scene.patches[i].area; };
    std::stable_sort(candidates.begin(), candidates.end(), [&](std::uint32_t a, std::uint32_t b) { return eta(a) > eta(b); });
    const std::size_t extra = static_cast<std::size_t>(factor) * factor - 1;
    // Dörfler's sums, per object when objects are flagged, else over the whole scene (one group).
    const auto group = [&](std::uint32_t i) -> std::size_t { return objects.empty() ? 0 : scene.patches[i].object; };
    std::vector<double> total(std::max<std::size_t>(scene.objects.size(), 1), 0.0), marked(total.size(), 0.0);
    for (const std::uint32_t i : candidates) total[group(i)] += eta(i);
    for (const std::uint32_t i : candidates) {
        const std::size_t g = group(i);
        if (marked[g] >= fraction * total[g]) continue;
        if (choice.elements_after + extra > max_elements) {
            choice.budget_limited = true;
            break;
        }
        choice.split[i] = factor;
        marked[g] += eta(i);
        choice.elements_after += extra;
        ++choice.marked;
    }
    return choice;
}

}  // namespace ffcube
