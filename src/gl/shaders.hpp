// The shaders of shaders/, embedded at build time (tools/cmake/EmbedShaders.cmake writes their
// definitions into the gl library): the one place their names are declared, for the hemicube
// worker (gl), the picture renderer (render) and the viewer.
#pragma once

#include <string_view>

namespace ffcube::shaders {
extern const std::string_view item_vert;        // hemicube item buffer: piece → patch ID
extern const std::string_view item_frag;
extern const std::string_view shade_vert;       // render/: solved radiosity pictures
extern const std::string_view shade_frag;
extern const std::string_view view_scene_vert;  // viewer/: the scene, IDs for picking, lines
extern const std::string_view view_scene_frag;
extern const std::string_view view_id_frag;
extern const std::string_view view_line_frag;
extern const std::string_view sun_vert;         // gl/sun_buffer.cpp: orthographic item buffer along the sun
extern const std::string_view sun_frag;
}  // namespace ffcube::shaders
