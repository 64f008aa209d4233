// ffcube view end to end: the real binary in a real window under Xvfb (started by xvfb-run -a on
// a free display), driven by --frames/--pick/--screenshot, checked through the saved images.
// Small on purpose (320×240, about 300 patches, 64-pixel hemicubes) so that llvmpipe keeps each
// run well under a second or two.
#include <OpenEXR/ImfRgbaFile.h>
#include <gtest/gtest.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <vector>

#include "cli/cli_util.hpp"
#include <glm/geometric.hpp>

#include "ffcube/io/ffm.hpp"
#include "ffcube/viewer/display.hpp"

namespace ffcube {
namespace {

using test::RunResult;
using test::TempDir;

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgb;
    Vec3 at(int x, int y) const {  // 0..255 per channel, (0, 0) the top left
        const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
        return Vec3(rgb[i], rgb[i + 1], rgb[i + 2]);
    }
    double mean() const {
        double s = 0.0;
        for (std::uint8_t v : rgb) s += v;
        return s / static_cast<double>(rgb.size());
    }
};

Image load_png(const std::string& path) {
    Image im;
    int n = 0;
    stbi_uc* data = stbi_load(path.c_str(), &im.width, &im.height, &n, 3);
    if (!data) return im;
    im.rgb.assign(data, data + 3 * im.width * im.height);
    stbi_image_free(data);
    return im;
}

bool have_xvfb() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

// Runs `ffcube view` with the small test settings and ARGS inside a fresh Xvfb (quiet: -q, no log).
RunResult view(const std::string& args, bool quiet = true) {
    const std::string cmd = "xvfb-run -a -s '-screen 0 640x480x24' " + std::string(FFCUBE_BINARY) + " view " +
                            (quiet ? "-q " : "") + "--patches 300 --resolution 64 --size 320x240 --hide-ui " + args + " 2>&1";
    RunResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
    const int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return r;
}

#define REQUIRE_XVFB() \
    if (!have_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (Debian packages xvfb and xauth): no X display for the viewer"

TEST(ViewCli, ScreenshotShowsTheLitCornellBox) {
    REQUIRE_XVFB();
    TempDir dir;
    const RunResult r = view("--frames 20 --screenshot " + dir / "a.png");
    ASSERT_EQ(r.code, 0) << r.output;
    const Image im = load_png(dir / "a.png");
    ASSERT_EQ(im.width, 320);
    ASSERT_EQ(im.height, 240);
    double mean = im.mean(), var = 0.0;
    for (std::uint8_t v : im.rgb) var += (v - mean) * (v - mean);
    EXPECT_GT(var / static_cast<double>(im.rgb.size()), 100.0);  // not one flat colour
    // The red and green walls: pixels where one channel clearly dominates (by 40 of 255).
    int red = 0, green = 0;
    for (int y = 0; y < im.height; ++y)
        for (int x = 0; x < im.width; ++x) {
            const Vec3 c = im.at(x, y);
            red += c.r > c.g + 40 && c.r > c.b + 40;
            green += c.g > c.r + 20 && c.g > c.b + 40;
        }
    EXPECT_GT(red, 500) << "no red wall";
    EXPECT_GT(green, 500) << "no green wall";
}

TEST(ViewCli, MoreShotsBrightenTheImage) {
    REQUIRE_XVFB();
    TempDir dir;
    // One shot per frame, no ambient term, a fixed exposure: each classic shot (no overshoot)
    // only adds radiosity, so the display can only brighten, and 38 more shots bring light to
    // surfaces in view.
    const std::string common = "--no-ambient --exposure 0 --shots-per-frame 1 --batch 1 ";
    ASSERT_EQ(view(common + "--frames 2 --screenshot " + dir / "few.png").code, 0);
    ASSERT_EQ(view(common + "--frames 40 --screenshot " + dir / "many.png").code, 0);
    const double few = load_png(dir / "few.png").mean(), many = load_png(dir / "many.png").mean();
    EXPECT_GT(many, few + 1.0) << "few " << few << " many " << many;
}

// The viewer gets its rows from the same factory as `ffcube formfactors` (and `solve`), with
// every row option honoured: the row of a picked patch is the formfactors row, entry count and
// sum alike. Options that change rows (--correct near with the far field on, --near-k, no
// rotation) are given to both, so a viewer that dropped one would show a different row.
TEST(ViewCli, PickedRowIsTheFormFactorsRow) {
    REQUIRE_XVFB();
    TempDir dir;
    const std::string rows = "--patches 300 --resolution 64 --correct near --far-field on --near-k 2.5 --no-rotate ";
    const RunResult ff = test::run_ffcube("formfactors -q " + rows + "-o " + dir / "F.ffm");
    ASSERT_EQ(ff.code, 0) << ff.output;
    const std::string cmd = "xvfb-run -a -s '-screen 0 640x480x24' " + std::string(FFCUBE_BINARY) + " view " + rows +
                            "--size 320x240 --hide-ui --frames 2 --pick 170,100 2>&1";
    RunResult v;
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) v.output.append(buf, n);
    ASSERT_EQ(pclose(p), 0) << v.output;
    const auto at = v.output.find("picked patch ");
    ASSERT_NE(at, std::string::npos) << v.output;
    unsigned patch = 0;
    std::size_t count = 0;
    double sum = -1;
    const std::string line = v.output.substr(at, v.output.find('\n', at) - at);
    ASSERT_EQ(std::sscanf(line.c_str(), "picked patch %u", &patch), 1) << line;
    const auto colon = line.find("): ");
    ASSERT_NE(colon, std::string::npos) << line;
    ASSERT_EQ(std::sscanf(line.c_str() + colon, "): %zu form factors, row sum %lf", &count, &sum), 2) << line;
    const FfmFile F = read_ffm(dir / "F.ffm");
    ASSERT_LT(patch, F.matrix.size());
    const RowView row = F.matrix.row(patch);
    EXPECT_EQ(count, row.col.size()) << line;
    // The same floats summed in the same order (SparseRow::sum and RowView::sum both sum in
    // double in column order); printed with 9 significant digits.
    EXPECT_NEAR(sum, row.sum(), 1e-8 * std::max(1.0, row.sum())) << line;
}

TEST(ViewCli, ScriptedPickShowsTheRowAsAHeatMap) {
    REQUIRE_XVFB();
    TempDir dir;
    // (170, 100) lies inside a back-wall patch in the default view of the built-in box meshed
    // uncut (the coordinates were chosen for that mesh; with the default contact cuts, --patches 300
    // meshes differently and that pixel is no longer drawn in the picked colour).
    const RunResult plain = view("--no-contact-cuts --frames 3 --screenshot " + dir / "plain.png");
    const RunResult picked = view("--no-contact-cuts --frames 3 --pick 170,100 --screenshot " + dir / "picked.png");
    ASSERT_EQ(plain.code, 0) << plain.output;
    ASSERT_EQ(picked.code, 0) << picked.output;
    const Image a = load_png(dir / "plain.png"), b = load_png(dir / "picked.png");
    ASSERT_EQ(b.width, 320);
    auto is = [](const Vec3& pixel, const Vec3& colour) { return glm::length(pixel - 255.0 * colour) < 1.5; };
    EXPECT_TRUE(is(b.at(170, 100), kPicked));
    // The back wall around it is coplanar with the picked patch: F = 0 exactly, so the marker
    // colour; the same pixels in the plain run show lit wall.
    int picked_px = 0, zero_px = 0, ramp_px = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            const Vec3 c = b.at(x, y);
            picked_px += is(c, kPicked);
            zero_px += is(c, kNoContribution);
            for (int k = 0; k <= 200; ++k)
                if (is(c, heat_color(k / 200.0)) || glm::length(c - 255.0 * heat_color(k / 200.0)) < 3.0) {
                    ++ramp_px;
                    break;
                }
            EXPECT_FALSE(is(a.at(x, y), kPicked) || is(a.at(x, y), kNoContribution)) << "plain run at " << x << "," << y;
        }
    EXPECT_GT(picked_px, 50);     // the patch (about 20 × 20 pixels, less its outline)
    EXPECT_GT(zero_px, 2000);     // the rest of the back wall, and what the blocks hide
    EXPECT_GT(ramp_px, 2000);     // ceiling, side walls and floor that the patch sees
}

