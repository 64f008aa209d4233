// The benchmark's cases and their exact object-to-object form factors.
#include <algorithm>
#include <cmath>
#include <string>
#include <limits>
#include <numbers>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/reference/l_room.hpp"
#include "ffcube/bench/bench.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/scene/mesher.hpp"

namespace ffcube {
namespace {

constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
using Poly = std::vector<Vec3>;

// Unit-free rectangle [x0,x1]×[y0,y1] in the plane z, facing up (+z) or down.
Poly rect_z(double x0, double x1, double y0, double y1, double z, bool up) {
    const Vec3 a(x0, y0, z), b(x1, y0, z), c(x1, y1, z), d(x0, y1, z);
    return up ? Poly{a, b, c, d} : Poly{a, d, c, b};
}
// Rectangle in the plane x, spanning y0..y1, z0..z1, facing +x or −x.
Poly rect_x(double x, double y0, double y1, double z0, double z1, bool plus) {
    const Vec3 a(x, y0, z0), b(x, y1, z0), c(x, y1, z1), d(x, y0, z1);
    return plus ? Poly{a, b, c, d} : Poly{a, d, c, b};
}
// Rectangle in the plane y, spanning x0..x1, z0..z1, facing +y or −y.
Poly rect_y(double y, double x0, double x1, double z0, double z1, bool plus) {
    const Vec3 a(x0, y, z0), b(x0, y, z1), c(x1, y, z1), d(x1, y, z0);
    return plus ? Poly{a, b, c, d} : Poly{a, d, c, b};
}

Poly transformed(Poly p, double scale, Vec3 offset) {
    for (Vec3& v : p) v = v * scale + offset;
    return p;
}

using Matrix = std::vector<std::vector<double>>;

// Meshing: about `target` patches on the largest object (square cells of its area).
double edge_for(const std::vector<NamedPolygon>& polys, double target) {
    double amax = 0;
    for (const auto& p : polys) amax = std::max(amax, polygon_area(p.vertices));
    return std::sqrt(amax / target) * (1.0 + 1e-9);
}

// A case whose objects are single polygons that all see each other unoccluded: exact[a][b] is
// the polygon-to-polygon contour integral (0 on the diagonal: planar objects).
BenchCase unoccluded(std::string name, std::string group, std::string description, std::vector<NamedPolygon> polys) {
    BenchCase c{std::move(name), std::move(group), std::move(description), std::move(polys), 0, {}};
    const std::size_t m = c.polygons.size();
    c.exact.assign(m, std::vector<double>(m, 0.0));
    for (std::size_t a = 0; a < m; ++a)
        for (std::size_t b = 0; b < m; ++b)
            if (a != b) c.exact[a][b] = ff_polygon_polygon(c.polygons[a].vertices, c.polygons[b].vertices);
    return c;
}

// Reciprocity: G_ba from G_ab.
double recip(double g_ab, double area_a, double area_b) { return g_ab * area_a / area_b; }

// The six inward walls of the box [0,s0]×[0,s1]×[0,s2], objects x0,x1,y0,y1,z0,z1, with exact
// values from closed forms only: opposite walls C-11, adjacent walls C-14.
BenchCase box_case(std::string name, std::string description, double sx, double sy, double sz) {
    const double s[3] = {sx, sy, sz};
    BenchCase c{std::move(name), "enclosure", std::move(description), {}, 0, {}};
    c.polygons = {{"x0", rect_x(0, 0, sy, 0, sz, true)},  {"x1", rect_x(sx, 0, sy, 0, sz, false)},
                  {"y0", rect_y(0, 0, sx, 0, sz, true)},  {"y1", rect_y(sy, 0, sx, 0, sz, false)},
                  {"z0", rect_z(0, sx, 0, sy, 0, true)},  {"z1", rect_z(0, sx, 0, sy, sz, false)}};
    c.exact.assign(6, std::vector<double>(6, 0.0));
    for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) {
            const int ka = a / 2, kb = b / 2;  // normal axes
            if (a == b) continue;
            if (ka == kb) {
                c.exact[a][b] = ff_parallel_rectangles(s[(ka + 1) % 3], s[(ka + 2) % 3], s[ka]);
            } else {
                const int q = 3 - ka - kb;  // the common edge's axis
                // Wall a spans axes q and kb: its width across the edge is s[kb]; b's height is s[ka].
                c.exact[a][b] = ff_perpendicular_rectangles_common_edge(s[q], s[kb], s[ka]);
            }
        }
    return c;
}

// The polygons of the two-walls-at-angle family: floor [0,1]² (normal +z) and a unit square
// hinged on the floor's edge x = 0, at angle θ to the floor, both facing into the wedge.
std::vector<NamedPolygon> wedge(double theta) {
    const Vec3 dir(std::cos(theta), 0, std::sin(theta));
    const Vec3 e0(0, 0, 0), e1(0, 1, 0);
    // Seen from inside the wedge, the hinged square's corners e0, e0+dir, e1+dir, e1 run CCW
    // when its normal points toward the floor side: n = (sin θ, 0, −cos θ).
    return {{"floor", rect_z(0, 1, 0, 1, 0, true)}, {"wall", {e0, e1, e1 + dir, e0 + dir}}};
}

BenchCase occluded_half_wall() {
    // A = [−1,1]² at z = 0 facing up, B the same at z = 1 facing down, and a one-sided wall in the
    // plane x = 0 between them (front −x; its back blocks too). A segment from A's half x < 0 to
    // B's half x > 0 crosses x = 0 at some z in (0,1) and y in [−1,1]: on the wall. So each half
    // sees only the half above it and, from x < 0, the wall's front; by symmetry
    //   G_AB = F(1×2 opposed at 1) (C-11), G_A,wall = ½ F(A's half x<0 → wall).
    BenchCase c{"half_wall", "occlusion",
                "2x2 plates at distance 1 split by a one-sided wall in their plane of symmetry", {}, 0, {}};
    c.polygons = {{"a", rect_z(-1, 1, -1, 1, 0, true)}, {"b", rect_z(-1, 1, -1, 1, 1, false)},
                  {"wall", rect_x(0, -1, 1, 0, 1, false)}};
    const double gab = ff_parallel_rectangles(1, 2, 1);
    const double gaw = 0.5 * ff_polygon_polygon(rect_z(-1, 0, -1, 1, 0, true), c.polygons[2].vertices);
    const double gbw = 0.5 * ff_polygon_polygon(rect_z(-1, 0, -1, 1, 1, false), c.polygons[2].vertices);
    const double aa = 4, aw = 2;
    c.exact = {{0, gab, gaw}, {gab, 0, gbw}, {recip(gaw, aa, aw), recip(gbw, aa, aw), 0}};
    return c;
}

BenchCase occluded_full_shadow() {
    // A = [0,1]² at z = 0 facing up, B at z = 2 facing down, a blocker [0,1]² at z = 1 facing
    // down. Every segment from A to B crosses z = 1 inside [0,1]² (a convex combination of two
    // points of the square): A sees only the blocker (C-11 at distance 1), B sees the blocker's
    // back (absorbed) and nothing else.
    BenchCase c{"full_shadow", "occlusion", "unit plates at distance 2 with a one-sided blocker between them", {}, 0, {}};
    c.polygons = {{"a", rect_z(0, 1, 0, 1, 0, true)}, {"b", rect_z(0, 1, 0, 1, 2, false)},
                  {"blocker", rect_z(0, 1, 0, 1, 1, false)}};
    const double f = ff_parallel_rectangles(1, 1, 1);
    c.exact = {{0, 0, f}, {0, 0, 0}, {f, 0, 0}};
    return c;
}

BenchCase occluded_cross() {
    // A = [−1,1]² at z = 0 (up), B at z = 1 (down), wall1 in x = 0 (front −x), wall2 in y = 0
    // (front −y), both spanning the plates and z ∈ [0,1]. The walls cut the box into four
    // quadrant cells; a segment between two cells crosses a wall. Each quadrant of A sees the
    // quadrant of B above it (unit squares at 1: C-11) and the wall halves bounding its cell
    // whose front faces into it; the wall halves in the cell x<0, y<0 see each other (C-14).
    BenchCase c{"cross_walls", "occlusion", "2x2 plates at distance 1 split into quadrants by two crossing walls", {},
                0, {}};
    c.polygons = {{"a", rect_z(-1, 1, -1, 1, 0, true)}, {"b", rect_z(-1, 1, -1, 1, 1, false)},
                  {"wall_x", rect_x(0, -1, 1, 0, 1, false)}, {"wall_y", rect_y(0, -1, 1, 0, 1, false)}};
    const double gab = ff_parallel_rectangles(1, 1, 1);
    auto quad_to = [](double z, bool up, const Poly& w1, const Poly& w2) {
        // Sum over the two quadrants of the plate at height z that face w1's and w2's fronts.
        return ff_polygon_polygon(rect_z(-1, 0, -1, 0, z, up), w1) + ff_polygon_polygon(rect_z(-1, 0, 0, 1, z, up), w2);
    };
    const Poly wx_neg = rect_x(0, -1, 0, 0, 1, false), wx_pos = rect_x(0, 0, 1, 0, 1, false);
    const Poly wy_neg = rect_y(0, -1, 0, 0, 1, false), wy_pos = rect_y(0, 0, 1, 0, 1, false);
    // wall_x's front (−x) bounds the cells x<0: y<0 (half wx_neg) and y>0 (half wx_pos).
    const double gawx = 0.25 * quad_to(0, true, wx_neg, wx_pos);
    const double gbwx = 0.25 * quad_to(1, false, wx_neg, wx_pos);
    // wall_y's front (−y) bounds the cells y<0: x<0 (half wy_neg) and x>0 (half wy_pos).
    const double gawy = 0.25 * (ff_polygon_polygon(rect_z(-1, 0, -1, 0, 0, true), wy_neg) +
                                ff_polygon_polygon(rect_z(0, 1, -1, 0, 0, true), wy_pos));
    const double gbwy = 0.25 * (ff_polygon_polygon(rect_z(-1, 0, -1, 0, 1, false), wy_neg) +
                                ff_polygon_polygon(rect_z(0, 1, -1, 0, 1, false), wy_pos));
    const double gww = 0.5 * ff_perpendicular_rectangles_common_edge(1, 1, 1);
    const double aa = 4, aw = 2;
    c.exact = {{0, gab, gawx, gawy},
               {gab, 0, gbwx, gbwy},
               {recip(gawx, aa, aw), recip(gbwx, aa, aw), 0, gww},
               {recip(gawy, aa, aw), recip(gbwy, aa, aw), gww, 0}};
    return c;
}

// View3D's L-shaped room (examples/l_shaped_room.vs3: the manual's example, Pinney & Bean test 4):
// twelve walls, floors and ceilings whose ceiling and floor parts combine (View3D's cmb) into
// eight objects; the re-entrant corner hides part of each arm from the other. Exact values:
// reference/l_room.hpp (closed forms, and the point factor integrated on the pieces where the
// corner hides; exact to 1e-12), combined by area as View3D combines them.
BenchCase l_shaped_room() {
    BenchCase c{"l_shaped_room", "occlusion",
                "View3D's L-shaped room (Pinney & Bean test 4): 12 surfaces as 8 objects, a re-entrant corner", {}, 0, {}};
    // S1..S12 of the .vs3 → objects: S9, S10 join S7 (the ceiling), S11, S12 join S8 (the floor).
    static const char* const object[12] = {"srf-1", "srf-2", "srf-3", "srf-4", "srf-5", "srf-6",
                                           "srf-7", "srf-8", "srf-7", "srf-7", "srf-8", "srf-8"};
    // Whole surfaces, as the .vs3 gives them to the mesher (the reference splits two walls at
    // the corner's planes: each whole wall is the union of its parts, one rectangle).
    std::vector<l_room::AxisRect> whole(12);
    std::vector<bool> seen(12, false);
    for (const l_room::RoomPart& p : l_room::l_room_parts()) {
        l_room::AxisRect& w = whole[static_cast<std::size_t>(p.surface)];
        if (!seen[static_cast<std::size_t>(p.surface)]) {
            w = p.rect;
            seen[static_cast<std::size_t>(p.surface)] = true;
        }
        for (int k = 0; k < 2; ++k) {
            w.lo[k] = std::min(w.lo[k], p.rect.lo[k]);
            w.hi[k] = std::max(w.hi[k], p.rect.hi[k]);
        }
    }
    std::vector<double> surface_area(12, 0.0);
    for (std::size_t i = 0; i < 12; ++i) {
        c.polygons.push_back({object[i], whole[i].polygon()});
        surface_area[i] = whole[i].area();
    }
    // Object k in the order first named (srf-1 … srf-8), as measure_errors orders them.
    const auto index = [](const char* name) { return static_cast<std::size_t>(name[4] - '1'); };
    const auto F = l_room::l_room_reference(16);
    std::vector<double> area(8, 0.0);
    c.exact.assign(8, std::vector<double>(8, 0.0));
    for (std::size_t i = 0; i < 12; ++i) {
        area[index(object[i])] += surface_area[i];
        for (std::size_t j = 0; j < 12; ++j) c.exact[index(object[i])][index(object[j])] += surface_area[i] * F[i][j];
    }
    for (std::size_t a = 0; a < 8; ++a)
        for (double& x : c.exact[a]) x /= area[a];
    return c;
}

std::vector<BenchCase> all_cases() {
    std::vector<BenchCase> cs;
    const double pi = std::numbers::pi;
    // ---- basic
    for (double d : {0.5, 1.0, 2.0}) {
        BenchCase c = unoccluded(d == 0.5 ? "parallel_d0.5" : d == 1.0 ? "parallel_d1" : "parallel_d2", "basic",
                                 "opposed unit squares at distance d (C-11)",
                                 {{"a", rect_z(0, 1, 0, 1, 0, true)}, {"b", rect_z(0, 1, 0, 1, d, false)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles(1, 1, d);
        cs.push_back(std::move(c));
    }
    {
        BenchCase c = unoccluded("parallel_offset", "basic", "unit squares at distance 1, offset by (0.5, 0.5) (C-12)",
                                 {{"a", rect_z(0, 1, 0, 1, 0, true)}, {"b", rect_z(0.5, 1.5, 0.5, 1.5, 1, false)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles_offset(0, 1, 0, 1, 0.5, 1.5, 0.5, 1.5, 1);
        cs.push_back(std::move(c));
    }
    for (auto [w, h] : {std::pair{1.0, 1.0}, std::pair{2.0, 0.5}}) {
        BenchCase c = unoccluded(w == 1.0 ? "perpendicular_1x1" : "perpendicular_2x0.5", "basic",
                                 "rectangles at 90 degrees with a common unit edge (C-14)",
                                 {{"floor", rect_z(0, w, 0, 1, 0, true)}, {"wall", rect_x(0, 0, 1, 0, h, true)}});
        c.exact[0][1] = ff_perpendicular_rectangles_common_edge(1, w, h);
        c.exact[1][0] = ff_perpendicular_rectangles_common_edge(1, h, w);
        cs.push_back(std::move(c));
    }
    {
        // Regular 48-gons of radius 1 at distance 1 (the polygons' exact value, not the disks').
        Poly lo, hi;
        for (int k = 0; k < 48; ++k) {
            const double t = 2 * pi * k / 48;
            lo.emplace_back(std::cos(t), std::sin(t), 0.0);
        }
        for (int k = 47; k >= 0; --k) hi.emplace_back(lo[k].x, lo[k].y, 1.0);
        cs.push_back(unoccluded("disks", "basic", "coaxial regular 48-gons (disks) of radius 1 at distance 1",
                                {{"a", lo}, {"b", hi}}));
    }
    cs.push_back(unoccluded("triangles", "basic", "two parallel right triangles at distance 0.5, one rotated",
                            {{"a", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {"b", {{1, 1, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}}}}));
    // ---- enclosure
    cs.push_back(box_case("cube", "inside of the unit cube (rows sum to 1)", 1, 1, 1));
    cs.push_back(box_case("long_box", "inside of a 1x1x8 box (rows sum to 1)", 1, 1, 8));
    cs.push_back(box_case("room", "inside of a 5x4x3 room (rows sum to 1)", 5, 4, 3));
    // ---- proximity
    {
        BenchCase c = unoccluded("gap_1e-3", "proximity", "opposed unit squares 1e-3 apart (C-11)",
                                 {{"a", rect_z(0, 1, 0, 1, 0, true)}, {"b", rect_z(0, 1, 0, 1, 1e-3, false)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles(1, 1, 1e-3);
        cs.push_back(std::move(c));
    }
    cs.push_back(unoccluded("gap_edge_1e-3", "proximity", "unit squares at 90 degrees, 1e-3 short of a common edge",
                            {{"floor", rect_z(0, 1, 0, 1, 0, true)}, {"wall", rect_x(0, 0, 1, 1e-3, 1 + 1e-3, true)}}));
    for (int deg : {60, 90, 120})
        cs.push_back(unoccluded("edge_" + std::to_string(deg), "proximity",
                                "unit squares sharing an edge at " + std::to_string(deg) + " degrees", wedge(deg * pi / 180)));
    cs.push_back(unoccluded("vertex", "proximity", "unit squares at 90 degrees sharing one vertex",
                            {{"floor", rect_z(0, 1, 0, 1, 0, true)}, {"wall", rect_x(0, -1, 0, 0, 1, true)}}));
    // ---- extreme
    {
        BenchCase c = unoccluded("aspect_1000", "extreme", "opposed 1000x1 strips at distance 1 (C-11)",
                                 {{"a", rect_z(0, 1000, 0, 1, 0, true)}, {"b", rect_z(0, 1000, 0, 1, 1, false)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles(1000, 1, 1);
        cs.push_back(std::move(c));
    }
    cs.push_back(unoccluded("size_1e4", "extreme", "a 1e-4 square 1 above the centre of a unit square",
                            {{"big", rect_z(0, 1, 0, 1, 0, true)},
                             {"small", rect_z(0.5 - 5e-5, 0.5 + 5e-5, 0.5 - 5e-5, 0.5 + 5e-5, 1, false)}}));
    {
        const Vec3 off(1e5, 1e5, 1e5);
        BenchCase c = unoccluded("offset_1e5", "extreme", "parallel_d1 moved by (1e5, 1e5, 1e5)",
                                 {{"a", transformed(rect_z(0, 1, 0, 1, 0, true), 1, off)},
                                  {"b", transformed(rect_z(0, 1, 0, 1, 1, false), 1, off)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles(1, 1, 1);
        cs.push_back(std::move(c));
    }
    for (double s : {1e-4, 1e4}) {
        BenchCase c = unoccluded(s < 1 ? "scale_1e-4" : "scale_1e4", "extreme", "perpendicular_1x1 scaled",
                                 {{"floor", transformed(rect_z(0, 1, 0, 1, 0, true), s, Vec3(0))},
                                  {"wall", transformed(rect_x(0, 0, 1, 0, 1, true), s, Vec3(0))}});
        c.exact[0][1] = c.exact[1][0] = ff_perpendicular_rectangles_common_edge(1, 1, 1);
        cs.push_back(std::move(c));
    }
    {
        BenchCase c = unoccluded("far_apart", "extreme", "opposed unit squares at distance 100 (C-11)",
                                 {{"a", rect_z(0, 1, 0, 1, 0, true)}, {"b", rect_z(0, 1, 0, 1, 100, false)}});
        c.exact[0][1] = c.exact[1][0] = ff_parallel_rectangles(1, 1, 100);
        cs.push_back(std::move(c));
    }
    // ---- occlusion
    cs.push_back(occluded_half_wall());
    cs.push_back(occluded_full_shadow());
    cs.push_back(occluded_cross());
    cs.push_back(l_shaped_room());
    return cs;
}

}  // namespace

const std::vector<std::string>& bench_groups() {
    static const std::vector<std::string> groups = {"basic", "enclosure", "proximity", "extreme", "occlusion"};
    return groups;
}

std::vector<BenchCase> bench_cases(bool quick) {
    // Default: about 144 patches on each case's largest object; quick: about 36, and one or two
    // cases per group.
    static const char* const quick_cases[] = {"parallel_d1", "perpendicular_1x1", "cube", "edge_60", "far_apart",
                                              "half_wall", "l_shaped_room"};
    std::vector<BenchCase> out;
    for (BenchCase& c : all_cases()) {
        if (quick && std::find(std::begin(quick_cases), std::end(quick_cases), c.name) == std::end(quick_cases))
            continue;
        c.max_patch_edge = edge_for(c.polygons, quick ? 36.0 : 144.0);
        out.push_back(std::move(c));
    }
    return out;
}

Scene build_bench_scene(const BenchCase& c) {
    const ObjModel m = model_from_polygons(c.polygons, "<bench case " + c.name + ">");
    MeshOptions o;
    o.max_patch_edge = c.max_patch_edge;
    return build_scene(m, o);
}

}  // namespace ffcube
