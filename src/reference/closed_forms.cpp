// Howell's closed forms (ffcube/reference/closed_forms.hpp): the bench's and the tests'
// independent references.
#include "ffcube/reference/closed_forms.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numbers>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

constexpr double kPi = std::numbers::pi;

void require_positive(const char* fn, const char* name, double v) {
    if (!(v > 0.0) || !std::isfinite(v))
        throw InputError(fmt::format("{}: {} = {} must be positive and finite", fn, name, v));
}

// φ(X, Y) = s·atan(X/s) − atan X with s = √(1+Y²): positive, and O(X³Y²) for small X, Y,
// where the two terms agree to many digits. Small X: its alternating Taylor series,
//   φ = Σ_{k≥1} (−1)^(k+1) X^(2k+1) (1 − q^k)/(2k+1),  q = 1/s², 1 − q^k = m(1 + q + … + q^(k−1)),
// m = 1 − q = Y²/(1+Y²); at X ≤ ½ term k is below 4^−k of the first, so 26 terms reach 1e-16.
// Otherwise φ = (s−1)·atan(X/s) − (atan X − atan(X/s)) with s − 1 = Y²/(s+1) and the atan
// difference as one atan: both parts are then exact to rounding and their difference loses at
// most a factor ~5 (X ≥ ½).
double opposed_phi(double x, double y) {
    const double s = std::sqrt(1.0 + y * y);
    if (x <= 0.5) {
        const double q = 1.0 / (s * s), m = y * y / (1.0 + y * y), x2 = x * x;
        double sum = 0.0, xpow = x, qsum = 0.0, qpow = 1.0, sign = 1.0;
        for (int k = 1; k <= 26; ++k) {
            xpow *= x2;
            qsum += qpow;
            qpow *= q;
            sum += sign * xpow * m * qsum / (2.0 * k + 1.0);
            sign = -sign;
        }
        return sum;
    }
    const double sm1 = y * y / (s + 1.0);
    return sm1 * std::atan(x / s) - std::atan(x * sm1 / (s + x * x));
}

}  // namespace

double ff_parallel_rectangles(double a, double b, double c) {
    const char* fn = "ff_parallel_rectangles";
    require_positive(fn, "a", a);
    require_positive(fn, "b", b);
    require_positive(fn, "c", c);
    const double x = a / c, y = b / c;
    // Howell's bracket regrouped into three positive parts (no cancellation, so far-apart and
    // thin rectangles keep full precision): ½ ln(1 + X²Y²/(1+X²+Y²)) + X φ(X,Y) + Y φ(Y,X).
    const double brace = 0.5 * std::log1p(x * x * y * y / (1.0 + x * x + y * y)) +
                         x * opposed_phi(x, y) + y * opposed_phi(y, x);
    return 2.0 / (kPi * x * y) * brace;
}

double ff_parallel_rectangles_offset(double x1, double x2, double y1, double y2, double xi1,
                                     double xi2, double eta1, double eta2, double c) {
    const char* fn = "ff_parallel_rectangles_offset";
    require_positive(fn, "c", c);
    require_positive(fn, "x2 - x1", x2 - x1);
    require_positive(fn, "y2 - y1", y2 - y1);
    require_positive(fn, "xi2 - xi1", xi2 - xi1);
    require_positive(fn, "eta2 - eta1", eta2 - eta1);
    const double c2 = c * c;
    const auto g = [c2](double u, double v) {
        const double su = std::sqrt(u * u + c2), sv = std::sqrt(v * v + c2);
        return v * su * std::atan(v / su) + u * sv * std::atan(u / sv) -
               0.5 * c2 * std::log(u * u + v * v + c2);
    };
    const std::array<double, 2> x = {x1, x2}, y = {y1, y2}, xi = {xi1, xi2}, eta = {eta1, eta2};
    double sum = 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k)
                for (int l = 0; l < 2; ++l) {
                    const double sign = ((i + j + k + l) % 2 == 0) ? 1.0 : -1.0;
                    sum += sign * g(x[i] - xi[k], y[j] - eta[l]);
                }
    return sum / (2.0 * kPi * (x2 - x1) * (y2 - y1));
}

double ff_perpendicular_rectangles_common_edge(double l, double w, double h) {
    const char* fn = "ff_perpendicular_rectangles_common_edge";
    require_positive(fn, "l", l);
    require_positive(fn, "w", w);
    require_positive(fn, "h", h);
    const double H = h / l, W = w / l;
    const double H2 = H * H, W2 = W * W, s = std::sqrt(H2 + W2);
    // The log of the product, taken as a sum of logs so that the large powers cannot overflow.
    const double log_term = std::log((1.0 + W2) * (1.0 + H2) / (1.0 + W2 + H2)) +
                            W2 * std::log(W2 * (1.0 + W2 + H2) / ((1.0 + W2) * (W2 + H2))) +
                            H2 * std::log(H2 * (1.0 + H2 + W2) / ((1.0 + H2) * (H2 + W2)));
    return (W * std::atan(1.0 / W) + H * std::atan(1.0 / H) - s * std::atan(1.0 / s) +
            0.25 * log_term) /
           (kPi * W);
}

double ff_coaxial_disks(double r1, double r2, double h) {
    const char* fn = "ff_coaxial_disks";
    require_positive(fn, "r1", r1);
    require_positive(fn, "r2", r2);
    require_positive(fn, "h", h);
    const double R1 = r1 / h, R2 = r2 / h;
    const double X = 1.0 + (1.0 + R2 * R2) / (R1 * R1);
    const double q = R2 / R1;
    // X − √(X² − 4q²) cancels when X is large (small disks far apart): use the conjugate form
    // 4q² / (X + √(X² − 4q²)), equal in exact arithmetic.
    return 0.5 * (4.0 * q * q) / (X + std::sqrt(X * X - 4.0 * q * q));
}

double ff_diff_parallel_rect(double a, double b, double c) {
    const char* fn = "ff_diff_parallel_rect";
    require_positive(fn, "a", a);
    require_positive(fn, "b", b);
    require_positive(fn, "c", c);
    const double A = a / c, B = b / c;
    const double sa = std::sqrt(1.0 + A * A), sb = std::sqrt(1.0 + B * B);
    return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2.0 * kPi);
}

double ff_diff_perpendicular_rect(double width, double height, double c) {
    const char* fn = "ff_diff_perpendicular_rect";
    require_positive(fn, "width", width);
    require_positive(fn, "height", height);
    require_positive(fn, "c", c);
    const double W = width / c, H = height / c;
    const double s = std::sqrt(1.0 + H * H), sm1 = H * H / (s + 1.0);
    // atan W − atan(W/s)/s = atan(W(s−1)/(s+W²)) + atan(W/s)(s−1)/s: two positive parts, so a
    // far or low rectangle (small H, where s → 1) keeps full precision.
    return (std::atan(W * sm1 / (s + W * W)) + std::atan(W / s) * sm1 / s) / (2.0 * kPi);
}

SphereFactors ff_concentric_spheres(double r1, double r2) {
    const char* fn = "ff_concentric_spheres";
    require_positive(fn, "r1", r1);
    require_positive(fn, "r2", r2);
    if (r2 < r1)
        throw InputError(fmt::format("{}: outer radius r2 = {} is smaller than inner r1 = {}", fn,
                                     r2, r1));
    const double q = (r1 / r2) * (r1 / r2);
    return {1.0, q, 1.0 - q};
}

}  // namespace ffcube
