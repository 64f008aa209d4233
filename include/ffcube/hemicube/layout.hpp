// The hemicube's five faces, their cameras, their places in one atlas image, and the exact
// delta form factor (ΔF) of every atlas pixel. Pure math, no GL: the GL renderer takes the
// FaceSpecs from here, and the CPU accumulation takes delta_ff().
//
// Local frame of a hemicube (see frame.hpp): x = tangent, y = bitangent, z = patch normal.
// The eye sits at the origin; the top face is the square z = 1, x,y ∈ [-1,1]; the four side
// faces are the half squares at distance 1 (x = ±1 or y = ±1) with z ∈ [0,1].
//
// Atlas (width 3N, height N, pixel (col, row), row 0 = bottom row, as glReadPixels returns it):
//
//     row N   +-----------------+--------+--------+
//             |                 |  -X    |  -Y    |   each side tile: N wide, N/2 tall,
//     row N/2 |       TOP       +--------+--------+   its row 0 at the horizon (z = 0),
//             |                 |  +X    |  +Y    |   its top row at the top face's edge (z = 1)
//     row 0   +-----------------+--------+--------+
//            col 0             col N    col 2N   col 3N
//
//   TOP  viewport (0,  0,   N, N)    forward +z, up +y, right -x
//   +X   viewport (N,  0,   N, N/2)  forward +x, up +z, right -y
//   -X   viewport (N,  N/2, N, N/2)  forward -x, up +z, right +y
//   +Y   viewport (2N, 0,   N, N/2)  forward +y, up +z, right +x
//   -Y   viewport (2N, N/2, N, N/2)  forward -y, up +z, right -x
//
// Every camera is an OpenGL camera: eye x = right, eye y = up, eye z = -forward, and
// right × up = -forward (right-handed, no mirroring, so front-face culling keeps its meaning).
// The side faces' up vector points away from the patch plane, so the horizon is each tile's
// bottom row. Within a face, pixel column i spans eye x ∈ [l + (r-l)·i/w, l + (r-l)·(i+1)/w]
// and row j spans eye y ∈ [b + (t-b)·j/h, ...] on the plane at distance 1 along forward; that is
// exactly what glFrustum(l·near, r·near, b·near, t·near, near, far) with glViewport(viewport)
// rasterises. All 3N² atlas pixels belong to a face.
#pragma once

#include <string_view>

#include "ffcube/geometry/polygon.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace ffcube {

enum class HemicubeFace : int { Top = 0, PosX = 1, NegX = 2, PosY = 3, NegY = 4 };

// Off-centre frustum on the plane at distance 1 along the face's forward vector, in eye
// coordinates (x along right, y along up). Multiply by the near distance for glFrustum.
struct FaceFrustum {
    double left, right, bottom, top;
};

// A rectangle of the atlas in pixels, origin at the bottom-left (glViewport's convention).
struct AtlasViewport {
    int x, y, width, height;
};

struct FaceSpec {
    HemicubeFace face;
    Vec3 forward;  // unit, hemicube local frame
    Vec3 up;       // unit, local frame
    Vec3 right;    // unit, local frame; right × up = -forward
    FaceFrustum frustum;
    AtlasViewport viewport;
};

// One pixel of the atlas: column x ∈ [0, 3N), row y ∈ [0, N), row 0 at the bottom.
struct AtlasPixel {
    HemicubeFace face;
    int x, y;
};

// The one rule for the resolution a hemicube row is rendered at (command line, bench, viewer,
// Python, the GL provider): an even number of pixels from 8 to 8192. Throws InputError
// "<what> <N>: must be an even number of pixels from 8 to 8192". The layout below accepts a wider
// range ([2, 16384]) because its ΔF table is exact for any even N; rendering is what sets 8..8192.
constexpr int kMinRowResolution = 8, kMaxRowResolution = 8192;
void check_row_resolution(int resolution, std::string_view what = "--resolution");

class HemicubeLayout {
public:
    // N: top-face resolution in pixels; even and in [2, 16384] (InputError otherwise, naming
    // the rule). Builds the ΔF table: 3N² doubles (N = 512: 6 MiB).
    explicit HemicubeLayout(int resolution);

    int resolution() const { return n_; }
    int atlas_width() const { return 3 * n_; }
    int atlas_height() const { return n_; }

    // Indexed by static_cast<int>(HemicubeFace).
    const std::array<FaceSpec, 5>& faces() const { return faces_; }
    const FaceSpec& face(HemicubeFace f) const { return faces_[static_cast<int>(f)]; }

    // ΔF per atlas pixel, row-major, index = row · atlas_width() + col, row 0 at the bottom.
    // Each value is the exact integral of cosθ·cosθ'/(π r²) over the pixel (the fraction of
    // the patch's cosine-weighted hemisphere the pixel subtends), computed in double from
    // closed-form antiderivatives; the table sums to 1 up to rounding (about 1e-13).
    const std::vector<double>& delta_ff() const { return dff_; }
    // The atlas row y in runs of pixels summed in one subtraction (the rows' accumulation,
    // gl/hemicube_worker.cpp: a patch covers runs of neighbouring pixels, and a run's ΔF costs
    // two table reads, not one addition a pixel). A row is three segments, one per face it
    // crosses; a segment's pixels [begin, end) (offsets in the atlas row) have the prefix sums
    // prefix_sums()[prefix + x − begin] = Σ ΔF of the segment's pixels before x, x ∈ [begin,
    // end]. Segments with the same ΔF (the top face's rows y and N−1−y, the side faces' rows at
    // one height) share one table: N/2 tables for the top and N/2 for the sides, N(N + 1)
    // doubles (N = 256: 514 KiB, against 1.5 MiB of delta_ff(), so that the table stays in a
    // core's cache beside the item buffer). The sums are added left to right; a run's
    // subtraction rounds by about 1e-16 of its row's ΔF (below 1/N), relative 1e-13 or less of
    // a one-pixel run's ΔF (about 1/(πN²)): far below the pixel discretisation itself.
    struct RowSegment {
        std::uint32_t begin, end, prefix;
    };
    const std::array<RowSegment, 3>& row_segments(int y) const { return segments_[static_cast<std::size_t>(y)]; }
    const std::vector<double>& prefix_sums() const { return prefix_; }
    // Σ ΔF over the pixels [a, b) of segment s (s.begin ≤ a ≤ b ≤ s.end).
    double run_sum(const RowSegment& s, std::size_t a, std::size_t b) const {
        const double* t = prefix_.data() + s.prefix;
        return t[b - s.begin] - t[a - s.begin];
    }

    // The atlas pixel that a direction (hemicube local frame, need not be unit) falls in, or
    // nullopt for a direction below the horizon (z < 0) or zero. Directions on a boundary
    // between pixels or faces go to one of them.
    std::optional<AtlasPixel> pixel_of_direction(const Vec3& dir) const;

    // The direction (local frame, not unit) through the eye-plane point (u, v) of a face, u
    // along right and v along up, at distance 1 along forward.
    static Vec3 face_direction(const FaceSpec& f, double u, double v) {
        return f.forward + u * f.right + v * f.up;
    }

private:
    int n_;
    std::array<FaceSpec, 5> faces_;
    std::vector<double> dff_;
    std::vector<std::array<RowSegment, 3>> segments_;
    std::vector<double> prefix_;
};

}  // namespace ffcube
