#include "ffcube/geometry/tolerance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ffcube {

double max_abs_coordinate(std::span<const Vec3> poly) {
    double m = 0.0;
    for (const Vec3& v : poly) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    return m;
}

double geometric_tolerance(double rel_tol, double size, double coord_max) {
    return std::max(rel_tol * size, kCoordinateRoundingUlps * std::numeric_limits<double>::epsilon() * coord_max);
}

}  // namespace ffcube
