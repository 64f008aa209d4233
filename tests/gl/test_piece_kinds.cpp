// The item shader's patch lookup for every kind of mesher piece: triangles (kind 3) and
// parallelogram quads (GPU kind 5) take the floor of their interpolated cell coordinates, other
// quads (kind 4) solve the inverse bilinear map; each kind present is drawn by its own program,
// compiled with only its own lookup (ONLY_KIND). T-vertices (a corner of one piece inside another's edge)
// add vertex slots whose parameters must follow the same rule.
//
// Two independent references:
//  * Pixels: every atlas pixel's centre ray, cast on the CPU in double against the scene's
//    patch polygons (nearest hit), names the patch that pixel must show. Only pixels whose
//    centre lies within kAmbiguous of a pixel from an outline (patch, piece or silhouette) are
//    skipped: there the rasterizer's subpixel snapping may legitimately pick the neighbour.
//  * Values: each row entry F_ij against Lambert's point-to-polygon formula from the hemicube's
//    eye (the sender's centroid raised by kEyeOffset × its size), no occlusion (none in these
//    scenes). Tolerance: 6σ of the pixel discretisation of patch j (see patch_tolerance).
// A pixel assigned to a neighbouring cell fails the pixel check outright, and moves a cell's
// weight to its neighbour, which the value check sees (checked: each piece has neighbouring
// cells whose exact values differ by more than both tolerances).
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ffcube/formfactor/checks.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::NamedPolygon;

constexpr std::uint32_t kBack = 0xFFFFFFFFu;
constexpr std::uint32_t kUnknown = 0xFFFFFFFEu;  // the CPU ray fell between patches (rounding)

// Pixel centres within this fraction of a pixel of an outline are skipped. llvmpipe snaps
// vertices to 1/256 of a pixel (8 subpixel bits), which moves an edge, and the cell boundaries
// interpolated from the snapped vertices, by at most ~1/256 pixel; float vertex coordinates
// (2^-24 relative, ~1e-5 pixel at N = 256) and float interpolation add far less. 1/32 pixel
// is 8× that; it skips ~2/32 of the pixels along outlines and none elsewhere.
constexpr double kAmbiguous = 1.0 / 32.0;

// Receivers put on a plane through `centre` whose normal points from centre to `aim`, from 2D
// outline points (CCW), with a and b the in-plane axes (a × b = normal, so CCW stays CCW seen
// from the front).
NamedPolygon place(const std::string& name, const std::vector<std::array<double, 2>>& pts, Vec3 centre, Vec3 aim) {
    const Vec3 n = glm::normalize(aim - centre);
    const Vec3 a = glm::normalize(glm::cross(Vec3(0.3, 0.2, 1.0), n));
    const Vec3 b = glm::cross(n, a);
    double cx = 0, cy = 0;
    for (const auto& p : pts) {
        cx += p[0] / static_cast<double>(pts.size());
        cy += p[1] / static_cast<double>(pts.size());
    }
    NamedPolygon poly{name, {}};
    for (const auto& p : pts) poly.vertices.push_back(centre + (p[0] - cx) * a + (p[1] - cy) * b);
    return poly;
}

enum class Kind { Parallelogram, Rectangle, General, Triangle };

// One receiver of each kind, each placed in its own part of the sender's hemisphere (their
// directions are ~70° apart, each subtends less than ~45°: no receiver hides another), tilted
// away from facing the sender so that perspective matters. Meshed with L = 0.32: 3 × 4 cells,
// 3 × 4, 4 × 4 and k = 4 (16 triangles).
NamedPolygon receiver(Kind k) {
    const Vec3 aim(0.25, -0.2, -0.3);
    switch (k) {
    case Kind::Parallelogram:  // sheared: edges 0.9 and |(0.3, 1.2)| = 1.24
        return place("parallelogram", {{0, 0}, {0.9, 0}, {1.2, 1.2}, {0.3, 1.2}}, Vec3(1.0, 1.0, 1.0), aim);
    case Kind::Rectangle:
        return place("rectangle", {{0, 0}, {0.9, 0}, {0.9, 1.2}, {0, 1.2}}, Vec3(-1.0, 1.0, 1.0), aim);
    case Kind::General:  // convex, no two sides parallel
        return place("general", {{0, 0}, {1.0, -0.15}, {1.15, 1.05}, {-0.1, 0.8}}, Vec3(-1.0, -1.0, 1.0), aim);
    case Kind::Triangle:
        return place("triangle", {{0, 0}, {1.15, 0}, {0.4, 1.05}}, Vec3(0.9, -0.8, 0.7), aim);
    }
    return {};
}

