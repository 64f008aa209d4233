// The error-against-time plot, drawn once through a small canvas interface with two back ends:
// SVG text, and an RGB raster (lines, markers, stb_easy_font text) written as PNG with
// stb_image_write. No runtime tool, no font file.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include "ffcube/bench/bench.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>
#include <stb/stb_easy_font.h>

namespace ffcube {
namespace {

struct Rgb {
    std::uint8_t r, g, b;
    std::string hex() const { return fmt::format("#{:02x}{:02x}{:02x}", r, g, b); }
};

enum class Anchor { Start, Middle, End };

// What the plot needs from a back end. Coordinates in pixels, y down.
class Canvas {
public:
    virtual ~Canvas() = default;
    virtual void line(double x0, double y0, double x1, double y1, Rgb c, double width, bool dashed) = 0;
    virtual void marker(double x, double y, bool square, Rgb c) = 0;
    // size: nominal text height in pixels; vertical: rotated 90° counter-clockwise about (x, y).
    virtual void text(double x, double y, const std::string& s, double size, Anchor a, bool vertical = false) = 0;
};

constexpr int kWidth = 960, kHeight = 640;
constexpr double kLeft = 90, kRight = 210, kTop = 40, kBottom = 70;  // margins; legend on the right

Rgb group_color(const std::string& g) {
    static const std::map<std::string, Rgb> colors = {{"basic", {31, 119, 180}},
                                                      {"enclosure", {255, 127, 14}},
                                                      {"proximity", {44, 160, 44}},
                                                      {"extreme", {214, 39, 40}},
                                                      {"occlusion", {148, 103, 189}}};
    const auto it = colors.find(g);
    return it == colors.end() ? Rgb{80, 80, 80} : it->second;
}

struct Curve {
    std::string method, group;
    std::vector<std::pair<double, double>> points;  // (seconds, error), in setting order
    std::vector<std::string> labels;                // the setting value, e.g. "256"
    std::vector<double> estimates;                  // runs to a target: the largest row estimate (else empty)
};

// Errors and times are clamped to these floors so that a zero stays on a log axis.
constexpr double kMinError = 1e-8, kMinSeconds = 1e-4;

// The groups drawn: the exact cases' groups, then "scene" (run_scene_sweep) when present.
std::vector<std::string> plot_groups(const std::vector<BenchResult>& results) {
    std::vector<std::string> groups = bench_groups();
    if (std::any_of(results.begin(), results.end(), [](const BenchResult& r) { return r.group == "scene"; }))
        groups.push_back("scene");
    return groups;
}

bool to_target(const std::string& method) { return method == "raycast@tolerance" || method == "auto@tolerance"; }

std::vector<Curve> make_curves(const std::vector<BenchResult>& results) {
    std::vector<Curve> curves;
    for (const char* method : {"hemicube", "hemicube+near", "raycast", "raycast@tolerance", "auto@tolerance"})
        for (const std::string& group : plot_groups(results)) {
            // setting value → (Σ seconds, max error), and the largest estimate
            std::map<double, std::pair<double, double>> by_setting;
            std::map<double, double> estimate;
            for (const BenchResult& r : results) {
                if (r.method != method || r.group != group) continue;
                auto& [s, e] = by_setting[r.value];
                s += r.seconds;
                e = std::max(e, r.errors.max_abs_error);
                if (!std::isnan(r.estimate)) estimate[r.value] = std::max(estimate[r.value], r.estimate);
            }
            if (by_setting.empty()) continue;
            Curve c{method, group, {}, {}, {}};
            for (const auto& [v, se] : by_setting) {
                c.points.emplace_back(std::max(se.first, kMinSeconds), std::max(se.second, kMinError));
                c.labels.push_back(fmt::format("{}", v));
                if (const auto it = estimate.find(v); it != estimate.end()) c.estimates.push_back(std::max(it->second, kMinError));
            }
            curves.push_back(std::move(c));
        }
    return curves;
}

void draw_plot(Canvas& cv, const std::vector<BenchResult>& results) {
    const std::vector<Curve> curves = make_curves(results);
    double xmin = std::numeric_limits<double>::infinity(), xmax = 0, ymin = xmin, ymax = 0;
    for (const Curve& c : curves) {
        for (const auto& [x, y] : c.points) {
            xmin = std::min(xmin, x), xmax = std::max(xmax, x);
            ymin = std::min(ymin, y), ymax = std::max(ymax, y);
        }
        for (double e : c.estimates) ymin = std::min(ymin, e), ymax = std::max(ymax, e);
    }
    if (curves.empty()) xmin = 1e-3, xmax = 1, ymin = 1e-4, ymax = 1;
    // Whole decades around the data.
    const int dx0 = static_cast<int>(std::floor(std::log10(xmin))), dx1 = static_cast<int>(std::ceil(std::log10(xmax)));
    const int dy0 = static_cast<int>(std::floor(std::log10(ymin))), dy1 = static_cast<int>(std::ceil(std::log10(ymax)));
    const int nx = std::max(1, dx1 - dx0), ny = std::max(1, dy1 - dy0);
    const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
    auto X = [&](double x) { return kLeft + (std::log10(x) - dx0) / nx * pw; };
    auto Y = [&](double y) { return kTop + ph - (std::log10(y) - dy0) / ny * ph; };

    const Rgb grid{225, 225, 225}, axis{0, 0, 0};
    for (int d = 0; d <= nx; ++d) {
        const double x = kLeft + d * pw / nx;
        cv.line(x, kTop, x, kTop + ph, grid, 1, false);
        cv.text(x, kTop + ph + 18, fmt::format("1e{}", dx0 + d), 12, Anchor::Middle);
    }
    for (int d = 0; d <= ny; ++d) {
        const double y = kTop + ph - d * ph / ny;
        cv.line(kLeft, y, kLeft + pw, y, grid, 1, false);
        cv.text(kLeft - 8, y + 4, fmt::format("1e{}", dy0 + d), 12, Anchor::End);
    }
    cv.line(kLeft, kTop + ph, kLeft + pw, kTop + ph, axis, 1.5, false);
    cv.line(kLeft, kTop, kLeft, kTop + ph, axis, 1.5, false);
    cv.text(kLeft + pw / 2, kHeight - 22, "wall seconds of the row computation (sum over the group's cases)", 13,
            Anchor::Middle);
    cv.text(24, kTop + ph / 2, "max |F - F_exact| (object level, worst case of the group; scene: rows)", 13,
            Anchor::Middle, true);
    cv.text(kLeft + pw / 2, 24, "ffcube bench: error against run time", 15, Anchor::Middle);

    for (const Curve& c : curves) {
        const Rgb col = group_color(c.group);
        const bool ray = c.method == "raycast" || to_target(c.method);
        // corrected: the thick solid line; rows refined to a target: the thick dashed one
        const double width = c.method == "hemicube+near" || to_target(c.method) ? 4 : 2;
        for (std::size_t k = 0; k + 1 < c.points.size(); ++k)
            cv.line(X(c.points[k].first), Y(c.points[k].second), X(c.points[k + 1].first), Y(c.points[k + 1].second), col,
                    width, ray);
        for (std::size_t k = 0; k < c.points.size(); ++k) {
            cv.marker(X(c.points[k].first), Y(c.points[k].second), ray, col);
            cv.text(X(c.points[k].first) + 6, Y(c.points[k].second) - 6, c.labels[k], 10, Anchor::Start);
        }
        // Each run's estimate beside its true error: a bar at the estimate, joined to the point.
        if (c.estimates.size() == c.points.size())
            for (std::size_t k = 0; k < c.points.size(); ++k) {
                const double x = X(c.points[k].first), ye = Y(c.estimates[k]);
                cv.line(x, Y(c.points[k].second), x, ye, col, 1, true);
                cv.line(x - 7, ye, x + 7, ye, col, 3, false);
            }
    }

    // Legend: groups by colour, methods by line style.
    double ly = kTop + 10;
    const double lx = kWidth - kRight + 20;
    for (const std::string& g : plot_groups(results)) {
        cv.line(lx, ly, lx + 28, ly, group_color(g), 3, false);
        cv.text(lx + 36, ly + 4, g == "scene" ? "scene (sampled rows)" : g, 12, Anchor::Start);
        ly += 20;
    }
    ly += 10;
    cv.line(lx, ly, lx + 28, ly, axis, 2, false);
    cv.marker(lx + 14, ly, false, axis);
    cv.text(lx + 36, ly + 4, "hemicube (N)", 12, Anchor::Start);
    ly += 20;
    if (std::any_of(curves.begin(), curves.end(), [](const Curve& c) { return c.method == "hemicube+near"; })) {
        cv.line(lx, ly, lx + 28, ly, axis, 4, false);
        cv.marker(lx + 14, ly, false, axis);
        cv.text(lx + 36, ly + 4, "hemicube+near (N)", 12, Anchor::Start);
        ly += 20;
    }
    cv.line(lx, ly, lx + 28, ly, axis, 2, true);
    cv.marker(lx + 14, ly, true, axis);
    cv.text(lx + 36, ly + 4, "raycast (rays)", 12, Anchor::Start);
    if (std::any_of(curves.begin(), curves.end(), [](const Curve& c) { return to_target(c.method); })) {
        ly += 20;
        cv.line(lx, ly, lx + 28, ly, axis, 4, true);
        cv.marker(lx + 14, ly, true, axis);
        cv.text(lx + 36, ly + 4, "to E (bar: estimate)", 12, Anchor::Start);
    }
}

std::string xml_escape(const std::string& s) {
    std::string o;
    for (char ch : s) {
        if (ch == '&') o += "&amp;";
        else if (ch == '<') o += "&lt;";
        else if (ch == '>') o += "&gt;";
        else o += ch;
    }
    return o;
}

class SvgCanvas final : public Canvas {
public:
    std::ostringstream os;
    SvgCanvas() {
        os << fmt::format(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
            "font-family=\"sans-serif\">\n<rect width=\"{0}\" height=\"{1}\" fill=\"#ffffff\"/>\n",
            kWidth, kHeight);
    }
    void line(double x0, double y0, double x1, double y1, Rgb c, double width, bool dashed) override {
        os << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"{}\" stroke-width=\"{}\"{}/>\n",
                          x0, y0, x1, y1, c.hex(), width, dashed ? " stroke-dasharray=\"6,4\"" : "");
    }
    void marker(double x, double y, bool square, Rgb c) override {
        if (square)
            os << fmt::format("<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"8\" height=\"8\" fill=\"{}\"/>\n", x - 4, y - 4, c.hex());
        else
            os << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"4\" fill=\"{}\"/>\n", x, y, c.hex());
    }
    void text(double x, double y, const std::string& s, double size, Anchor a, bool vertical) override {
        const char* anchor = a == Anchor::Start ? "start" : a == Anchor::Middle ? "middle" : "end";
        os << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" font-size=\"{}\" text-anchor=\"{}\"{}>{}</text>\n", x, y, size,
                          anchor, vertical ? fmt::format(" transform=\"rotate(-90 {:.2f} {:.2f})\"", x, y) : "",
                          xml_escape(s));
    }
    std::string finish() { return os.str() + "</svg>\n"; }
};