// examples/lidded_box.vs3 against open_box.vs3 (the same five S surfaces without the O lid):
// nothing emits, so every radiating patch is black (B = 0) and the pictures differ only by the
// lid, which the default view (from the open side, above) looks through. The lid is glass:
// kObstruction blended with kObstructionAlpha over the black floor, never a radiosity colour;
// with the wireframe (on here) its patches' outlines are kObstruction itself.
TEST(ViewCli, ObstructionOnlySurfacesAreDrawnAsGlassWithoutRadiosity) {
    REQUIRE_XVFB();
    TempDir dir;
    const RunResult open = view(test::example("open_box.vs3") + " --frames 3 --screenshot " + dir / "open.png");
    const RunResult lidded = view(test::example("lidded_box.vs3") + " --frames 3 --wireframe --screenshot " + dir / "lidded.png");
    ASSERT_EQ(open.code, 0) << open.output;
    ASSERT_EQ(lidded.code, 0) << lidded.output;
    const Image a = load_png(dir / "open.png"), b = load_png(dir / "lidded.png");
    ASSERT_EQ(a.width, 320);
    ASSERT_EQ(b.width, 320);
    // 8-bit rounding of the blend and of the sRGB write: within 1.5 of 255 × colour.
    const Vec3 glass = 255.0 * double(kObstructionAlpha) * kObstruction, outline = 255.0 * kObstruction;
    auto near = [](const Vec3& pixel, const Vec3& want) { return glm::length(pixel - want) < 1.5; };
    EXPECT_TRUE(near(a.at(160, 120), Vec3(0.0))) << "the open box's floor, unlit";
    EXPECT_TRUE(near(b.at(160, 120), glass)) << "the lid over that floor (mid-cell: the 7 x 7 outlines miss it)";
    int glass_px = 0, outline_px = 0, open_glass = 0, open_outline = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            glass_px += near(b.at(x, y), glass), outline_px += near(b.at(x, y), outline);
            open_glass += near(a.at(x, y), glass), open_outline += near(a.at(x, y), outline);
        }
    EXPECT_GT(glass_px, 5000);   // the box's opening fills much of the 320 × 240 view, less the lines
    EXPECT_GT(outline_px, 300);  // the lid's patch outlines (a grid of 7 × 7 patches)
    EXPECT_EQ(open_glass, 0);
    EXPECT_EQ(open_outline, 0);
}