// GPU kind of a mesher piece as prepare_pieces decides it (independently restated).
std::uint32_t gpu_kind(const PatchGrid& g) {
    if (g.count == 3) return 3;
    const Vec3 d = g.corners[2] - g.corners[1] - g.corners[3] + g.corners[0];
    const double size = std::max(glm::length(g.corners[1] - g.corners[0]), glm::length(g.corners[3] - g.corners[0]));
    return glm::length(d) <= 1e-9 * size ? 5 : 4;
}

// CPU ray caster over the scene's patches, pieces first.
class Caster {
public:
    explicit Caster(const Scene& s) : s_(s) {
        for (const PatchGrid& g : s.grids) {
            Piece p;
            p.n = polygon_normal(std::span<const Vec3>(g.corners.data(), g.count));
            p.count = g.count;
            p.corners = g.corners;
            p.first = g.first_patch;
            p.cells = g.count == 4 ? g.nu * g.nv : g.nu * g.nu;
            pieces_.push_back(p);
        }
    }

    // What the ray eye + t·dir (t > 0) hits first: 1 + patch (front), kBack, 0, or kUnknown.
    std::uint32_t cast(const Vec3& eye, const Vec3& dir) const {
        double best = INFINITY;
        const Piece* hit = nullptr;
        for (const Piece& p : pieces_) {
            const double den = glm::dot(p.n, dir);
            if (den == 0) continue;
            const double t = glm::dot(p.n, p.corners[0] - eye) / den;
            if (!(t > 0) || t >= best) continue;
            if (!inside(std::span<const Vec3>(p.corners.data(), p.count), p.n, eye + t * dir)) continue;
            best = t;
            hit = &p;
        }
        if (!hit) return 0;
        const Vec3 x = eye + best * dir;
        for (std::uint32_t c = 0; c < hit->cells; ++c) {
            const std::uint32_t j = hit->first + c;
            const auto v = s_.patch_vertices(j);
            if (inside(std::span<const Vec3>(v.data(), s_.patches[j].count), hit->n, x))
                return glm::dot(hit->n, dir) < 0 ? j + 1 : kBack;
        }
        return kUnknown;
    }

private:
    struct Piece {
        Vec3 n;
        std::array<Vec3, 4> corners;
        std::uint32_t count, first, cells;
    };
    // Convex polygon, CCW about n; points on an edge (to 1e-12 of its size) count as inside.
    static bool inside(std::span<const Vec3> poly, const Vec3& n, const Vec3& x) {
        for (std::size_t k = 0; k < poly.size(); ++k) {
            const Vec3 e = poly[(k + 1) % poly.size()] - poly[k];
            if (glm::dot(glm::cross(e, x - poly[k]), n) < -1e-12 * glm::dot(e, e)) return false;
        }
        return true;
    }
    const Scene& s_;
    std::vector<Piece> pieces_;
};

struct PixelCheck {
    std::size_t checked = 0;     // pixels compared
    std::size_t ambiguous = 0;   // skipped: within kAmbiguous of an outline
    std::size_t wrong = 0;       // showed another patch than the CPU ray
    std::string first_wrong;     // a description of the first
};

