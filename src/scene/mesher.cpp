// Meshing in two steps. decompose() turns every face into pieces — convex planar quads and
// triangles — once; a piece knows how many patches it becomes for any edge bound L, so counting
// (and the search for the L that gives a target count) never builds a patch. emit_quad() and
// emit_triangle() then split each piece into a grid that shares its vertices within the piece,
// and record the piece as a Scene::grids entry (renderers draw pieces whole).
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/refine.hpp"

#include <unistd.h>

#include "ffcube/geometry/tolerance.hpp"

#include <fmt/format.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "ffcube/core/error.hpp"
#include "ear_clip.hpp"

namespace ffcube {
namespace detail {

// Ear clipping in the plane of unit_normal. Ears are convex corners with no other vertex inside;
// when rounding leaves none (a self-touching or non-simple polygon), the most convex corner is
// cut so that the loop always ends. Triangles keep the polygon's orientation.
void ear_clip(std::span<const Vec3> poly, const Vec3& unit_normal, std::vector<std::array<Vec3, 3>>& out) {
    const Vec3 axis = std::abs(unit_normal.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const Vec3 u = glm::normalize(glm::cross(unit_normal, axis));
    const Vec3 w = glm::cross(unit_normal, u);  // u × w = normal: counter-clockwise stays positive
    std::vector<glm::dvec2> q(poly.size());
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3 d = poly[i] - poly[0];
        q[i] = {glm::dot(d, u), glm::dot(d, w)};
    }
    const auto cross2 = [](glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; };
    const auto inside = [&](glm::dvec2 p, glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
        return cross2(b - a, p - a) >= 0.0 && cross2(c - b, p - b) >= 0.0 && cross2(a - c, p - c) >= 0.0;
    };
    std::vector<std::size_t> ring(poly.size());
    for (std::size_t i = 0; i < ring.size(); ++i) ring[i] = i;
    while (ring.size() > 3) {
        const std::size_t m = ring.size();
        std::size_t ear = m, best = 0;
        double best_turn = -std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < m && ear == m; ++k) {
            const std::size_t a = ring[(k + m - 1) % m], b = ring[k], c = ring[(k + 1) % m];
            const double t = cross2(q[b] - q[a], q[c] - q[b]);
            if (t > best_turn) best_turn = t, best = k;
            if (!(t > 0.0)) continue;
            bool empty = true;
            for (std::size_t r = 0; r < m && empty; ++r) {
                const std::size_t x = ring[r];
                if (x == a || x == b || x == c || q[x] == q[a] || q[x] == q[b] || q[x] == q[c]) continue;
                empty = !inside(q[x], q[a], q[b], q[c]);
            }
            if (empty) ear = k;
        }
        if (ear == m) ear = best;
        out.push_back({poly[ring[(ear + m - 1) % m]], poly[ring[ear]], poly[ring[(ear + 1) % m]]});
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(ear));
    }
    out.push_back({poly[ring[0]], poly[ring[1]], poly[ring[2]]});
}

}  // namespace detail

