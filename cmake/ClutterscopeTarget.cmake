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
  if(CLUTTERSCOPE_UBSAN)
    target_compile_options(${target} PRIVATE -fsanitize=undefined -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=undefined)
  endif()
  if(CLUTTERSCOPE_FUZZ)
    # Coverage instrumentation for libFuzzer; the fuzz executables add -fsanitize=fuzzer.
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
  cmake_parse_arguments(ARG "" "" "PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp")
  if(NOT sources)
    # A folder with headers only so far.
    add_library(clutterscope_${name} INTERFACE)
    add_library(clutterscope::${name} ALIAS clutterscope_${name})
    target_include_directories(clutterscope_${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(clutterscope_${name} INTERFACE ${ARG_PUBLIC_DEPS})
    return()
  endif()
  add_library(clutterscope_${name} STATIC ${sources})
  add_library(clutterscope::${name} ALIAS clutterscope_${name})
  target_include_directories(clutterscope_${name}
    PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(clutterscope_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  clutterscope_configure_target(clutterscope_${name})
endfunction()
