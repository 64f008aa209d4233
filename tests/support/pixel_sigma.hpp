// Pixel discretisation σ of hemicube object-to-object values, from the actual item buffers.
// Used by the tests that compare hemicube results with analytic values (tests/gl, tests/bench).
//
// A pixel cut by a receiver's outline counts wholly or not at all, an error of at most its ΔF;
// under the seeded rotation these errors are independent and roughly uniform in ±ΔF/2 (variance
// ΔF²/12). For sender patch i, σ_i² = Σ_{cut pixels} ΔF²/12; for the object value
// σ² = Σ_i (A_i/A)² σ_i². Cut pixels are counted as both pixels of each 4-neighbour pair (within
// one face) showing different objects: about twice the cut pixels, so conservative.
#pragma once

#include <cmath>
#include <vector>

#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

// σ[a][b] for the value of object a → object b.
inline std::vector<std::vector<double>> pixel_sigma(HemicubeRowProvider& provider, const Scene& scene, int resolution) {
    const std::size_t m = scene.objects.size();
    std::vector<std::vector<double>> var(m, std::vector<double>(m, 0.0));
    std::vector<double> area(m, 0.0);
    for (const Patch& p : scene.patches) area[p.object] += p.area;
    const HemicubeLayout layout(resolution);
    const auto& dff = layout.delta_ff();
    const int W = layout.atlas_width();
    auto object_of = [&](std::uint32_t id) -> int {
        return id == 0 || id == 0xFFFFFFFFu ? -1 : static_cast<int>(scene.patches[id - 1].object);
    };
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const auto ids = provider.item_buffer(i);
        std::vector<double> vi(m, 0.0);
        for (const FaceSpec& f : layout.faces()) {
            const auto& vp = f.viewport;
            for (int y = vp.y; y < vp.y + vp.height; ++y)
                for (int x = vp.x; x < vp.x + vp.width; ++x) {
                    const std::size_t k = static_cast<std::size_t>(y) * W + x;
                    const std::size_t nb[2] = {x + 1 < vp.x + vp.width ? k + 1 : k, y + 1 < vp.y + vp.height ? k + W : k};
                    for (std::size_t kk : nb) {
                        const int o = object_of(ids[k]), o2 = object_of(ids[kk]);
                        if (o == o2) continue;
                        for (int obj : {o, o2})
                            if (obj >= 0) vi[static_cast<std::size_t>(obj)] += (dff[k] * dff[k] + dff[kk] * dff[kk]) / 12.0;
                    }
                }
        }
        const Patch& p = scene.patches[i];
        const double w = p.area / area[p.object];
        for (std::size_t b = 0; b < m; ++b) var[p.object][b] += w * w * vi[b];
    }
    for (auto& row : var)
        for (double& v : row) v = std::sqrt(v);
    return var;
}

}  // namespace ffcube::test