namespace {

using detail::ear_clip;


// A face is degenerate when its area is at most kDegenerate × (longest edge)². The Newell sum of
// a face of size s carries rounding errors of a few 2.2e-16 × s², so 1e-12 × s² lies thousands of
// rounding errors above zero: a face below it has no area that doubles can resolve (its aspect
// ratio would exceed 1e12). The same bound decides collinear vertices in convexity tests.
constexpr double kDegenerate = 1e-12;
// A face is non-planar when a vertex lies more than kPlanar × (longest edge) off its Newell plane.
constexpr double kPlanar = kPlanarityTolerance;  // geometry/tolerance.hpp
// Divisions per edge are ceil(e/L × (1 − kEdgeSlack)): an edge that is L times an integer up to
// rounding is not split once more. Lengths carry relative errors of a few 1e-16 × (coordinate
// magnitude / edge): a unit edge at 1e5 from the origin is off by ~1e-11, hence 1e-9. Patch
// edges are then at most L × (1 + 1e-9).
constexpr double kEdgeSlack = 1e-9;
// Warnings naming single faces stop after this many; a summary line counts the rest.
constexpr std::size_t kMaxFaceWarnings = 10;

// A convex planar quad (count 4, split into a bilinear grid) or a triangle (count 3, split into
// k² similar triangles).
struct Piece {
    std::array<Vec3, 4> p;
    std::uint32_t count;
    std::uint32_t face;  // index into ObjModel::faces
    double eu;           // quad: longer of edges p0p1, p3p2; triangle: its longest edge
    double ev;           // quad: longer of edges p0p3, p1p2; triangle: unused
};

struct Decomposition {
    std::vector<Piece> pieces;
    std::size_t degenerate = 0;
    std::size_t triangulated = 0;
    std::size_t non_planar = 0;
    std::vector<std::string> warnings;
    double longest = 0.0;  // longest piece edge measure: L at or above it gives one patch per piece
};

double divisions(double edge, double max_edge) {
    return std::max(1.0, std::ceil(edge / max_edge * (1.0 - kEdgeSlack)));
}

// Patches a piece becomes, in double so that absurd bounds (L = 1e-9) cannot overflow.
double piece_patches(const Piece& piece, double max_edge) {
    if (piece.count == 4) return divisions(piece.eu, max_edge) * divisions(piece.ev, max_edge);
    const double k = divisions(piece.eu, max_edge);
    return k * k;
}

double count_pieces(const std::vector<Piece>& pieces, double max_edge) {
    double n = 0.0;
    for (const Piece& piece : pieces) n += piece_patches(piece, max_edge);
    return n;
}

double turn(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& unit_normal) {
    return glm::dot(glm::cross(b - a, c - b), unit_normal);
}

// Convex: every corner turns left (or goes straight, when !strict) and the polygon winds once,
// which a fan from vertex 0 with no backward triangle confirms (a pentagram turns left everywhere).
bool is_convex(std::span<const Vec3> poly, const Vec3& unit_normal, double tolerance, bool strict) {
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const double t = turn(poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n], unit_normal);
        if (strict ? !(t > tolerance) : t < -tolerance) return false;
    }
    for (std::size_t i = 1; i + 1 < n; ++i)
        if (turn(poly[0], poly[i], poly[i + 1], unit_normal) < -tolerance) return false;
    return true;
}

void add_triangle(Decomposition& d, const Vec3& a, const Vec3& b, const Vec3& c, std::uint32_t face) {
    const double e = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    d.pieces.push_back(Piece{{a, b, c, c}, 3, face, e, e});
    d.longest = std::max(d.longest, e);
}

Decomposition decompose(const ObjModel& model) {
    Decomposition d;
    d.pieces.reserve(model.faces.size());
    std::vector<Vec3> poly;
    std::vector<std::array<Vec3, 3>> triangles;
    std::size_t non_planar_unreported = 0;
    for (std::size_t fi = 0; fi < model.faces.size(); ++fi) {
        const ObjFace& face = model.faces[fi];
        const auto face_index = static_cast<std::uint32_t>(fi);
        // Repeated consecutive vertices ("f 1 2 2 3") add nothing: drop them.
        poly.clear();
        for (const std::uint32_t v : face.v)
            if (poly.empty() || model.positions[v] != poly.back()) poly.push_back(model.positions[v]);
        while (poly.size() > 1 && poly.back() == poly.front()) poly.pop_back();

        const double size = polygon_max_edge(poly);
        const double area = polygon_area(poly);
        if (poly.size() < 3 || !(area > kDegenerate * size * size)) {
            ++d.degenerate;
            continue;
        }
        if (poly.size() == 3) {
            add_triangle(d, poly[0], poly[1], poly[2], face_index);
            continue;
        }
        const Vec3 normal = polygon_normal(poly);
        const double deviation = polygon_planarity_deviation(poly);
        const bool planar = deviation <= kPlanar * size;
        const double tolerance = kDegenerate * size * size;
        if (!planar) {
            ++d.non_planar;
            if (d.non_planar <= kMaxFaceWarnings)
                d.warnings.push_back(fmt::format("{}:{}: face is not planar (a vertex lies {:.3g} off its plane, more than "
                                                 "1e-6 of its size {:.3g}); it is triangulated",
                                                 model.source, face.line, deviation, size));
            else
                ++non_planar_unreported;
        }
        if (planar && poly.size() == 4 && is_convex(poly, normal, tolerance, true)) {
            const double eu = std::max(glm::length(poly[1] - poly[0]), glm::length(poly[2] - poly[3]));
            const double ev = std::max(glm::length(poly[3] - poly[0]), glm::length(poly[2] - poly[1]));
            d.pieces.push_back(Piece{{poly[0], poly[1], poly[2], poly[3]}, 4, face_index, eu, ev});
            d.longest = std::max({d.longest, eu, ev});
            continue;
        }
        ++d.triangulated;
        triangles.clear();
        if (planar && is_convex(poly, normal, tolerance, false)) {
            // A fan from the area centroid: for a regular n-gon (a disk) all triangles are alike,
            // where ear clipping would make slivers fanning out of one vertex.
            const Vec3 c = polygon_centroid(poly);
            for (std::size_t i = 0; i < poly.size(); ++i) triangles.push_back({c, poly[i], poly[(i + 1) % poly.size()]});
        } else {
            ear_clip(poly, normal, triangles);
        }
        for (const auto& t : triangles) {
            // Collinear vertices on an edge make zero-area ears: they cover nothing.
            if (polygon_area(t) > tolerance) add_triangle(d, t[0], t[1], t[2], face_index);
        }
    }
    if (non_planar_unreported > 0)
        d.warnings.push_back(fmt::format("{}: {} more faces are not planar and were triangulated", model.source,
                                         non_planar_unreported));
    return d;
}

