# Shared warning, sanitizer and clang-tidy settings for every target of ours.
function(clutterscope_configure_target target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Werror)
  if(CLUTTERSCOPE_ASAN)
    target_compile_options(${target} PRIVATE -fsanitize=address -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address)
  endif()
  if(CLUTTERSCOPE_ASAN OR CLUTTERSCOPE_UBSAN)
    # With sanitizer instrumentation GCC 12 reports false -Wmaybe-uninitialized inside
    # libstdc++'s std::regex / std::function (seen in notebook_test.cpp); the normal build keeps
    # the warning.
    target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
  endif()
  if(CLUTTERSCOPE_ASAN OR CLUTTERSCOPE_UBSAN OR CLUTTERSCOPE_FUZZ)
    # -O1, as AddressSanitizer's and libFuzzer's documentation advise, after the build type's -O3
    # so it wins: GCC 12 with ASan + UBSan took 67 s for cmd_graph.cpp at -O3 and 32 s at -O1
    # (2026-12-03), and the sanitizer build is most of CI's time.
    target_compile_options(${target} PRIVATE -O1)
  endif()
  if(CLUTTERSCOPE_UBSAN)
    target_compile_options(${target} PRIVATE -fsanitize=undefined -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=undefined)
  endif()
  if(CLUTTERSCOPE_FUZZ)
    # Coverage instrumentation for libFuzzer; the fuzz executables add -fsanitize=fuzzer. The
    # other executables (the test suites, clutterscope) link without libFuzzer: the ASan runtime
    # has the coverage callbacks, so one tree serves the fuzz targets and the suites.
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link,address,undefined
                                             -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
  if(CLUTTERSCOPE_CLANG_TIDY)
    find_program(CLANG_TIDY_EXE NAMES clang-tidy REQUIRED)
    set_target_properties(${target} PROPERTIES CXX_CLANG_TIDY "${CLANG_TIDY_EXE}")
  endif()
endfunction()

# One library per top-level folder: sources are every src/*.cpp, public headers live in
# include/clutterscope/<folder>/. New files are picked up without editing CMake.
function(clutterscope_add_library name)
  cmake_parse_arguments(ARG "NO_UNITY_BUILD" "" "PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp")
  if(NOT sources)
    # A folder with headers only so far.
    add_library(clutterscope_${name} INTERFACE)
    add_library(clutterscope::${name} ALIAS clutterscope_${name})
    target_include_directories(clutterscope_${name} INTERFACE
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
    target_link_libraries(clutterscope_${name} INTERFACE ${ARG_PUBLIC_DEPS})
    _clutterscope_register_library(${name})
    return()
  endif()
  add_library(clutterscope_${name} STATIC ${sources})
  add_library(clutterscope::${name} ALIAS clutterscope_${name})
  target_include_directories(clutterscope_${name}
    PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>
    PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(clutterscope_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  # The Python module (a shared object) links the libraries: their code must be PIC.
  if(CLUTTERSCOPE_PYTHON)
    set_target_properties(clutterscope_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endif()
  clutterscope_configure_target(clutterscope_${name})
  if(CLUTTERSCOPE_UNITY_BUILD AND NOT ARG_NO_UNITY_BUILD)
    # One translation unit per library: each .cpp parses nlohmann/json, CLI11, Eigen or OpenCV,
    # and their inline templates are compiled once per library instead of once per file. Batch
    # size 0 puts every file of the library in the one unit, so which files share a unit never
    # changes with the number of files.
    set_target_properties(clutterscope_${name} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 0)
    # GCC takes every included file for a header, and warns when a class defined there (a
    # State of a .cpp's pimpl) has a member of an anonymous-namespace type; in the unit, each
    # .cpp is an included file.
    target_compile_options(clutterscope_${name} PRIVATE
                           $<$<CXX_COMPILER_ID:GNU>:-Wno-subobject-linkage>)
  endif()
  _clutterscope_register_library(${name})
endfunction()

# Every library is installed and exported as clutterscope::<name> (cmake/Install.cmake), with
# its public headers include/clutterscope/<name>/.
function(_clutterscope_register_library name)
  set_target_properties(clutterscope_${name} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY CLUTTERSCOPE_LIBRARIES ${name})
  set_property(GLOBAL APPEND PROPERTY CLUTTERSCOPE_INCLUDE_DIRS ${CMAKE_CURRENT_SOURCE_DIR}/include)
endfunction()

# Compiles the files of DIR matching GLOBS into TARGET as string literals (cmake/embed_files.cmake
# generates FUNCTION() returning `const std::vector<ENTRY_TYPE>&` of {file name, text}, declared
# in HEADER, a private header of TARGET). NAME_REGEX, NAME_RULE and UNIQUE_FIRST_GROUP check the
# file names at build time.
function(clutterscope_embed_files target)
  cmake_parse_arguments(ARG "UNIQUE_FIRST_GROUP" "DIR;HEADER;NAMESPACE;ENTRY_TYPE;FUNCTION;NAME_REGEX;NAME_RULE" "GLOBS" ${ARGN})
  set(absolute_globs "")
  foreach(glob IN LISTS ARG_GLOBS)
    list(APPEND absolute_globs "${ARG_DIR}/${glob}")
  endforeach()
  file(GLOB embedded_files CONFIGURE_DEPENDS ${absolute_globs})
  list(JOIN ARG_GLOBS "," globs)
  set(script "${PROJECT_SOURCE_DIR}/cmake/embed_files.cmake")
  set(output "${CMAKE_CURRENT_BINARY_DIR}/generated/${ARG_FUNCTION}_data.cpp")
  add_custom_command(
    OUTPUT "${output}"
    COMMAND "${CMAKE_COMMAND}" "-DINPUT_DIR=${ARG_DIR}" "-DGLOBS=${globs}" "-DOUTPUT=${output}"
            "-DHEADER=${ARG_HEADER}" "-DNAMESPACE=${ARG_NAMESPACE}"
            "-DENTRY_TYPE=${ARG_ENTRY_TYPE}" "-DFUNCTION=${ARG_FUNCTION}"
            "-DNAME_REGEX=${ARG_NAME_REGEX}" "-DNAME_RULE=${ARG_NAME_RULE}"
            "-DUNIQUE_FIRST_GROUP=${ARG_UNIQUE_FIRST_GROUP}" -P "${script}"
    DEPENDS ${embedded_files} "${script}"
    COMMENT "Embedding ${ARG_DIR}"
    VERBATIM)
  target_sources(${target} PRIVATE "${output}")
endfunction()
