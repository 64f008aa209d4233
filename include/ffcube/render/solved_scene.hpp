// What pictures and meshes of a solved scene show, in one place for `ffcube solve`, the viewer
// and the Python module: radiance L = B/π of a Lambertian surface of radiosity B, the exposure
// that maps it to display values, and the solved mesh with per-vertex colours.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "ffcube/io/ply.hpp"
#include "ffcube/render/shading.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// L_i = B_i / π per patch.
std::vector<Vec3> patch_radiance(std::span<const Vec3> radiosity);

// The exposure (display value = exposure × radiance): `given` when set (> 0, finite), else
// automatic from the patches' luminances weighted by area (auto_exposure, render/image.hpp).
double scene_exposure(const Scene& scene, std::span<const Vec3> radiance, std::optional<double> given);

// The solved mesh for PLY: positions and faces of shade_patches(scene, radiosity, shading), the
// radiosity per vertex as values, and colours = 8-bit sRGB of exposure × radiosity / π.
PlyMesh solved_ply_mesh(const Scene& scene, std::span<const Vec3> radiosity, Shading shading, double exposure);

}  // namespace ffcube