// Compares patch i's item buffer with the CPU rays through each pixel centre; a pixel is
// ambiguous when the rays through its centre ± kAmbiguous pixel (in x and in y) disagree.
PixelCheck check_pixels(const Scene& s, const HemicubeOptions& o, std::uint32_t i, const std::vector<std::uint32_t>& ids) {
    const HemicubeLayout layout(o.resolution);
    const Patch& pa = s.patches[i];
    const HemicubeFrame fr = make_frame(pa.normal, o.rotate ? hemicube_angle(o.seed, i) : 0.0);
    const Vec3 eye = pa.centroid + pa.normal * (HemicubeRowProvider::kEyeOffset * pa.size);
    const Caster caster(s);
    const int W = layout.atlas_width();
    PixelCheck r;
    for (const FaceSpec& f : layout.faces()) {
        const auto& vp = f.viewport;
        const double pw = (f.frustum.right - f.frustum.left) / vp.width;
        const double ph = (f.frustum.top - f.frustum.bottom) / vp.height;
        for (int y = vp.y; y < vp.y + vp.height; ++y)
            for (int x = vp.x; x < vp.x + vp.width; ++x) {
                const double u = f.frustum.left + pw * (x - vp.x + 0.5), v = f.frustum.bottom + ph * (y - vp.y + 0.5);
                const auto ray = [&](double du, double dv) {
                    return caster.cast(eye, fr.to_world(HemicubeLayout::face_direction(f, u + du * pw, v + dv * ph)));
                };
                const std::uint32_t want = ray(0, 0);
                const bool amb = want == kUnknown || ray(kAmbiguous, 0) != want || ray(-kAmbiguous, 0) != want ||
                                 ray(0, kAmbiguous) != want || ray(0, -kAmbiguous) != want;
                if (amb) {
                    ++r.ambiguous;
                    continue;
                }
                ++r.checked;
                const std::uint32_t got = ids[static_cast<std::size_t>(y) * W + x];
                if (got != want) {
                    if (r.wrong == 0)
                        r.first_wrong = "pixel (" + std::to_string(x) + "," + std::to_string(y) + ") shows id " + std::to_string(got) +
                                        ", the ray hits id " + std::to_string(want);
                    ++r.wrong;
                }
            }
    }
    return r;
}

// Pixel discretisation tolerance of each entry F_ij of row i, from its item buffer. A pixel cut
// by patch j's outline counts wholly or not at all, an error within ±ΔF (±ΔF/2 for a straight
// outline: the half-plane holding the pixel centre covers at least half the pixel). Cut pixels
// are counted as both pixels of every 4-neighbour pair (within one face) showing j and another
// id: about twice the cut pixels, so conservative. Errors are not independent pixel by pixel: a
// straight outline crosses a run of pixel rows (or columns) at slowly drifting offsets, and an
// outline nearly parallel to the pixel grid crosses all of them at one offset (edges parallel to
// the sender's normal are vertical in the side faces whatever the rotation; and at 5° from a
// multiple of 90°, the closest the seeded rotation comes, an edge drifts one pixel in 11). So the
// pairs are grouped into runs: consecutive rows (columns) where j's boundary sits between the
// same two columns (rows). Each run is one error uniform in ±(its ΔF sum)/2 on each side of the
// boundary (variance (ΣΔF)²/12 for the pixels of j, the same for those beside them), runs
// independent (the model of support/pixel_sigma.hpp with runs in place of pixels; a run of
// one pair is exactly that model). Tolerance 6σ.
std::vector<double> patch_tolerance(const Scene& s, int resolution, const std::vector<std::uint32_t>& ids) {
    const HemicubeLayout layout(resolution);
    const auto& dff = layout.delta_ff();
    const int W = layout.atlas_width();
    std::vector<double> var(s.size(), 0.0);
    struct Run {
        int last = -2;  // row (column) of the last pair in the run
        double in = 0, out = 0;
    };
    // Key: id, face, orientation (0: boundary between columns x, x + 1; 1: between rows), which
    // side j is on, and the column (row) of the pair.
    std::map<std::array<std::int64_t, 5>, Run> runs;
    const auto flush = [&](std::uint32_t id, Run& r) {
        var[id - 1] += (r.in * r.in + r.out * r.out) / 12.0;
        r = Run{};
    };
    const auto add = [&](std::array<std::int64_t, 5> key, int along, double in, double out) {
        Run& r = runs[key];
        if (r.last != along - 1 && r.last != -2) flush(static_cast<std::uint32_t>(key[0]), r);
        r.last = along;
        r.in += in;
        r.out += out;
    };
    // A patch id (an id past the last patch, which a broken lookup could write, is left to the
    // pixel check that reports it).
    const auto patch = [&](std::uint32_t id) { return id != 0 && id != kBack && id <= s.size(); };
    for (const FaceSpec& f : layout.faces()) {
        const auto& vp = f.viewport;
        const auto face = static_cast<std::int64_t>(f.face);
        for (int y = vp.y; y < vp.y + vp.height; ++y)
            for (int x = vp.x; x < vp.x + vp.width; ++x) {
                const std::size_t k = static_cast<std::size_t>(y) * W + x;
                if (x + 1 < vp.x + vp.width && ids[k] != ids[k + 1]) {  // boundary between columns x, x + 1: runs along y
                    if (patch(ids[k])) add({ids[k], face, 0, 0, x}, y, dff[k], dff[k + 1]);
                    if (patch(ids[k + 1])) add({ids[k + 1], face, 0, 1, x}, y, dff[k + 1], dff[k]);
                }
                if (y + 1 < vp.y + vp.height && ids[k] != ids[k + W]) {  // between rows y, y + 1: runs along x
                    if (patch(ids[k])) add({ids[k], face, 1, 0, y}, x, dff[k], dff[k + W]);
                    if (patch(ids[k + W])) add({ids[k + W], face, 1, 1, y}, x, dff[k + W], dff[k]);
                }
            }
    }
    for (auto& [key, r] : runs)
        if (r.last != -2) flush(static_cast<std::uint32_t>(key[0]), r);
    // Plus 1e-12 for the double sums of ΔF and of the contour formula.
    std::vector<double> tol(s.size());
    for (std::size_t j = 0; j < s.size(); ++j) tol[j] = 6.0 * std::sqrt(var[j]) + 1e-12;
    return tol;
}

