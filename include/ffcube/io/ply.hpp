// PLY output (Stanford polygon format, binary little-endian 1.0) of a coloured polygon mesh, for
// other tools (MeshLab, Blender, Open3D, CloudCompare read it).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// A mesh with per-vertex display colours and per-vertex linear values.
struct PlyMesh {
    std::vector<Vec3> positions;                       // written as float x, y, z
    std::vector<std::array<std::uint8_t, 3>> colors;   // one per position: uchar red, green, blue
    // One per position, written as float radiosity_r, radiosity_g, radiosity_b (tools that do not
    // know these properties skip them); may be empty, then the properties are left out.
    std::vector<Vec3> values;
    // Face f has face_sizes[f] (3 or 4) vertices, listed in order in face_indices (CCW from the
    // front), each < positions.size().
    std::vector<std::uint8_t> face_sizes;
    std::vector<std::uint32_t> face_indices;
};

// Header:
//   ply / format binary_little_endian 1.0 / comment <comment> /
//   element vertex N / property float x,y,z / property uchar red,green,blue /
//   [property float radiosity_r,radiosity_g,radiosity_b] /
//   element face M / property list uchar uint vertex_indices / end_header
// Atomic (atomic_file.hpp); IoError when it cannot be written. FFCUBE_CHECK on inconsistent sizes
// (a programming error).
void write_ply(const std::filesystem::path& path, const PlyMesh& mesh, const std::string& comment);

}  // namespace ffcube
