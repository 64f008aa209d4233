#include "ffcube/geometry/polygon.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace ffcube {

Vec3 newell_vector(std::span<const Vec3> poly) {
    Vec3 n(0.0);
    const std::size_t k = poly.size();
    if (k < 3) return n;
    // Relative to the first vertex: far-off coordinates (1e5) keep their precision.
    const Vec3 o = poly[0];
    for (std::size_t i = 1; i + 1 < k; ++i) n += glm::cross(poly[i] - o, poly[i + 1] - o);
    return n;
}

double polygon_area(std::span<const Vec3> poly) { return 0.5 * glm::length(newell_vector(poly)); }

Vec3 polygon_normal(std::span<const Vec3> poly) {
    const Vec3 n = newell_vector(poly);
    const double len = glm::length(n);
    return len > 0.0 ? n / len : Vec3(0.0);
}

Vec3 polygon_centroid(std::span<const Vec3> poly) {
    const std::size_t k = poly.size();
    if (k == 0) return Vec3(0.0);
    const Vec3 o = poly[0];
    const Vec3 n = newell_vector(poly);
    const double n2 = glm::dot(n, n);
    Vec3 mean(0.0);
    for (const Vec3& p : poly) mean += p - o;
    mean /= static_cast<double>(k);
    if (k < 3 || n2 <= 0.0) return o + mean;
    // Fan triangulation from vertex 0, each triangle weighted by its signed area along n.
    Vec3 acc(0.0);
    double wsum = 0.0;
    for (std::size_t i = 1; i + 1 < k; ++i) {
        const Vec3 a = poly[i] - o, b = poly[i + 1] - o;
        const double w = glm::dot(glm::cross(a, b), n);
        acc += w * (a + b) / 3.0;
        wsum += w;
    }
    return wsum != 0.0 ? o + acc / wsum : o + mean;
}

double polygon_planarity_deviation(std::span<const Vec3> poly) {
    if (poly.size() < 4) return 0.0;
    const Vec3 n = polygon_normal(poly);
    const Vec3 c = polygon_centroid(poly);
    double dev = 0.0;
    for (const Vec3& p : poly) dev = std::max(dev, std::abs(glm::dot(p - c, n)));
    return dev;
}

double polygon_max_edge(std::span<const Vec3> poly) {
    double m = 0.0;
    for (std::size_t i = 0; i < poly.size(); ++i)
        m = std::max(m, glm::length(poly[(i + 1) % poly.size()] - poly[i]));
    return m;
}

void orthonormal_basis(const Vec3& n, Vec3& t, Vec3& b) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double c = n.x * n.y * a;
    t = Vec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = Vec3(c, sign + n.y * n.y * a, -n.y);
}

}  // namespace ffcube