std::uint32_t object_of(const Scene& s, const std::string& name) {
    for (std::uint32_t k = 0; k < s.objects.size(); ++k)
        if (s.objects[k] == name) return k;
    ADD_FAILURE() << "no object " << name;
    return 0;
}

struct RowCheck {
    double worst_ratio = 0;   // max |F − exact| / tolerance over the row
    double worst_abs = 0;     // the |F − exact| there
    double row_sum = 0;
    std::vector<double> exact, tol;
};

// Row i from the provider (in double, as accumulated) against the analytic values, entry by entry.
RowCheck check_row(const Scene& s, HemicubeRowProvider& provider, const HemicubeOptions& o, std::uint32_t i,
                   const std::string& label) {
    const std::vector<std::uint32_t> ids = provider.item_buffer(i);
    const PixelCheck px = check_pixels(s, o, i, ids);
    EXPECT_EQ(px.wrong, 0u) << label << " sender " << i << ": " << px.first_wrong;
    // Outlines are a small part of the atlas: most pixels are checked, few skipped.
    EXPECT_GT(px.checked, static_cast<std::size_t>(2.5 * o.resolution * o.resolution)) << label;
    EXPECT_LT(px.ambiguous, static_cast<std::size_t>(0.1 * o.resolution * o.resolution)) << label;

    SparseRow row;
    provider.compute_row(i, row);
    std::vector<double> F(s.size(), 0.0);
    for (std::size_t k = 0; k < row.nnz(); ++k) F[row.col[k]] = row.val[k];
    const std::vector<double> tolerance = patch_tolerance(s, o.resolution, ids);
    const Patch& pa = s.patches[i];
    const Vec3 eye = pa.centroid + pa.normal * (HemicubeRowProvider::kEyeOffset * pa.size);
    RowCheck rc;
    rc.exact.assign(s.size(), 0.0);
    rc.tol.assign(s.size(), 0.0);
    for (std::uint32_t j = 0; j < s.size(); ++j) {
        if (j == i) continue;
        const auto v = s.patch_vertices(j);
        const double exact = ff_point_polygon(eye, pa.normal, std::span<const Vec3>(v.data(), s.patches[j].count));
        const double tol = tolerance[j];  // see patch_tolerance
        rc.exact[j] = exact;
        rc.tol[j] = tol;
        rc.row_sum += F[j];
        EXPECT_NEAR(F[j], exact, tol) << label << " F(" << i << "," << j << ") object " << s.objects[s.patches[j].object];
        const double err = std::abs(F[j] - exact);
        if (err / tol > rc.worst_ratio) {
            rc.worst_ratio = err / tol;
            rc.worst_abs = err;
        }
    }
    return rc;
}

