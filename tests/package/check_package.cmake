# CTest's package.install_and_use: installs this build to a fresh prefix, builds
# examples/one_row.cpp as a separate project against it (tests/package/CMakeLists.txt), runs it on
# the parallel squares from another directory, and requires the output of the build tree's own
# example_one_row: the installed headers, libraries and package reproduce the library exactly,
# shaders included (they are compiled into the gl library, not read from the source tree).
#   cmake -DBUILD_DIR= -DSOURCE_DIR= -DWORK= -DREFERENCE=<example_one_row> -DGENERATOR= -P check_package.cmake
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err WORKING_DIRECTORY ${WORK})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/prefix)
foreach(f include/ffcube/pipeline/row_source.hpp lib/cmake/ffcube/ffcubeConfig.cmake lib/libffcube_gl.a)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
set(launcher)
find_program(CCACHE ccache)
if(CCACHE)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${CCACHE})
endif()
run("configuring the user project" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/package -B ${WORK}/build -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_PREFIX_PATH=${WORK}/prefix -DFFCUBE_EXAMPLE=${SOURCE_DIR}/examples/one_row.cpp
    ${launcher})
run("building the user project" ${CMAKE_COMMAND} --build ${WORK}/build)
set(scene ${SOURCE_DIR}/examples/parallel_squares.obj)
run("the installed example" ${WORK}/build/one_row ${scene} 0)
set(installed "${output}")
run("the build tree's example" ${REFERENCE} ${scene} 0)
if(NOT installed STREQUAL output)
  message(FATAL_ERROR "the installed library's row differs from the build tree's:\n${installed}\nvs\n${output}")
endif()
if(NOT installed MATCHES "row sum 0\\.[0-9]+")
  message(FATAL_ERROR "unexpected output:\n${installed}")
endif()
message(STATUS "installed ffcube::ffcube gives the build tree's row:\n${installed}")
file(REMOVE_RECURSE ${WORK})
