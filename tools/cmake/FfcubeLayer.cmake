# ffcube_layer(NAME DEPS...): one static library per layer, built from src/NAME/*.cpp.
# Each layer links only the layers below it (see docs/architecture.md), so a wrong
# include fails to build instead of living on.
function(ffcube_layer name)
  cmake_parse_arguments(L "" "" "PUBLIC;PRIVATE" ${ARGN})
  file(GLOB_RECURSE srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
  add_library(ffcube_${name} STATIC ${srcs})
  add_library(ffcube::${name} ALIAS ffcube_${name})
  target_include_directories(ffcube_${name}
    PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
    PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(ffcube_${name} PUBLIC ${L_PUBLIC} PRIVATE ffcube_warnings ${L_PRIVATE})
  # PIC: the Python module (src/python/) links these static libraries into a shared object.
  set_target_properties(ffcube_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON EXPORT_NAME ${name})
endfunction()