// `view --target-error`: the adaptive levels run before the window (as `solve --target-error`),
// then the wireframe outlines the starting patches in kPatchEdge and the elements inside split
// patches in kElementEdge. Without refinement no element edge exists, so none of its colour may be
// drawn (it is not a radiosity colour of this scene: the control for the count with refinement).
TEST(ViewCli, WireframeShowsTheElementsOfAdaptiveRefinement) {
    REQUIRE_XVFB();
    TempDir dir;
    // At most 420 elements from 300 patches: one refinement of up to 40 patches, then the budget
    // stops it (two solves of about 300 and 400 rows at 64 pixels: the run took 8.4 s on
    // llvmpipe with the machine's 2 cores at load average 18). The levels are shown one after the
    // other: --until-done waits for the refined one.
    const RunResult adaptive = view("--target-error 0.05 --max-elements 420 --wireframe --until-done --screenshot " + dir / "a.png");
    const RunResult plain = view("--wireframe --frames 3 --screenshot " + dir / "p.png");
    ASSERT_EQ(adaptive.code, 0) << adaptive.output;
    ASSERT_EQ(plain.code, 0) << plain.output;
    auto count = [](const Image& im, const Vec3& colour) {
        int n = 0;
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) n += glm::length(im.at(x, y) - 255.0 * colour) < 1.5;
        return n;
    };
    const Image a = load_png(dir / "a.png"), p = load_png(dir / "p.png");
    ASSERT_EQ(a.width, 320);
    // Each split patch's inner cross is about 2 × 20 pixels at this size; at least a few are in view.
    EXPECT_GT(count(a, kElementEdge), 100);
    EXPECT_GT(count(a, kPatchEdge), 1000);
    EXPECT_EQ(count(p, kElementEdge), 0);
    EXPECT_GT(count(p, kPatchEdge), 1000);
}

// The first number after each match of `pattern` (one capture group) in the log.
std::vector<std::size_t> numbers_after(const std::string& log, const std::string& pattern) {
    std::vector<std::size_t> out;
    const std::regex re(pattern);
    for (auto it = std::sregex_iterator(log.begin(), log.end(), re); it != std::sregex_iterator(); ++it)
        out.push_back(std::stoul((*it)[1].str()));
    return out;
}

