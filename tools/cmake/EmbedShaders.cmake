# Embeds shader sources into the binary at build time, so ffcube never reads shader files
# relative to the working directory. Usage (script mode):
#   cmake -DOUT=file.cpp -DSHADERS="a.vert;b.frag" -P EmbedShaders.cmake
set(body "// Generated from shaders/ by tools/cmake/EmbedShaders.cmake. Do not edit.\n#include \"gl/shaders.hpp\"\n#include <string_view>\nnamespace ffcube::shaders {\n")
foreach(path ${SHADERS})
  get_filename_component(name ${path} NAME)
  string(MAKE_C_IDENTIFIER ${name} ident)
  file(READ ${path} text)
  string(APPEND body "extern const std::string_view ${ident};\nconst std::string_view ${ident} = R\"ffcube_shader(${text})ffcube_shader\";\n")
endforeach()
string(APPEND body "}  // namespace ffcube::shaders\n")
file(WRITE ${OUT}.tmp "${body}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUT}.tmp)