// For each receiver piece: some pair of cells one step apart along u (quads: (i, j) and
// (i + 1, j); triangles: the upright cells (i, j) and (i + 1, j)) has exact values further apart
// than both tolerances, so a lookup off by one cell along u (cell j's pixels shown as the next
// one's) would fail check_row there.
void expect_shift_detectable(const Scene& s, const RowCheck& rc, std::uint32_t object) {
    for (const PatchGrid& g : s.grids) {
        if (s.patches[g.first_patch].object != object) continue;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
        if (g.count == 4) {
            for (std::uint32_t j = 0; j < g.nv; ++j)
                for (std::uint32_t i = 0; i + 1 < g.nu; ++i) pairs.emplace_back(j * g.nu + i, j * g.nu + i + 1);
        } else {
            const std::uint32_t k = g.nu;
            for (std::uint32_t j = 0; j < k; ++j)
                for (std::uint32_t i = 0; i + 1 < k - j; ++i) pairs.emplace_back(j * (2 * k - j) + 2 * i, j * (2 * k - j) + 2 * i + 2);
        }
        int detectable = 0;
        for (const auto& [a, b] : pairs) {
            const std::uint32_t ja = g.first_patch + a, jb = g.first_patch + b;
            if (std::abs(rc.exact[ja] - rc.exact[jb]) > rc.tol[ja] + rc.tol[jb]) ++detectable;
        }
        EXPECT_GT(detectable, 0) << "piece of " << s.objects[object] << ": a one-cell shift would go unseen";
        std::printf("  %s: %d of %zu neighbour pairs differ by more than their tolerances\n", s.objects[object].c_str(), detectable,
                    pairs.size());
    }
}

const Vec3 kSender[4] = {{-0.01, -0.01, 0}, {0.01, -0.01, 0}, {0.01, 0.01, 0}, {-0.01, 0.01, 0}};

// One thread (the row in this process), N = 256, the rotation of this seed.
HemicubeOptions row_options(std::uint64_t seed) {
    HemicubeOptions o;
    o.resolution = 256;
    o.threads = 1;
    o.seed = seed;
    return o;
}

void run_receivers(const std::vector<Kind>& kinds, const std::string& label) {
    std::vector<NamedPolygon> polys{{"sender", {kSender[0], kSender[1], kSender[2], kSender[3]}}};
    for (const Kind k : kinds) polys.push_back(receiver(k));
    const Scene s = test::make_scene(polys, 0.32);
    // The scene holds exactly the piece kinds asked for (so the shader is specialised as meant).
    std::array<bool, 6> want{}, have{};
    for (const Kind k : kinds) want[k == Kind::Triangle ? 3 : k == Kind::General ? 4 : 5] = true;
    for (const PatchGrid& g : s.grids)
        if (s.patches[g.first_patch].object != 0) {
            have[gpu_kind(g)] = true;
            EXPECT_GE(g.count == 4 ? g.nu * g.nv : g.nu * g.nu, 12u) << label << ": receivers of several cells";
        }
    ASSERT_EQ(have, want) << label;
    ASSERT_FALSE(prepare_pieces(s.grids).single_cell) << label << ": the shader's cell lookup is what is tested";
    const std::uint32_t sender = 0;
    ASSERT_EQ(s.patches[sender].object, object_of(s, "sender"));
    ASSERT_EQ(s.grids[0].nu * s.grids[0].nv, 1u);

    for (const std::uint64_t seed : {0x5eedull, 0x1234567ull}) {
        const HemicubeOptions o = row_options(seed);
        HemicubeRowProvider provider(s, o);
        const RowCheck rc = check_row(s, provider, o, sender, label);
        for (const Kind k : kinds) expect_shift_detectable(s, rc, object_of(s, receiver(k).object));
        std::printf("[ %s seed %llx ] worst |F - exact| = %.3g = %.3f of its tolerance; row sum %.6f\n", label.c_str(),
                    static_cast<unsigned long long>(seed), rc.worst_abs, rc.worst_ratio, rc.row_sum);
    }
}

