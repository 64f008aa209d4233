# `cmake --install build --prefix P`: the ffcube binary, the headers under P/include/ffcube, the
# libraries' static archives and a CMake package (P/lib/cmake/ffcube) whose ffcube::ffcube links
# every library layer. The viewer (GLFW, Dear ImGui) and the bench stay with the binary.
include(CMakePackageConfigHelpers)
set(ffcube_package_layers core geometry scene hemicube formfactor solver io accuracy raycast gl render pipeline)
set(ffcube_package_targets ffcube_warnings)
foreach(layer ${ffcube_package_layers})
  list(APPEND ffcube_package_targets ffcube_${layer})
endforeach()
add_library(ffcube_all INTERFACE)
set_target_properties(ffcube_all PROPERTIES EXPORT_NAME ffcube)
add_library(ffcube::ffcube ALIAS ffcube_all)  # the same name for a project that adds ffcube as a subdirectory
target_link_libraries(ffcube_all INTERFACE ffcube_pipeline ffcube_render)
# The warnings target is linked PRIVATE by every layer (so only $<LINK_ONLY:...> in the export,
# adding nothing to a user's build), but an exported target must name only exported targets.
set_target_properties(ffcube_warnings PROPERTIES EXPORT_NAME warnings)
install(TARGETS ${ffcube_package_targets} ffcube_all EXPORT ffcubeTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/ffcube DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(ffcube_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/ffcube)
install(EXPORT ffcubeTargets NAMESPACE ffcube:: DESTINATION ${ffcube_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/tools/cmake/ffcubeConfig.cmake.in
  ${PROJECT_BINARY_DIR}/ffcubeConfig.cmake INSTALL_DESTINATION ${ffcube_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ffcubeConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ffcubeConfig.cmake ${PROJECT_BINARY_DIR}/ffcubeConfigVersion.cmake
  DESTINATION ${ffcube_cmake_dir})
