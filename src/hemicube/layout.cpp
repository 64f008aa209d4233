#include "ffcube/hemicube/layout.hpp"

#include "ffcube/core/error.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ffcube {

namespace {

constexpr double kInv2Pi = 0.5 / std::numbers::pi;

// Top face (plane at distance 1): ∫∫ dx dy / (π (1+x²+y²)²) has the antiderivative
//   G(x,y) = 1/(2π) [ x/√(1+x²) · atan(y/√(1+x²)) + y/√(1+y²) · atan(x/√(1+y²)) ],
// which is also the form factor from a differential element to the rectangle [0,x]×[0,y] at
// distance 1 with a corner over the element (Howell B-1 style), i.e. ∂²G/∂x∂y is the integrand.
double top_antiderivative(double x, double y) {
    const double cx = std::sqrt(1.0 + x * x);
    const double cy = std::sqrt(1.0 + y * y);
    return kInv2Pi * (x / cx * std::atan(y / cx) + y / cy * std::atan(x / cy));
}

// Exact ΔF of the top-face rectangle [a0,a1]×[b0,b1] with 0 ≤ a0 < a1, 0 ≤ b0 < b1. Grouping
// the four terms as (corner sums) makes the result bit-identical when x and y swap, since
// G(x,y) = G(y,x) term for term and floating-point addition commutes.
double top_rect(double a0, double a1, double b0, double b1) {
    return (top_antiderivative(a1, b1) + top_antiderivative(a0, b0)) -
           (top_antiderivative(a0, b1) + top_antiderivative(a1, b0));
}

// Side face (plane at distance 1, u horizontal, z height above the patch plane): the
// integrand is z / (π (1+u²+z²)²). Integrating z over [z0,z1] first gives
//   1/(2π) [ 1/(1+u²+z0²) − 1/(1+u²+z1²) ],
// and ∫ du/(c²+u²) = atan(u/c)/c with c² = 1+z², so H(u,z) = atan(u/c)/c is the u-antiderivative.
double side_antiderivative(double u, double z) {
    const double c = std::sqrt(1.0 + z * z);
    return std::atan(u / c) / c;
}

// Exact ΔF of the side-face rectangle u ∈ [a0,a1], z ∈ [z0,z1] with 0 ≤ a0 < a1.
double side_rect(double a0, double a1, double z0, double z1) {
    return kInv2Pi * ((side_antiderivative(a1, z0) - side_antiderivative(a0, z0)) -
                      (side_antiderivative(a1, z1) - side_antiderivative(a0, z1)));
}

// The integrands are even in the horizontal coordinate(s), so every pixel is evaluated on its
// mirror image in the non-negative quarter: mirrored pixels then get bit-identical values.
// Pixel edges (2i − N)/N are exact negatives of each other, and N even puts an edge at 0.
struct Interval {
    double lo, hi;
};
Interval folded(double e0, double e1) { return e1 <= 0.0 ? Interval{-e1, -e0} : Interval{e0, e1}; }

}  // namespace

void check_row_resolution(int resolution, std::string_view what) {
    if (resolution < kMinRowResolution || resolution > kMaxRowResolution || resolution % 2 != 0)
        throw InputError(fmt::format("{} {}: must be an even number of pixels from {} to {}", what, resolution,
                                     kMinRowResolution, kMaxRowResolution));
}

