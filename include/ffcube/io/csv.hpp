// CSV outputs (RFC 4180: comma-separated, "\n" line ends, a header line). Numbers are written
// with 9 significant digits ("%.9g"); names are quoted only when they need it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// A field as RFC 4180 wants it: unchanged, or in double quotes with inner quotes doubled when it
// holds a comma, a double quote, CR or LF.
std::string csv_field(std::string_view s);

// Object-to-object form factors. G[a][b] as from object_form_factors() (checks.hpp): the
// area-weighted fraction of the energy leaving object a that arrives at object b; names[a] as in
// the OBJ. Header "from,to,F", one line per pair with G[a][b] > 0, a then b ascending.
// Atomic; IoError when the file cannot be written.
void write_groups_csv(const std::filesystem::path& path, const std::vector<std::vector<double>>& G,
                      const std::vector<std::string>& names);

// Area-weighted mean radiosity per object. Header "object,area,B_r,B_g,B_b"; one line per object
// a: names[a], area[a] (scene units²), B[a] per RGB channel (power per unit area).
void write_object_radiosity_csv(const std::filesystem::path& path, const std::vector<std::string>& names,
                                std::span<const double> area, std::span<const Vec3> B);

// Radiosity per patch. Header "patch,object,area,B_r,B_g,B_b"; one line per patch i: i (0-based,
// the row of the form-factor matrix), object_names[object[i]], area[i], B[i] per RGB channel.
void write_patch_radiosity_csv(const std::filesystem::path& path, std::span<const std::uint32_t> object,
                               std::span<const double> area, std::span<const Vec3> B,
                               const std::vector<std::string>& object_names);

}  // namespace ffcube