// Affine pieces only: the shader is compiled with HAS_BILINEAR 0 (and HAS_TRIANGLES 0 when
// there is no triangle).
TEST(PieceKinds, ParallelogramsOnlyMapPixelsToTheirCells) {
    run_receivers({Kind::Parallelogram, Kind::Rectangle}, "parallelograms");
}

TEST(PieceKinds, AffinePiecesOnlyMapPixelsToTheirCells) {
    run_receivers({Kind::Parallelogram, Kind::Rectangle, Kind::Triangle}, "affine");
}

TEST(PieceKinds, GeneralQuadWithoutTrianglesMapsPixelsToItsCells) {
    run_receivers({Kind::General, Kind::Parallelogram}, "bilinear+parallelogram");
}

// Every piece one patch (a mesh read with --no-subdivide): the front pass's shaders are compiled
// with SINGLE_CELL 1 (shaders/item.vert), which passes the patch per vertex and interpolates
// nothing; every pixel must still name the patch the CPU ray hits, and every entry match Lambert.
TEST(PieceKinds, OnePatchPerPieceMapsPixelsToTheirPatches) {
    std::vector<NamedPolygon> polys{{"sender", {kSender[0], kSender[1], kSender[2], kSender[3]}}};
    for (const Kind k : {Kind::Parallelogram, Kind::Rectangle, Kind::General, Kind::Triangle}) polys.push_back(receiver(k));
    const Scene s = test::make_scene(polys, 10.0);  // a maximum edge above every receiver's size
    ASSERT_EQ(s.size(), polys.size());
    ASSERT_TRUE(prepare_pieces(s.grids).single_cell);
    for (const std::uint64_t seed : {0x5eedull, 0x1234567ull}) {
        const HemicubeOptions o = row_options(seed);
        HemicubeRowProvider provider(s, o);
        const RowCheck rc = check_row(s, provider, o, 0, "one patch per piece");
        std::printf("[ one patch per piece, seed %llx ] worst |F - exact| = %.3g = %.3f of its tolerance; row sum %.6f\n",
                    static_cast<unsigned long long>(seed), rc.worst_abs, rc.worst_ratio, rc.row_sum);
    }
}

TEST(PieceKinds, AllKindsTogetherMapPixelsToTheirCells) {
    run_receivers({Kind::Parallelogram, Kind::Rectangle, Kind::General, Kind::Triangle}, "all kinds");
}

// A closed convex prism over the trapezoid (0,0) (2,0) (2.2,1) (0,1), height 1, every face
// meeting others in T-junctions:
//   floor: trapezoid (0,0) (1,0) (1.2,1) (0,1) (kind 4) beside two parallelograms (kind 5)
//     (1,0) (2,0) (2.1,.5) (1.1,.5) and (1.1,.5) (2.1,.5) (2.2,1) (1.2,1), whose shared corner
//     (1.1,.5) lies inside the trapezoid's edge, and (2.1,.5) inside the right wall's bottom edge;
//   ceiling: the same trapezoid (kind 4), a triangle (1,0) (2,0) (2.2,1) and two triangles
//     split at (1.6,.5), the middle of the first one's long edge (a T-vertex of a triangle);
//   walls: rectangles (kind 5), with the floor's and ceiling's corners (1,0) and (1.2,1) inside
//     the front and back walls' edges.
std::vector<NamedPolygon> prism() {
    const auto f = [](double x, double y) { return Vec3(x, y, 0); };
    const auto c = [](double x, double y) { return Vec3(x, y, 1); };
    return {
        {"floor_trap", {f(0, 0), f(1, 0), f(1.2, 1), f(0, 1)}},
        {"floor_par_a", {f(1, 0), f(2, 0), f(2.1, 0.5), f(1.1, 0.5)}},
        {"floor_par_b", {f(1.1, 0.5), f(2.1, 0.5), f(2.2, 1), f(1.2, 1)}},
        // ceiling faces down: clockwise seen from above
        {"ceil_trap", {c(0, 0), c(0, 1), c(1.2, 1), c(1, 0)}},
        {"ceil_tri", {c(1, 0), c(2.2, 1), c(2, 0)}},
        {"ceil_tri_a", {c(1, 0), c(1.2, 1), c(1.6, 0.5)}},
        {"ceil_tri_b", {c(1.6, 0.5), c(1.2, 1), c(2.2, 1)}},
        {"front", {f(0, 0), c(0, 0), c(2, 0), f(2, 0)}},        // y = 0, normal +y
        {"right", {f(2, 0), c(2, 0), c(2.2, 1), f(2.2, 1)}},    // normal towards −x
        {"back", {f(2.2, 1), c(2.2, 1), c(0, 1), f(0, 1)}},     // y = 1, normal −y
        {"left", {f(0, 1), c(0, 1), c(0, 0), f(0, 0)}},         // x = 0, normal +x
    };
}