HemicubeLayout::HemicubeLayout(int resolution) : n_(resolution) {
    if (resolution < 2 || resolution > 16384 || resolution % 2 != 0)
        throw InputError(fmt::format(
            "hemicube resolution {}: must be an even number of pixels in [2, 16384] (the side faces "
            "are N × N/2 pixels)",
            resolution));
    const int n = n_, h = n_ / 2;
    const Vec3 px(1, 0, 0), py(0, 1, 0), pz(0, 0, 1);
    const FaceFrustum top_fr{-1.0, 1.0, -1.0, 1.0};
    const FaceFrustum side_fr{-1.0, 1.0, 0.0, 1.0};
    faces_ = {{
        {HemicubeFace::Top, pz, py, -px, top_fr, {0, 0, n, n}},
        {HemicubeFace::PosX, px, pz, -py, side_fr, {n, 0, n, h}},
        {HemicubeFace::NegX, -px, pz, py, side_fr, {n, h, n, h}},
        {HemicubeFace::PosY, py, pz, px, side_fr, {2 * n, 0, n, h}},
        {HemicubeFace::NegY, -py, pz, -px, side_fr, {2 * n, h, n, h}},
    }};

    // Pixel edges along the horizontal [-1,1] (both faces) and the vertical [-1,1] (top) or
    // [0,1] (sides). Computed once, shared by all faces, so equal edges are equal bits.
    std::vector<double> e(static_cast<std::size_t>(n) + 1), ez(static_cast<std::size_t>(h) + 1);
    for (int i = 0; i <= n; ++i) e[i] = static_cast<double>(2 * i - n) / n;
    for (int j = 0; j <= h; ++j) ez[j] = static_cast<double>(j) / h;

    const int w = atlas_width();
    dff_.assign(static_cast<std::size_t>(w) * n, 0.0);
    for (int j = 0; j < n; ++j) {
        const Interval b = folded(e[j], e[j + 1]);
        for (int i = 0; i < n; ++i) {
            const Interval a = folded(e[i], e[i + 1]);
            dff_[static_cast<std::size_t>(j) * w + i] = top_rect(a.lo, a.hi, b.lo, b.hi);
        }
    }
    // The four side tiles hold the same table: fill one row of values and copy it to each.
    std::vector<double> side_row(static_cast<std::size_t>(n));
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < n; ++i) {
            const Interval a = folded(e[i], e[i + 1]);
            side_row[i] = side_rect(a.lo, a.hi, ez[j], ez[j + 1]);
        }
        for (int f = 1; f < 5; ++f) {
            const AtlasViewport& vp = faces_[f].viewport;
            std::copy(side_row.begin(), side_row.end(),
                      dff_.begin() + static_cast<std::ptrdiff_t>(vp.y + j) * w + vp.x);
        }
    }
    // The prefix tables (row_segments): the top face's rows 0 … N/2 − 1 (row N−1−y has row y's
    // values, bit for bit: folded above), then the side faces' rows 0 … N/2 − 1.
    const std::size_t table = static_cast<std::size_t>(n) + 1;
    prefix_.assign(table * static_cast<std::size_t>(n), 0.0);
    auto fill = [&](std::size_t t, const double* row) {
        double* out = prefix_.data() + t * table;
        double sum = 0.0;
        out[0] = 0.0;
        for (int i = 0; i < n; ++i) {
            sum += row[i];
            out[i + 1] = sum;
        }
    };
    for (int j = 0; j < h; ++j) fill(static_cast<std::size_t>(j), dff_.data() + static_cast<std::size_t>(j) * w);
    for (int j = 0; j < h; ++j)
        fill(static_cast<std::size_t>(h + j), dff_.data() + static_cast<std::size_t>(j) * w + faces_[1].viewport.x);
    segments_.resize(static_cast<std::size_t>(n));
    for (int y = 0; y < n; ++y) {
        const auto top = static_cast<std::uint32_t>(std::min(y, n - 1 - y) * table);
        const auto side = static_cast<std::uint32_t>((h + y % h) * table);
        const auto un = static_cast<std::uint32_t>(n);
        segments_[static_cast<std::size_t>(y)] = {{{0, un, top}, {un, 2 * un, side}, {2 * un, 3 * un, side}}};
    }
}

std::optional<AtlasPixel> HemicubeLayout::pixel_of_direction(const Vec3& d) const {
    if (!(d.z >= 0.0) || (d.x == 0.0 && d.y == 0.0 && d.z == 0.0)) return std::nullopt;
    const double ax = std::abs(d.x), ay = std::abs(d.y);
    HemicubeFace f;
    if (d.z >= ax && d.z >= ay)
        f = HemicubeFace::Top;
    else if (ax >= ay)
        f = d.x > 0.0 ? HemicubeFace::PosX : HemicubeFace::NegX;
    else
        f = d.y > 0.0 ? HemicubeFace::PosY : HemicubeFace::NegY;
    const FaceSpec& s = face(f);
    const double depth = glm::dot(d, s.forward);  // > 0: the dominant axis was chosen
    const double u = glm::dot(d, s.right) / depth, v = glm::dot(d, s.up) / depth;
    const FaceFrustum& fr = s.frustum;
    const AtlasViewport& vp = s.viewport;
    const auto cell = [](double t, double lo, double hi, int count) {
        const int k = static_cast<int>(std::floor((t - lo) / (hi - lo) * count));
        return std::clamp(k, 0, count - 1);
    };
    return AtlasPixel{f, vp.x + cell(u, fr.left, fr.right, vp.width),
                      vp.y + cell(v, fr.bottom, fr.top, vp.height)};
}

}  // namespace ffcube
