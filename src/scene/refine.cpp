// Splitting chosen patches into elements (scene/refine.hpp).
#include "ffcube/scene/refine.hpp"

#include <fmt/format.h>
#include <glm/common.hpp>

#include <array>
#include <limits>

#include "ffcube/core/error.hpp"
#include "ffcube/geometry/polygon.hpp"

namespace ffcube {
namespace {

// The mesher's layouts (scene.hpp, PatchGrid), so that a renderer finds an element from its
// position in the grid exactly as it finds a patch.
void split_quad(Scene& out, const Patch& p, const std::array<Vec3, 4>& c, std::uint32_t s) {
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (std::uint32_t j = 0; j <= s; ++j) {
        const double t = static_cast<double>(j) / s;
        for (std::uint32_t i = 0; i <= s; ++i) {
            const double u = static_cast<double>(i) / s;
            out.positions.push_back((1 - u) * (1 - t) * c[0] + u * (1 - t) * c[1] + u * t * c[2] + (1 - u) * t * c[3]);
        }
    }
    out.grids.push_back(PatchGrid{c, 4, s, s, static_cast<std::uint32_t>(out.patches.size())});
    const std::uint32_t row = s + 1;
    for (std::uint32_t j = 0; j < s; ++j)
        for (std::uint32_t i = 0; i < s; ++i) {
            Patch e = p;
            const std::uint32_t a = base + j * row + i;
            e.v = {a, a + 1, a + row + 1, a + row};
            fill_patch_geometry(out, e);
            out.patches.push_back(e);
        }
}

void split_triangle(Scene& out, const Patch& p, const std::array<Vec3, 4>& c, std::uint32_t k) {
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (std::uint32_t j = 0; j <= k; ++j)
        for (std::uint32_t i = 0; i + j <= k; ++i) {
            const double b = static_cast<double>(i) / k, cc = static_cast<double>(j) / k;
            const double a = static_cast<double>(k - i - j) / k;
            out.positions.push_back(a * c[0] + b * c[1] + cc * c[2]);
        }
    const auto at = [&](std::uint32_t i, std::uint32_t j) { return base + j * (k + 1) - j * (j - 1) / 2 + i; };
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t cc) {
        Patch e = p;
        e.v = {a, b, cc, cc};
        fill_patch_geometry(out, e);
        out.patches.push_back(e);
    };
    out.grids.push_back(PatchGrid{{c[0], c[1], c[2], c[2]}, 3, k, k, static_cast<std::uint32_t>(out.patches.size())});
    for (std::uint32_t j = 0; j < k; ++j)
        for (std::uint32_t i = 0; i + j < k; ++i) {
            add(at(i, j), at(i + 1, j), at(i, j + 1));
            if (i + j + 1 < k) add(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
        }
}

std::uint32_t grid_cells(const PatchGrid& g) { return g.count == 4 ? g.nu * g.nv : g.nu * g.nu; }

}  // namespace

RefinedScene refine_patches(const Scene& scene, std::span<const std::uint32_t> split) {
    FFCUBE_CHECK_MSG(split.size() == scene.size(), "one split factor per patch");
    RefinedScene r;
    Scene& out = r.scene;
    out.source = scene.source;
    out.objects = scene.objects;
    out.materials = scene.materials;
    out.stats = scene.stats;
    out.positions = scene.positions;  // kept grids keep their vertex indices
    out.bbox_min = scene.bbox_min;
    out.origin = scene.origin;
    out.bbox_max = scene.bbox_max;
    for (const PatchGrid& g : scene.grids) {
        const std::uint32_t cells = grid_cells(g);
        bool any = false;
        for (std::uint32_t c = 0; c < cells; ++c) {
            const std::uint32_t s = split[g.first_patch + c];
            FFCUBE_CHECK_MSG(s >= 1, "a split factor is at least 1");
            any = any || s > 1;
        }
        if (!any) {  // the whole grid as it was: one piece for the hemicube
            PatchGrid kept = g;
            kept.first_patch = static_cast<std::uint32_t>(out.patches.size());
            out.grids.push_back(kept);
            for (std::uint32_t c = 0; c < cells; ++c) {
                out.patches.push_back(scene.patches[g.first_patch + c]);
                r.parent.push_back(g.first_patch + c);
            }
            continue;
        }
        for (std::uint32_t c = 0; c < cells; ++c) {  // one grid per patch, 1 × 1 when kept
            const std::uint32_t i = g.first_patch + c;
            const Patch& p = scene.patches[i];
            const std::array<Vec3, 4> corners = scene.patch_vertices(i);
            const std::size_t before = out.patches.size();
            if (p.count == 4)
                split_quad(out, p, corners, split[i]);
            else
                split_triangle(out, p, corners, split[i]);
            r.parent.insert(r.parent.end(), out.patches.size() - before, i);
        }
    }
    FFCUBE_CHECK(r.parent.size() == out.patches.size());
    FFCUBE_CHECK_MSG(out.positions.size() < std::numeric_limits<std::uint32_t>::max(), "vertex indices must fit 32 bits");
    std::size_t refined = 0;
    for (const std::uint32_t s : split) refined += s > 1 ? 1 : 0;
    out.stats.how = scene.stats.how + fmt::format(", {} patches refined into {} elements", refined, out.patches.size());
    out.fingerprint = scene_fingerprint(out);
    return r;
}

}  // namespace ffcube