TEST(PieceKinds, TJunctionsBetweenKindsLeaveNoCracksAndMapPixelsToTheirCells) {
    const auto polys = prism();
    const Scene s = test::make_scene(polys, 0.3);
    std::array<int, 6> kinds{};
    for (const PatchGrid& g : s.grids) ++kinds[gpu_kind(g)];
    ASSERT_EQ(kinds[3], 3);
    ASSERT_EQ(kinds[4], 2);
    ASSERT_EQ(kinds[5], 6);
    // The closed-form check of the arrangement: every patch's exact row closes (Σ_j F = 1).
    {
        const Patch& p = s.patches[0];
        double sum = 0;
        for (std::uint32_t j = 1; j < s.size(); ++j) {
            const auto v = s.patch_vertices(j);
            sum += ff_point_polygon(p.centroid + p.normal * 1e-9, p.normal, std::span<const Vec3>(v.data(), s.patches[j].count));
        }
        ASSERT_NEAR(sum, 1.0, 1e-9);
    }

    // No cracks: at N = 128 every pixel of every hemicube shows a front face. One pixel missed
    // or showing a back face costs at least min ΔF ≈ 1/(π N²)·(1/3)² = 2e-6 of its row, while the
    // rows, stored as float (2^-24 relative per entry), sum to 1 within 6e-8 (1e-7 asserted).
    {
        HemicubeOptions o;
        o.resolution = 128;
        o.threads = 2;
        HemicubeRowProvider provider(s, o);
        const CsrMatrix F = compute_all_rows(provider);
        const RowSumStats rs = row_sum_stats(F);
        std::printf("[ prism, %zu patches, N=128 ] row sums in [1%+.2g, 1%+.2g]; miss %.3g back %.3g\n", s.size(), rs.min - 1,
                    rs.max - 1, provider.stats().miss_weight(), provider.stats().back_face_weight());
        EXPECT_NEAR(rs.min, 1.0, 1e-7);
        EXPECT_NEAR(rs.max, 1.0, 1e-7);
        EXPECT_EQ(provider.stats().miss_weight(), 0.0);
        EXPECT_EQ(provider.stats().back_face_weight(), 0.0);
        EXPECT_EQ(provider.stats().self_hits, 0u);
    }

    // Senders that see the T-junctions: per object, its patch nearest the prism's middle.
    HemicubeOptions o;
    o.resolution = 256;
    o.threads = 1;
    HemicubeRowProvider provider(s, o);
    const Vec3 middle(1.1, 0.5, 0.5);
    for (std::uint32_t obj = 0; obj < s.objects.size(); ++obj) {
        std::uint32_t best = 0;
        double best_d = INFINITY;
        for (std::uint32_t i = 0; i < s.size(); ++i)
            if (s.patches[i].object == obj && glm::length(s.patches[i].centroid - middle) < best_d) {
                best_d = glm::length(s.patches[i].centroid - middle);
                best = i;
            }
        const RowCheck rc = check_row(s, provider, o, best, "prism");
        // All 3N² pixels land on some patch: the sum of all ΔF, 1 up to the table's 1e-13.
        EXPECT_NEAR(rc.row_sum, 1.0, 1e-9) << "sender " << best << " on " << s.objects[obj];
        std::printf("[ prism sender %u on %s ] worst |F - exact| = %.3g = %.3f of its tolerance; row sum 1%+.2g\n", best,
                    s.objects[obj].c_str(), rc.worst_abs, rc.worst_ratio, rc.row_sum - 1);
    }
}

}  // namespace
}  // namespace ffcube