// The L for which the count is closest to the target. count(L) falls as L grows (each piece's
// divisions do), so a bracket [lo, hi] with count(lo) ≥ target > count(hi) is bisected
// geometrically; the closer of its two ends wins.
double closest_max_edge(const std::vector<Piece>& pieces, double longest, double target) {
    double hi = longest;  // one patch per piece: the fewest meshing can give
    if (count_pieces(pieces, hi) >= target) return hi;
    double lo = hi;
    while (count_pieces(pieces, lo) < target) lo *= 0.5;  // each halving about quadruples the count
    while (hi / lo > 1.0 + 1e-9) {
        const double mid = std::sqrt(lo * hi);
        (count_pieces(pieces, mid) >= target ? lo : hi) = mid;
    }
    const double n_lo = count_pieces(pieces, lo), n_hi = count_pieces(pieces, hi);
    return n_lo / target <= target / n_hi ? lo : hi;
}

// Where the count leaves n between 'inside' (count n) and 'outside' (another count).
double plateau_edge(const std::vector<Piece>& pieces, double inside, double outside, double n) {
    while (std::abs(outside / inside - 1.0) > 1e-9) {
        const double mid = std::sqrt(inside * outside);
        (count_pieces(pieces, mid) == n ? inside : outside) = mid;
    }
    return inside;
}

// The L to use for a target count: the bisection ends next to a jump of count(L), where a
// printed, rounded L could fall on the other side. So take the middle of the plateau of L that
// give the same count, and round it to the fewest significant digits that stay on the plateau:
// the printed "--max-patch-edge L" then reproduces the same mesh.
double solve_max_edge(const std::vector<Piece>& pieces, double longest, double target) {
    const double chosen = closest_max_edge(pieces, longest, target);
    const double n = count_pieces(pieces, chosen);
    if (chosen == longest) return longest;  // one patch per piece: every L ≥ longest gives it
    // Halving L adds a division to the longest piece at least (L ≤ longest), so the count changes.
    const double low = plateau_edge(pieces, chosen, 0.5 * chosen, n);
    const double high = plateau_edge(pieces, chosen, std::min(2.0 * chosen, longest), n);
    const double middle = std::sqrt(low * high);
    for (int digits = 2; digits < 17; ++digits) {
        const std::string text = fmt::format("{:.{}g}", middle, digits);
        double rounded = 0.0;
        std::from_chars(text.data(), text.data() + text.size(), rounded);  // as the CLI will read it
        if (count_pieces(pieces, rounded) == n) return rounded;
    }
    return middle;
}

class Fnv1a {
public:
    template <typename T>
    void add(const T& value) {
        unsigned char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        for (const unsigned char b : bytes) hash_ = (hash_ ^ b) * 1099511628211ull;
    }
    std::uint64_t value() const { return hash_; }

private:
    std::uint64_t hash_ = 14695981039346656037ull;
};

void fill_patch(Scene& scene, Patch& patch) {
    const std::array<Vec3, 4> v = {scene.positions[patch.v[0]], scene.positions[patch.v[1]],
                                   scene.positions[patch.v[2]], scene.positions[patch.v[3]]};
    const std::span<const Vec3> poly(v.data(), patch.count);
    patch.area = polygon_area(poly);
    patch.normal = polygon_normal(poly);
    patch.centroid = polygon_centroid(poly);
    patch.size = polygon_max_edge(poly);
}

