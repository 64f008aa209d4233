// The closed form of a box's shadow on the ground (tests of `ffcube sun`): the unit box
// [0,1]² × [0,1] standing on the square ground [−5,5]² at z = 0, lit from the unit direction s
// towards the sun (s_z > 0). The shadow of a convex solid on a plane is the convex hull of the
// shadows of its corners: the footprint's corners (their own shadow) and the roof's corners
// moved along −s down to z = 0, i.e. by −(s_x, s_y)/s_z. It is clipped to the ground
// (Sutherland–Hodgman against the square's four sides) and measured by the shoelace formula.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace ffcube::test {

struct P2 {
    double x, y;
};

inline double cross2(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// Andrew's monotone chain: the hull counter-clockwise, no collinear points.
inline std::vector<P2> convex_hull(std::vector<P2> p) {
    std::sort(p.begin(), p.end(), [](P2 a, P2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    std::vector<P2> h(2 * p.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
        h[k++] = p[i];
    }
    for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
        h[k++] = p[i];
    }
    h.resize(k - 1);
    return h;
}

inline double shoelace(const std::vector<P2>& p) {
    double a = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const P2 &u = p[i], &v = p[(i + 1) % p.size()];
        a += u.x * v.y - v.x * u.y;
    }
    return 0.5 * std::abs(a);
}

// Keeps the part of convex polygon p where a·x + b·y ≤ c.
inline std::vector<P2> clip(const std::vector<P2>& p, double a, double b, double c) {
    std::vector<P2> out;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const P2 &u = p[i], &v = p[(i + 1) % p.size()];
        const double fu = a * u.x + b * u.y - c, fv = a * v.x + b * v.y - c;
        if (fu <= 0) out.push_back(u);
        if ((fu < 0) != (fv < 0) && fu != fv) {
            const double t = fu / (fu - fv);
            out.push_back({u.x + t * (v.x - u.x), u.y + t * (v.y - u.y)});
        }
    }
    return out;
}

// The shadow area of the box [0,1]³ on the ground [−g, g]² (g = 5), s_z > 0.
inline double box_shadow_on_ground(double sx, double sy, double sz, double g = 5.0) {
    const double dx = -sx / sz, dy = -sy / sz;
    std::vector<P2> pts;
    for (const P2 c : {P2{0, 0}, P2{1, 0}, P2{1, 1}, P2{0, 1}}) {
        pts.push_back(c);
        pts.push_back({c.x + dx, c.y + dy});
    }
    std::vector<P2> h = convex_hull(pts);
    h = clip(h, 1, 0, g);
    h = clip(h, -1, 0, g);
    h = clip(h, 0, 1, g);
    h = clip(h, 0, -1, g);
    return h.size() >= 3 ? shoelace(h) : 0.0;
}

// The unit box [0,1]³ (roof and four walls, facing out; no floor) on the ground [−5,5]², one
// object per face (--no-subdivide: one patch each).
inline const char* kBoxOnPlane = R"(o ground
v -5 -5 0
v 5 -5 0
v 5 5 0
v -5 5 0
f 1 2 3 4
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
o roof
f 9 10 11 12
o south
f 5 6 10 9
o east
f 6 7 11 10
o north
f 7 8 12 11
o west
f 8 5 9 12
)";

// The direction towards a sun at azimuth az (clockwise from north, +y; east +x) and elevation el,
// in degrees (what `ffcube sun --sun AZ,EL` means).
inline std::array<double, 3> sun_from_angles(double az_deg, double el_deg) {
    const double a = az_deg * M_PI / 180, e = el_deg * M_PI / 180;
    return {std::sin(a) * std::cos(e), std::cos(a) * std::cos(e), std::sin(e)};
}

// The ten sun positions of the tests: grazing (5°, 10°) to the zenith, azimuths all round and
// off the box's axes.
inline constexpr std::array<std::array<double, 2>, 10> kSunPositions{{
    {0, 5}, {37, 5}, {90, 10}, {200, 10}, {135, 30}, {290, 30}, {45, 60}, {250, 60}, {0, 90}, {123, 45},
}};

}  // namespace ffcube::test
