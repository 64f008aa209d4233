// run_viewer on one scene and its rows (no adaptive levels): the viewer's ViewerLevels with one level.
#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/viewer/viewer.hpp"

namespace ffcube {
namespace {

// One level that ends with its solve: a plain (not adaptive) view.
class SingleLevel final : public ViewerLevels {
public:
    SingleLevel(const Scene& scene, RowProvider& rows, HemicubeRowProvider* hemicube, std::span<const std::uint32_t> origin)
        : scene_(scene), rows_(rows), hemicube_(hemicube), origin_(origin) {}
    const Scene& scene() const override { return scene_; }
    RowProvider& provider() override { return rows_; }
    HemicubeRowProvider* hemicube() override { return hemicube_; }
    std::span<const std::uint32_t> origin() const override { return origin_; }
    std::uint32_t level() const override { return 0; }
    bool finish(const SolveResult&) override { return false; }
    void advance() override { throw InternalError("SingleLevel::advance: there is no next level"); }

private:
    const Scene& scene_;
    RowProvider& rows_;
    HemicubeRowProvider* hemicube_;
    std::span<const std::uint32_t> origin_;
};

}  // namespace

SolveResult run_viewer(const Scene& scene, RowProvider& rows, HemicubeRowProvider* hemicube, const SolverOptions& solver_options,
                       const ViewerOptions& options, std::span<const std::uint32_t> origin) {
    if (!origin.empty() && origin.size() != scene.size())
        throw InternalError(fmt::format("run_viewer: {} origins for {} patches", origin.size(), scene.size()));
    SingleLevel level(scene, rows, hemicube, origin);
    return run_viewer(level, solver_options, options);
}

}  // namespace ffcube