// The patches of a face's piece: its object and material, and its element (Gmsh) when it has one.
Patch patch_of(const ObjFace& face) {
    Patch like;
    like.object = face.object;
    like.material = face.material;
    return like;
}
void add_elements(Scene& scene, const ObjFace& face, std::size_t cells) {
    if (face.element != 0) scene.patch_elements.insert(scene.patch_elements.end(), cells, face.element);
}

void emit_quad(Scene& scene, const Piece& piece, const ObjFace& face, double max_edge) {
    const auto nu = static_cast<std::uint32_t>(divisions(piece.eu, max_edge));
    const auto nv = static_cast<std::uint32_t>(divisions(piece.ev, max_edge));
    // Every grid edge along u at parameter t is ((1−t)(p1−p0) + t(p2−p3))/nu, no longer than eu/nu ≤ L.
    append_quad_grid(scene, piece.p, nu, nv, patch_of(face));
    add_elements(scene, face, std::size_t(nu) * nv);
}

void emit_triangle(Scene& scene, const Piece& piece, const ObjFace& face, double max_edge) {
    const auto k = static_cast<std::uint32_t>(divisions(piece.eu, max_edge));
    append_triangle_grid(scene, piece.p, k, patch_of(face));
    add_elements(scene, face, std::size_t(k) * k);
}

std::uint64_t fingerprint_of(const Scene& scene) {
    Fnv1a h;
    h.add(static_cast<std::uint64_t>(scene.positions.size()));
    for (const Vec3& p : scene.positions) h.add(p.x), h.add(p.y), h.add(p.z);
    h.add(static_cast<std::uint64_t>(scene.patches.size()));
    for (const Patch& patch : scene.patches) {
        h.add(patch.count);
        for (std::uint32_t i = 0; i < patch.count; ++i) h.add(patch.v[i]);
        h.add(patch.object);
    }
    return h.value();
}

// The radiating part of a scene whose last `obstruction_objects` objects are obstruction-only
// (their faces come last in the model, so their patches, grids and vertices come last too), with
// the whole scene as its `drawn` (Scene::drawn).
Scene split_obstructions(Scene all, std::uint32_t obstruction_objects) {
    FFCUBE_CHECK(obstruction_objects < all.objects.size());
    const auto first_object = static_cast<std::uint32_t>(all.objects.size() - obstruction_objects);
    const auto first = static_cast<std::size_t>(
        std::find_if(all.patches.begin(), all.patches.end(), [&](const Patch& p) { return p.object >= first_object; }) -
        all.patches.begin());
    FFCUBE_CHECK_MSG(std::all_of(all.patches.begin() + static_cast<std::ptrdiff_t>(first), all.patches.end(),
                                 [&](const Patch& p) { return p.object >= first_object; }),
                     "obstruction patches must come after every radiating patch");
    if (first == 0) throw InputError(fmt::format("{}: every surface is an obstruction: the scene has nothing to radiate", all.source));
    all.obstruction_first = static_cast<std::uint32_t>(first);
    Scene r;
    r.source = all.source;
    r.objects.assign(all.objects.begin(), all.objects.begin() + first_object);
    r.materials = all.materials;
    r.stats = all.stats;
    r.stats.how += fmt::format(", {} of them obstruction-only", all.patches.size() - first);
    r.view3d = all.view3d;
    r.patches.assign(all.patches.begin(), all.patches.begin() + static_cast<std::ptrdiff_t>(first));
    for (const PatchGrid& g : all.grids)
        if (g.first_patch < first) r.grids.push_back(g);
    std::uint32_t vertices = 0;
    for (const Patch& p : r.patches)
        for (std::uint32_t k = 0; k < p.count; ++k) vertices = std::max(vertices, p.v[k] + 1);
    r.positions.assign(all.positions.begin(), all.positions.begin() + vertices);
    r.bbox_min = all.bbox_min;  // the whole scene's box: its extent sets the tolerances of both
    r.bbox_max = all.bbox_max;
    r.fingerprint = all.fingerprint;  // the obstructions change every row
    r.drawn = std::make_shared<const Scene>(std::move(all));
    return r;
}

void check_max_edge(double max_edge) {
    if (!(std::isfinite(max_edge) && max_edge > 0.0))
        throw InputError(fmt::format("--max-patch-edge {} is invalid: it must be a positive, finite length in scene units",
                                     max_edge));
}

}  // namespace

std::uint64_t scene_fingerprint(const Scene& scene) { return fingerprint_of(scene); }

