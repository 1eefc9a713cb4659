# Turns the files of a folder into a C++ source holding each file as a raw string literal, so an
# installed or moved binary needs no source tree. The files stay the source of truth: this runs
# at build time whenever one of them changes (see clutterscope_embed_files in
# ClutterscopeTarget.cmake, which sets the variables below).
#
# Usage: cmake -DINPUT_DIR=<dir> -DGLOBS=<*.a,*.b> -DOUTPUT=<file.cpp> -DHEADER=<header.hpp>
#              -DNAMESPACE=<ns> -DENTRY_TYPE=<struct> -DFUNCTION=<name>
#              [-DNAME_REGEX=<regex> -DNAME_RULE=<text> [-DUNIQUE_FIRST_GROUP=ON]]
#              -P embed_files.cmake
# The generated FUNCTION() returns `const std::vector<ENTRY_TYPE>&` of {file name, text} in
# file-name order; HEADER declares both. With NAME_REGEX every file name must match it (else
# the build fails with NAME_RULE); with UNIQUE_FIRST_GROUP its first group must differ between
# files.
cmake_minimum_required(VERSION 3.20)  # script mode: enables IN_LIST
foreach(required INPUT_DIR GLOBS OUTPUT HEADER NAMESPACE ENTRY_TYPE FUNCTION)
  if("${${required}}" STREQUAL "")
    message(FATAL_ERROR "embed_files.cmake needs -D${required}=...")
  endif()
endforeach()

string(REPLACE "," ";" globs "${GLOBS}")
list(TRANSFORM globs PREPEND "${INPUT_DIR}/")
file(GLOB files RELATIVE "${INPUT_DIR}" ${globs})
list(SORT files)
if(NOT files)
  message(FATAL_ERROR "no files (${GLOBS}) in ${INPUT_DIR}")
endif()

set(delimiter "cs_embedded")  # raw-string delimiters are at most 16 characters
set(entries "")
set(first_groups "")
foreach(name IN LISTS files)
  if(NAME_REGEX)
    if(NOT name MATCHES "${NAME_REGEX}")
      message(FATAL_ERROR "${INPUT_DIR}/${name}: ${NAME_RULE}")
    endif()
    if(UNIQUE_FIRST_GROUP)
      if(CMAKE_MATCH_1 IN_LIST first_groups)
        message(FATAL_ERROR "${INPUT_DIR}/${name}: another file is also named "
                            "'${CMAKE_MATCH_1}'; names must be unique")
      endif()
      list(APPEND first_groups "${CMAKE_MATCH_1}")
    endif()
  endif()
  file(READ "${INPUT_DIR}/${name}" text)
  string(FIND "${text}" ")${delimiter}\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${INPUT_DIR}/${name} contains the raw-string delimiter )${delimiter}\"")
  endif()
  string(APPEND entries "    {\"${name}\", R\"${delimiter}(${text})${delimiter}\"},\n")
endforeach()

set(source "// Generated from ${INPUT_DIR} by embed_files.cmake. Do not edit: edit the files\n")
string(APPEND source "// instead.\n")
string(APPEND source "#include \"${HEADER}\"\n\n")
string(APPEND source "namespace ${NAMESPACE} {\n\n")
string(APPEND source "const std::vector<${ENTRY_TYPE}>& ${FUNCTION}() {\n")
string(APPEND source "  static const std::vector<${ENTRY_TYPE}> files = {\n")
string(APPEND source "${entries}")
string(APPEND source "  };\n  return files;\n}\n\n")
string(APPEND source "}  // namespace ${NAMESPACE}\n")

file(WRITE "${OUTPUT}" "${source}")
