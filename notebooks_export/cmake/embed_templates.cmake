# Turns the cell templates (templates/NN_name.md|py) into a C++ source holding each file as a raw
# string literal, so an installed or moved binary needs no source tree. The files stay the source
# of truth: this runs at build time whenever one of them changes.
# Usage: cmake -DTEMPLATE_DIR=<dir> -DOUTPUT=<file.cpp> -P embed_templates.cmake
cmake_minimum_required(VERSION 3.20)  # script mode: enables IN_LIST
if(NOT TEMPLATE_DIR OR NOT OUTPUT)
  message(FATAL_ERROR "embed_templates.cmake needs -DTEMPLATE_DIR=... and -DOUTPUT=...")
endif()

file(GLOB templates RELATIVE "${TEMPLATE_DIR}" "${TEMPLATE_DIR}/*.md" "${TEMPLATE_DIR}/*.py")
list(SORT templates)
if(NOT templates)
  message(FATAL_ERROR "no cell templates (*.md, *.py) in ${TEMPLATE_DIR}")
endif()

set(delimiter "cs_template")  # raw-string delimiters are at most 16 characters
set(entries "")
set(cell_names "")
foreach(name IN LISTS templates)
  if(NOT name MATCHES "^[0-9][0-9]_([a-z0-9_]+)\\.(md|py)$")
    message(FATAL_ERROR "cell template ${TEMPLATE_DIR}/${name}: name must be NN_name.md or NN_name.py "
                        "(two-digit order, lower-case name)")
  endif()
  # The name after NN_ becomes the cell id, which nbformat requires to be unique.
  if(CMAKE_MATCH_1 IN_LIST cell_names)
    message(FATAL_ERROR "cell template ${TEMPLATE_DIR}/${name}: another template is also named "
                        "'${CMAKE_MATCH_1}'; cell names must be unique")
  endif()
  list(APPEND cell_names "${CMAKE_MATCH_1}")
  file(READ "${TEMPLATE_DIR}/${name}" text)
  string(FIND "${text}" ")${delimiter}\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "cell template ${TEMPLATE_DIR}/${name} contains the raw-string delimiter "
                        ")${delimiter}\"")
  endif()
  string(APPEND entries "    {\"${name}\", R\"${delimiter}(${text})${delimiter}\"},\n")
endforeach()

set(source "// Generated from notebooks_export/templates/ by embed_templates.cmake. Do not edit:\n")
string(APPEND source "// edit the template files instead.\n")
string(APPEND source "#include \"cell_templates.hpp\"\n\n")
string(APPEND source "namespace clutterscope::notebooks_export::detail {\n\n")
string(APPEND source "const std::vector<CellTemplate>& cell_templates() {\n")
string(APPEND source "  static const std::vector<CellTemplate> templates = {\n")
string(APPEND source "${entries}")
string(APPEND source "  };\n  return templates;\n}\n\n")
string(APPEND source "}  // namespace clutterscope::notebooks_export::detail\n")

file(WRITE "${OUTPUT}" "${source}")