TEST(ViewCli, UntilDoneShowsTheAdaptiveLevelsAsTheyRunAndEndsWithSolvesObjects) {
    REQUIRE_XVFB();
    TempDir dir;
    // The wireframe test's refinement: 300 patches, then one level of at most 420 elements.
    const std::string adaptive = "--target-error 0.05 --max-elements 420 --tolerance 1e-4 ";
    const RunResult v = view(adaptive + "--until-done --objects " + dir / "v.csv", false);
    ASSERT_EQ(v.code, 0) << v.output;
    // The window opens on level 0 and switches to each refined level when its solve converges.
    const std::vector<std::size_t> start = numbers_after(v.output, R"(viewer: (\d+) patches, window)");
    const std::vector<std::size_t> levels = numbers_after(v.output, R"(viewer: level \d+: (\d+) elements)");
    ASSERT_EQ(start.size(), 1u) << v.output;
    ASSERT_GE(levels.size(), 1u) << v.output;
    EXPECT_GT(levels.front(), start.front());
    for (std::size_t l = 1; l < levels.size(); ++l) EXPECT_GT(levels[l], levels[l - 1]);
    EXPECT_EQ(numbers_after(v.output, R"(viewer: (\d+) adaptive levels shown)"), std::vector<std::size_t>{levels.size() + 1});
    // The same options solved by `ffcube solve`: each level's solve is progressive shooting on the
    // same rows in both (the viewer's ProgressiveSolver in frame-sized steps, solve's in windows of
    // shots; shooting is deterministic however the shots are split, solver/progressive.hpp), and
    // solve's switch to GMRES does not happen here (it is for stiff scenes: ρ near 1). So the same
    // refinement and the same radiosity: the CSVs are equal byte for byte.
    const RunResult s = test::run_ffcube("solve -q --patches 300 --resolution 64 --solver shoot " + adaptive + "--objects " +
                                         dir / "s.csv");
    ASSERT_EQ(s.code, 0) << s.output;
    const std::string objects = test::read_text(dir / "v.csv");
    EXPECT_NE(objects.find("tall_block,"), std::string::npos) << objects;
    EXPECT_EQ(objects, test::read_text(dir / "s.csv"));
}

TEST(ViewCli, ExrHoldsTheLinearRadiance) {
    REQUIRE_XVFB();
    TempDir dir;
    ASSERT_EQ(view("--frames 5 --exr " + dir / "a.exr").code, 0);
    Imf::RgbaInputFile in((dir / "a.exr").c_str());
    const Imath::Box2i dw = in.dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    ASSERT_EQ(w, 320);
    ASSERT_EQ(h, 240);
    std::vector<Imf::Rgba> px(static_cast<std::size_t>(w) * h);
    in.setFrameBuffer(px.data(), 1, static_cast<std::size_t>(w));
    in.readPixels(dw.min.y, dw.max.y);
    // Not tone mapped: radiance L = B/π, so the light shows at least its emitted radiosity over π
    // (Ke 53.407 in red; more where it also reflects); the RgbaInputFile reads the float channels
    // as half, which rounds 17.0 by at most 2^-11 relative (0.0083). The corners show no surface: 0.
    float max_red = 0.0f;
    for (const Imf::Rgba& p : px) max_red = std::max(max_red, static_cast<float>(p.r));
    EXPECT_GE(max_red, 53.407f / 3.14159265f - 0.0083f);
    EXPECT_EQ(static_cast<float>(px.front().r), 0.0f);
    EXPECT_EQ(static_cast<float>(px.back().g), 0.0f);
}

TEST(ViewCli, BadOptionsAreRefusedBeforeAnyWindow) {
    // No display needed: validation comes first, exit code 2 (bad input).
    for (const char* args : {"--screenshot x.png", "--frames 2 --pick 5", "--size 320x240 --frames 2 --pick 999,5", "--size 10x10",
                             "--budget-ms 0", "--frames 2 --screenshot /nonexistent-dir/x.png", "--target-error 0",
                             "--max-elements 10",  // fewer than the ~500 patches of the adaptive start
                             "--frames 2 --until-done", "--until-done --paused", "--frames 2 --objects /nonexistent-dir/o.csv"}) {
        const RunResult r = test::run_ffcube(std::string("view -q ") + args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find("error"), std::string::npos) << args;
    }
}

}  // namespace
}  // namespace ffcube
