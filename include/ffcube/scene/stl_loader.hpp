// STL input, ASCII and binary, read by hand (the format is small, and every refusal must name the
// line or the facet). One object per ASCII `solid` (named by it; a binary file is one object named
// after the file's stem); exactly coinciding vertices are merged; degenerate facets (a repeated
// vertex, or no area that doubles resolve) are dropped and counted in ObjModel::dropped_degenerate.
// Winding: STL's vertices run counter-clockwise seen from outside, which is ffcube's front; a
// stored normal that disagrees with the winding is counted in a warning and ignored.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Whether these bytes are a binary STL: at least the 84-byte header, and exactly 84 + 50·n bytes
// for the facet count n at offset 80 (so a binary file whose header begins with "solid" is still
// binary, and an ASCII file is never taken for one unless its size happens to match and it does
// not begin with "solid").
bool is_binary_stl(std::string_view bytes);

// Parses STL bytes. 'source' names them in messages; 'stem' names the object of a binary file
// (and of an ASCII solid without a name).
ObjModel parse_stl(std::string_view bytes, const std::string& source, const std::string& stem);

ObjModel load_stl(const std::filesystem::path& path);

}  // namespace ffcube
