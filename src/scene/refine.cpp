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
            // The mesher's layouts (scene.hpp, PatchGrid), so that a renderer finds an element from
            // its position in the grid exactly as it finds a patch.
            if (p.count == 4)
                append_quad_grid(out, corners, split[i], split[i], p);
            else
                append_triangle_grid(out, corners, split[i], p);
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