void fill_patch_geometry(Scene& scene, Patch& patch) { fill_patch(scene, patch); }

void append_quad_grid(Scene& scene, const std::array<Vec3, 4>& c, std::uint32_t nu, std::uint32_t nv, const Patch& like) {
    const auto base = static_cast<std::uint32_t>(scene.positions.size());
    // Bilinear weights are exactly 0 or 1 at the corners, so corners stay bit-exact.
    for (std::uint32_t j = 0; j <= nv; ++j) {
        const double t = static_cast<double>(j) / nv;
        for (std::uint32_t i = 0; i <= nu; ++i) {
            const double s = static_cast<double>(i) / nu;
            scene.positions.push_back((1 - s) * (1 - t) * c[0] + s * (1 - t) * c[1] + s * t * c[2] + (1 - s) * t * c[3]);
        }
    }
    scene.grids.push_back(PatchGrid{c, 4, nu, nv, static_cast<std::uint32_t>(scene.patches.size())});
    const std::uint32_t row = nu + 1;
    for (std::uint32_t j = 0; j < nv; ++j)
        for (std::uint32_t i = 0; i < nu; ++i) {
            Patch patch = like;
            const std::uint32_t a = base + j * row + i;
            patch.v = {a, a + 1, a + row + 1, a + row};
            patch.count = 4;
            fill_patch(scene, patch);
            scene.patches.push_back(patch);
        }
}