class RasterCanvas final : public Canvas {
public:
    std::vector<std::uint8_t> rgb = std::vector<std::uint8_t>(static_cast<std::size_t>(kWidth) * kHeight * 3, 255);

    void line(double x0, double y0, double x1, double y1, Rgb c, double width, bool dashed) override {
        // Stamps discs of the line's width every half pixel; dashes of 6 px on, 4 off as in the SVG.
        const double len = std::hypot(x1 - x0, y1 - y0);
        const int steps = std::max(1, static_cast<int>(len * 2));
        for (int k = 0; k <= steps; ++k) {
            const double t = static_cast<double>(k) / steps;
            if (dashed && std::fmod(t * len, 10.0) >= 6.0) continue;
            disc(x0 + t * (x1 - x0), y0 + t * (y1 - y0), width / 2, c);
        }
    }
    void marker(double x, double y, bool square, Rgb c) override {
        if (square)
            fill_rect(x - 4, y - 4, x + 4, y + 4, c);
        else
            disc(x, y, 4, c);
    }
    void text(double x, double y, const std::string& s, double size, Anchor a, bool vertical) override {
        // stb_easy_font: glyphs about 7 units tall; scaled so capitals are ~0.7 × size.
        const double scale = size / 10.0;
        std::vector<char> buf(s.size() * 64 * 16 + 64);  // at most 16 quads of 64 bytes per glyph
        std::string str = s;
        const int quads = stb_easy_font_print(0, 0, str.data(), nullptr, buf.data(), static_cast<int>(buf.size()));
        const double w = stb_easy_font_width(str.data()) * scale;
        const double shift = a == Anchor::Start ? 0 : a == Anchor::Middle ? -w / 2 : -w;
        const double base = -7 * scale;  // stb's y grows down from the top of the glyphs; (x, y) is the baseline
        const auto* v = reinterpret_cast<const float*>(buf.data());
        for (int q = 0; q < quads; ++q) {
            const float* p = v + q * 16;  // 4 vertices of (x, y, z, colour)
            const double u0 = p[0] * scale + shift, t0 = p[1] * scale + base;
            const double u1 = p[8] * scale + shift, t1 = p[9] * scale + base;
            if (vertical)
                fill_rect(x + t0, y - u1, x + t1, y - u0, Rgb{0, 0, 0});
            else
                fill_rect(x + u0, y + t0, x + u1, y + t1, Rgb{0, 0, 0});
        }
    }

private:
    void put(int x, int y, Rgb c, double alpha = 1.0) {
        if (x < 0 || y < 0 || x >= kWidth || y >= kHeight) return;
        std::uint8_t* px = &rgb[(static_cast<std::size_t>(y) * kWidth + x) * 3];
        px[0] = static_cast<std::uint8_t>(std::lround(px[0] + alpha * (c.r - px[0])));
        px[1] = static_cast<std::uint8_t>(std::lround(px[1] + alpha * (c.g - px[1])));
        px[2] = static_cast<std::uint8_t>(std::lround(px[2] + alpha * (c.b - px[2])));
    }
    void disc(double cx, double cy, double r, Rgb c) {
        r = std::max(r, 0.6);
        for (int y = static_cast<int>(std::floor(cy - r - 1)); y <= static_cast<int>(std::ceil(cy + r + 1)); ++y)
            for (int x = static_cast<int>(std::floor(cx - r - 1)); x <= static_cast<int>(std::ceil(cx + r + 1)); ++x) {
                // Coverage from the distance of the pixel centre to the disc's edge: soft edges.
                const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
                const double cover = std::clamp(r + 0.5 - d, 0.0, 1.0);
                if (cover > 0) put(x, y, c, cover);
            }
    }
    // Pixels whose centres lie in the rectangle, at least one per axis (stb_easy_font's strokes
    // are one unit wide, thinner than a pixel at small sizes).
    void fill_rect(double x0, double y0, double x1, double y1, Rgb c) {
        const int xa = static_cast<int>(std::lround(std::min(x0, x1))), ya = static_cast<int>(std::lround(std::min(y0, y1)));
        const int xb = std::max(xa + 1, static_cast<int>(std::lround(std::max(x0, x1))));
        const int yb = std::max(ya + 1, static_cast<int>(std::lround(std::max(y0, y1))));
        for (int y = ya; y < yb; ++y)
            for (int x = xa; x < xb; ++x) put(x, y, c);
    }
};

void png_to_string(void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
}

}  // namespace

std::string bench_plot_svg(const std::vector<BenchResult>& results) {
    SvgCanvas cv;
    draw_plot(cv, results);
    return cv.finish();
}

void write_bench_plot_svg(const std::filesystem::path& path, const std::vector<BenchResult>& results) {
    const std::string svg = bench_plot_svg(results);
    write_file_atomically(path, [&](std::ostream& os) { os << svg; });
}

void write_bench_plot_png(const std::filesystem::path& path, const std::vector<BenchResult>& results) {
    RasterCanvas cv;
    draw_plot(cv, results);
    std::string png;
    if (!stbi_write_png_to_func(png_to_string, &png, kWidth, kHeight, 3, cv.rgb.data(), kWidth * 3))
        throw InternalError("bench: PNG encoding failed");
    write_file_atomically(path, [&](std::ostream& os) { os.write(png.data(), static_cast<std::streamsize>(png.size())); });
}

}  // namespace ffcube
