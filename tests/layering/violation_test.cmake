# Runs the layer check (cmake/CheckLayering.cmake) on a copy of the tree with one forbidden edge
# added, and expects the configure to stop naming it (issue 26: the check must fail on an added
# forbidden include or link, not only pass on the tree as it is).
#
#   cmake -DSOURCE_DIR=<tree> -DWORK_DIR=<scratch> -DCASE=<case> -DGENERATOR=<generator>
#         -DCXX_COMPILER=<compiler> -P violation_test.cmake
#
# CASE: none (the unchanged copy configures: the copy itself is sound), include_tools (a domain
# library includes a tools/ header), include_domain (a domain library includes a domain library
# its row does not allow), link (a domain library links a tools/ library), public (a link
# PUBLIC that no public header needs).

foreach(var SOURCE_DIR WORK_DIR CASE GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "violation_test.cmake: -D${var}=... is required")
  endif()
endforeach()

file(REMOVE_RECURSE "${WORK_DIR}")
set(copy "${WORK_DIR}/src")
file(MAKE_DIRECTORY "${copy}")
# The configure needs the CMake files and the libraries' sources, not the tests (they are off),
# the samples, hidden folders (the history) or build trees.
file(GLOB entries RELATIVE "${SOURCE_DIR}" "${SOURCE_DIR}/*")
foreach(entry IN LISTS entries)
  if(entry MATCHES "^(\\..*|tests|build.*)$" OR EXISTS "${SOURCE_DIR}/${entry}/CMakeCache.txt")
    continue()
  endif()
  file(COPY "${SOURCE_DIR}/${entry}" DESTINATION "${copy}" PATTERN "samples" EXCLUDE)
endforeach()

function(append file text)
  if(NOT EXISTS "${copy}/${file}")
    message(FATAL_ERROR "violation_test.cmake: ${file} is not in the tree any more: pick another")
  endif()
  file(APPEND "${copy}/${file}" "${text}")
endfunction()

set(expected)
if(CASE STREQUAL "none")
elseif(CASE STREQUAL "include_tools")
  append(visibility/src/eq10.cpp "\n#include <clutterscope/batch/batch.hpp>\n")
  list(APPEND expected
    "visibility/src/eq10.cpp: visibility includes <clutterscope/batch/batch.hpp>, of batch, which the layer table does not allow"
    "visibility/src/eq10.cpp: visibility \\(outside tools/\\) includes <clutterscope/batch/batch.hpp>, of batch \\(tools/\\), which it must not")
elseif(CASE STREQUAL "include_domain")
  append(simulation/include/clutterscope/simulation/unloading.hpp
         "\n#include \"clutterscope/render/renderer.hpp\"\n")
  list(APPEND expected
    "simulation/include/clutterscope/simulation/unloading.hpp: simulation includes <clutterscope/render/renderer.hpp>, of render, which the layer table does not allow")
elseif(CASE STREQUAL "link")
  append(simulation/CMakeLists.txt
         "target_link_libraries(clutterscope_simulation PRIVATE clutterscope::report)\n")
  list(APPEND expected
    "simulation links report, which the layer table does not allow"
    "simulation \\(outside tools/\\) reaches report \\(tools/\\) through its links, which it must not")
elseif(CASE STREQUAL "public")
  append(simulation/CMakeLists.txt
         "target_link_libraries(clutterscope_simulation PUBLIC clutterscope::estimator)\n")
  list(APPEND expected
    "simulation links estimator PUBLIC, but no public header of simulation includes it: link it PRIVATE")
else()
  message(FATAL_ERROR "violation_test.cmake: unknown CASE ${CASE}")
endif()

execute_process(
  COMMAND "${CMAKE_COMMAND}" -S "${copy}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
          "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" -DCLUTTERSCOPE_BUILD_TESTS=OFF
  RESULT_VARIABLE result
  OUTPUT_VARIABLE output
  ERROR_VARIABLE output)

if(CASE STREQUAL "none")
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "the unchanged copy does not configure (exit ${result}):\n${output}")
  endif()
  message(STATUS "the unchanged copy configures")
  return()
endif()
if(result EQUAL 0)
  message(FATAL_ERROR "the configure with the forbidden edge (${CASE}) succeeded:\n${output}")
endif()
if(NOT output MATCHES "Layering check \\(cmake/CheckLayering.cmake\\) failed")
  message(FATAL_ERROR "the configure failed, but not in the layer check:\n${output}")
endif()
foreach(line IN LISTS expected)
  if(NOT output MATCHES "${line}")
    message(FATAL_ERROR "the layer check did not say '${line}':\n${output}")
  endif()
endforeach()
message(STATUS "the layer check refused the forbidden edge (${CASE})")