void append_triangle_grid(Scene& scene, const std::array<Vec3, 4>& c, std::uint32_t k, const Patch& like) {
    const auto base = static_cast<std::uint32_t>(scene.positions.size());
    // Vertex (i, j) = c0 + i/k (c1 − c0) + j/k (c2 − c0), i + j ≤ k, stored row by row (j).
    for (std::uint32_t j = 0; j <= k; ++j) {
        for (std::uint32_t i = 0; i + j <= k; ++i) {
            const double b = static_cast<double>(i) / k, cc = static_cast<double>(j) / k;
            const double a = static_cast<double>(k - i - j) / k;
            scene.positions.push_back(a * c[0] + b * c[1] + cc * c[2]);
        }
    }
    const auto at = [&](std::uint32_t i, std::uint32_t j) { return base + j * (k + 1) - j * (j - 1) / 2 + i; };
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t cc) {
        Patch patch = like;
        patch.v = {a, b, cc, cc};
        patch.count = 3;
        fill_patch(scene, patch);
        scene.patches.push_back(patch);
    };
    scene.grids.push_back(PatchGrid{{c[0], c[1], c[2], c[2]}, 3, k, k, static_cast<std::uint32_t>(scene.patches.size())});
    // Upright triangles (i,j),(i+1,j),(i,j+1) and inverted ones (i+1,j),(i+1,j+1),(i,j+1): all
    // similar to the piece, all with its orientation. Row j holds 2(k − j) − 1 of them, so the
    // upright cell (i, j) is patch j(2k − j) + 2i of the piece, as PatchGrid documents.
    for (std::uint32_t j = 0; j < k; ++j) {
        for (std::uint32_t i = 0; i + j < k; ++i) {
            add(at(i, j), at(i + 1, j), at(i, j + 1));
            if (i + j + 1 < k) add(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
}

std::size_t count_patches(const ObjModel& model, double max_patch_edge) {
    check_max_edge(max_patch_edge);
    const double n = count_pieces(decompose(model).pieces, max_patch_edge);
    // Doubles above 2^64 do not convert: saturate.
    constexpr double kLimit = 18446744073709549568.0;  // largest double below 2^64
    return n >= kLimit ? std::numeric_limits<std::size_t>::max() : static_cast<std::size_t>(n);
}

Scene build_scene(const ObjModel& model, const MeshOptions& options) {
    if (model.faces.empty()) throw InputError(fmt::format("{}: no faces: the scene has no geometry", model.source));
    Decomposition d = decompose(model);
    if (d.pieces.empty())
        throw InputError(fmt::format("{}: no faces with non-zero area (all {} faces are degenerate)", model.source,
                                     model.faces.size()));

    double max_edge = 0.0;
    std::string how;
    if (!options.subdivide) {
        FFCUBE_CHECK_MSG(options.max_patch_edge == 0.0 && options.target_patches == 0,
                         "--no-subdivide takes no edge bound or patch target");
        // One patch per piece (L = the longest piece measure), and one piece per face.
        for (std::size_t i = 0; i < d.pieces.size(); ++i) {
            if (i + 1 < d.pieces.size() && d.pieces[i + 1].face == d.pieces[i].face) {
                const ObjFace& face = model.faces[d.pieces[i].face];
                const auto pieces = std::count_if(d.pieces.begin() + static_cast<std::ptrdiff_t>(i), d.pieces.end(),
                                                  [&](const Piece& p) { return p.face == d.pieces[i].face; });
                throw InputError(fmt::format("{}:{}: --no-subdivide: this face of {} vertices is not a triangle or a convex planar "
                                             "quad, so it cannot be one patch (it would be {} triangles); split it in the "
                                             "input, or mesh without --no-subdivide",
                                             model.source, face.line, face.v.size(), pieces));
            }
        }
        max_edge = d.longest;
        how = "--no-subdivide";
    } else if (options.max_patch_edge != 0.0) {
        check_max_edge(options.max_patch_edge);
        max_edge = options.max_patch_edge;
        how = fmt::format("--max-patch-edge {}", max_edge);
    } else {
        const std::size_t target = options.target_patches > 0 ? options.target_patches : MeshOptions::kDefaultPatches;
        max_edge = solve_max_edge(d.pieces, d.longest, static_cast<double>(target));
        how = fmt::format("{}--patches {} -> --max-patch-edge {}", options.target_patches > 0 ? "" : "default: ",
                          target, max_edge);
    }
    const double n = count_pieces(d.pieces, max_edge);
    if (n > static_cast<double>(options.max_patches)) {
        const double bytes = n * static_cast<double>(sizeof(Patch) + sizeof(Vec3));
        throw InputError(fmt::format("{}: {} would make about {:.2g} patches (needs about {:.2g} GB); the limit is {} "
                                     "patches: choose a longer edge or fewer patches",
                                     model.source, how, n, bytes / 1e9, options.max_patches));
    }

    Scene scene;
    scene.source = model.source;
    scene.objects = model.objects;
    scene.view3d = model.view3d;
    scene.materials = model.materials;
    std::size_t vertices = 0;
    for (const Piece& piece : d.pieces) {
        const auto u = static_cast<std::size_t>(divisions(piece.eu, max_edge));
        vertices += piece.count == 4 ? (u + 1) * (static_cast<std::size_t>(divisions(piece.ev, max_edge)) + 1)
                                     : (u + 1) * (u + 2) / 2;
    }
    FFCUBE_CHECK_MSG(vertices < std::numeric_limits<std::uint32_t>::max(), "vertex indices must fit 32 bits");
    scene.positions.reserve(vertices);
    scene.patches.reserve(static_cast<std::size_t>(n));
    scene.grids.reserve(d.pieces.size());
    for (const Piece& piece : d.pieces) {
        const ObjFace& face = model.faces[piece.face];
        if (piece.count == 4)
            emit_quad(scene, piece, face, max_edge);
        else
            emit_triangle(scene, piece, face, max_edge);
    }
    FFCUBE_CHECK(scene.patches.size() == static_cast<std::size_t>(n));
    FFCUBE_CHECK(scene.positions.size() == vertices);

    scene.bbox_min = scene.bbox_max = scene.positions.front();
    for (const Vec3& p : scene.positions) {
        scene.bbox_min = glm::min(scene.bbox_min, p);
        scene.bbox_max = glm::max(scene.bbox_max, p);
    }
    scene.stats.input_faces = model.faces.size();
    scene.stats.triangulated_ngons = d.triangulated;
    scene.stats.dropped_degenerate = d.degenerate;
    scene.stats.non_planar = d.non_planar;
    scene.stats.max_patch_edge = max_edge;
    scene.stats.how = how + fmt::format(" ({} patches)", scene.patches.size());
    scene.stats.warnings = std::move(d.warnings);
    if (scene.patch_elements.size() != scene.patches.size()) scene.patch_elements.clear();  // ids only where every face has one
    scene.fingerprint = fingerprint_of(scene);
    if (model.obstruction_objects > 0) return split_obstructions(std::move(scene), model.obstruction_objects);
    return scene;
}

std::size_t patch_limit_for_physical_memory(std::size_t limit) {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return limit;
    const double bytes = static_cast<double>(pages) * static_cast<double>(page);
    return std::min(limit, static_cast<std::size_t>(bytes / static_cast<double>(sizeof(Patch) + sizeof(Vec3))));
}

}  // namespace ffcube
