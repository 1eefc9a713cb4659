# The layering of the libraries, checked at every configure (issues 15 and 26; docs/architecture.md).
#
# clutterscope_check_layering() checks, for every library of the table below:
#   - links: its direct links to libraries of ours are among its row (nothing more may appear);
#   - includes: every #include <clutterscope/NAME/...> (or "clutterscope/NAME/...") of its
#     sources, private and public headers names itself or a library of its row;
#   - PUBLIC links: each library of ours it links PUBLIC is included by one of its public headers
#     (include/clutterscope/<library>/); otherwise the link must be PRIVATE;
#   - tools/: a library outside tools/ reaches no library in tools/ through its links, and
#     includes none (the application layer and the front ends sit above the domain libraries);
#   - the forbidden table: batch and report reach no OpenGL/EGL, the estimator core neither the
#     renderer nor any other library of ours.
# A violation stops the configure with a message naming the edge (and, for an include, the
# file). tests/layering runs it on copies of the tree with an edge added. `cmake
# --graphviz=layers.dot build` draws the link graph.

set(CLUTTERSCOPE_LAYERS
  "datasets:"
  "batch:datasets"
  "notebooks_export:"
  "report:batch,datasets,estimator"
  "render:datasets"
  "visibility:datasets,render"
  "estimator:"
  "scene_estimation:datasets,render,visibility,estimator"
  "simulation:datasets,estimator"
  "jobs:datasets,batch,notebooks_export,report,render,visibility,estimator,scene_estimation,simulation"
  "cli:datasets,batch,notebooks_export,report,render,visibility,estimator,scene_estimation,simulation,jobs")

# Entries are "library:dependency,dependency".
# The libraries whose transitive links must not contain the given targets.
set(CLUTTERSCOPE_FORBIDDEN
  "batch:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render"
  "report:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render"
  "estimator:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render,clutterscope_datasets")

# "name:a,b" -> name, list a;b. (Not REGEX REPLACE: CMake re-anchors ^ after each match.)
function(_clutterscope_split_entry entry name_out list_out)
  string(FIND "${entry}" ":" colon)
  string(SUBSTRING "${entry}" 0 ${colon} name)
  math(EXPR rest "${colon} + 1")
  string(SUBSTRING "${entry}" ${rest} -1 items)
  string(REPLACE "," ";" items "${items}")
  set(${name_out} ${name} PARENT_SCOPE)
  set(${list_out} ${items} PARENT_SCOPE)
endfunction()

# An alias (clutterscope::x) resolved to its target (clutterscope_x); anything else unchanged.
function(_clutterscope_resolve item out)
  if(TARGET ${item})
    get_target_property(aliased ${item} ALIASED_TARGET)
    if(aliased)
      set(item ${aliased})
    endif()
  endif()
  set(${out} ${item} PARENT_SCOPE)
endfunction()

# The direct link items of `target` (LINK_LIBRARIES and INTERFACE_LINK_LIBRARIES, with
# $<LINK_ONLY:...> unwrapped and aliases resolved) in *out.
function(_clutterscope_direct_links target out)
  set(items)
  get_target_property(type ${target} TYPE)
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(linked ${target} LINK_LIBRARIES)
    if(linked)
      list(APPEND items ${linked})
    endif()
  endif()
  get_target_property(interface ${target} INTERFACE_LINK_LIBRARIES)
  if(interface)
    list(APPEND items ${interface})
  endif()
  set(result)
  foreach(item IN LISTS items)
    string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" item "${item}")
    _clutterscope_resolve(${item} item)
    list(APPEND result ${item})
  endforeach()
  list(REMOVE_DUPLICATES result)
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# The items `target` links PUBLIC (or INTERFACE): INTERFACE_LINK_LIBRARIES without the
# $<LINK_ONLY:...> entries a static library's PRIVATE links leave there.
function(_clutterscope_public_links target out)
  get_target_property(interface ${target} INTERFACE_LINK_LIBRARIES)
  set(result)
  foreach(item IN LISTS interface)
    if(item MATCHES "^\\$<LINK_ONLY:")
      continue()
    endif()
    _clutterscope_resolve(${item} item)
    list(APPEND result ${item})
  endforeach()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

function(_clutterscope_transitive_links target out)
  set(seen)
  set(todo ${target})
  while(todo)
    list(POP_FRONT todo current)
    if(NOT TARGET ${current})
      continue()
    endif()
    _clutterscope_direct_links(${current} links)
    foreach(link IN LISTS links)
      if(NOT link IN_LIST seen)
        list(APPEND seen ${link})
        list(APPEND todo ${link})
      endif()
    endforeach()
  endwhile()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# The source files of library `name` that exist at configure time (generated ones do not and
# include nothing of ours) and its headers: public (include/clutterscope/<name>/) and private
# (src/). *files_out: all of them; *public_out: the public headers.
function(_clutterscope_library_files name files_out public_out)
  get_target_property(dir clutterscope_${name} SOURCE_DIR)
  set(files)
  get_target_property(type clutterscope_${name} TYPE)
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(sources clutterscope_${name} SOURCES)
    foreach(source IN LISTS sources)
      if(NOT IS_ABSOLUTE "${source}")
        set(source "${dir}/${source}")
      endif()
      if(EXISTS "${source}")
        list(APPEND files "${source}")
      endif()
    endforeach()
  endif()
  file(GLOB_RECURSE public "${dir}/include/clutterscope/${name}/*")
  file(GLOB_RECURSE private "${dir}/src/*.hpp" "${dir}/src/*.h")
  list(APPEND files ${public} ${private})
  list(REMOVE_DUPLICATES files)
  set(${files_out} ${files} PARENT_SCOPE)
  set(${public_out} ${public} PARENT_SCOPE)
endfunction()

# The libraries of ours that `files` include, as "library|file|header" entries in *out.
function(_clutterscope_included_libraries files out)
  set(result)
  foreach(file IN LISTS files)
    file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]clutterscope/[A-Za-z0-9_]+/")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "[<\"](clutterscope/([A-Za-z0-9_]+)/[^>\"]*)" _ "${line}")
      list(APPEND result "${CMAKE_MATCH_2}|${file}|${CMAKE_MATCH_1}")
    endforeach()
  endforeach()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# Whether library `name` lives under tools/ (the application layer and the front ends).
function(_clutterscope_in_tools name out)
  get_target_property(dir clutterscope_${name} SOURCE_DIR)
  file(RELATIVE_PATH relative "${PROJECT_SOURCE_DIR}" "${dir}")
  if(relative MATCHES "^tools/")
    set(${out} TRUE PARENT_SCOPE)
  else()
    set(${out} FALSE PARENT_SCOPE)
  endif()
endfunction()

function(clutterscope_check_layering)
  set(names)
  set(ours)
  foreach(entry IN LISTS CLUTTERSCOPE_LAYERS)
    string(REGEX REPLACE ":.*" "" name "${entry}")
    list(APPEND names ${name})
    list(APPEND ours clutterscope_${name})
  endforeach()
  set(problems)
  foreach(entry IN LISTS CLUTTERSCOPE_LAYERS)
    _clutterscope_split_entry("${entry}" name allowed)
    if(NOT TARGET clutterscope_${name})
      list(APPEND problems "the table names clutterscope_${name}, which does not exist")
    endif()
  endforeach()
  if(problems)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "Layering check (cmake/CheckLayering.cmake) failed:\n  ${text}")
  endif()
  set(tools_libraries)
  foreach(name IN LISTS names)
    _clutterscope_in_tools(${name} in_tools)
    if(in_tools)
      list(APPEND tools_libraries ${name})
    endif()
  endforeach()

  foreach(entry IN LISTS CLUTTERSCOPE_LAYERS)
    _clutterscope_split_entry("${entry}" name allowed)
    _clutterscope_in_tools(${name} in_tools)
    # Links.
    _clutterscope_direct_links(clutterscope_${name} links)
    foreach(link IN LISTS links)
      if(link IN_LIST ours)
        string(REGEX REPLACE "^clutterscope_" "" linked_name "${link}")
        if(NOT linked_name IN_LIST allowed)
          list(APPEND problems "${name} links ${linked_name}, which the layer table does not allow")
        endif()
      endif()
    endforeach()
    if(NOT in_tools)
      _clutterscope_transitive_links(clutterscope_${name} reached)
      foreach(tool IN LISTS tools_libraries)
        if(clutterscope_${tool} IN_LIST reached)
          list(APPEND problems
               "${name} (outside tools/) reaches ${tool} (tools/) through its links, which it must not")
        endif()
      endforeach()
    endif()
    # Includes.
    _clutterscope_library_files(${name} files public_headers)
    _clutterscope_included_libraries("${files}" includes)
    foreach(include IN LISTS includes)
      string(REPLACE "|" ";" parts "${include}")
      list(GET parts 0 included)
      list(GET parts 1 file)
      list(GET parts 2 header)
      file(RELATIVE_PATH file "${PROJECT_SOURCE_DIR}" "${file}")
      if(included STREQUAL name)
        continue()
      endif()
      if(NOT included IN_LIST names)
        list(APPEND problems "${file}: ${name} includes <${header}>, of no library in the layer table")
      elseif(NOT included IN_LIST allowed)
        list(APPEND problems
             "${file}: ${name} includes <${header}>, of ${included}, which the layer table does not allow")
      endif()
      if(NOT in_tools AND included IN_LIST tools_libraries)
        list(APPEND problems
             "${file}: ${name} (outside tools/) includes <${header}>, of ${included} (tools/), which it must not")
      endif()
    endforeach()
    # PUBLIC only where a public header needs it.
    _clutterscope_included_libraries("${public_headers}" public_includes)
    set(publicly_included)
    foreach(include IN LISTS public_includes)
      string(REGEX REPLACE "\\|.*" "" included "${include}")
      list(APPEND publicly_included ${included})
    endforeach()
    _clutterscope_public_links(clutterscope_${name} public_links)
    foreach(link IN LISTS public_links)
      if(link IN_LIST ours)
        string(REGEX REPLACE "^clutterscope_" "" linked_name "${link}")
        if(NOT linked_name IN_LIST publicly_included)
          list(APPEND problems
               "${name} links ${linked_name} PUBLIC, but no public header of ${name} includes it: link it PRIVATE")
        endif()
      endif()
    endforeach()
  endforeach()
  foreach(entry IN LISTS CLUTTERSCOPE_FORBIDDEN)
    _clutterscope_split_entry("${entry}" name forbidden)
    _clutterscope_transitive_links(clutterscope_${name} reached)
    foreach(item IN LISTS forbidden)
      if(item IN_LIST reached)
        list(APPEND problems "${name} reaches ${item} through its links, which it must not")
      endif()
    endforeach()
  endforeach()
  if(problems)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "Layering check (cmake/CheckLayering.cmake) failed:\n  ${text}")
  endif()
  message(STATUS "Layering check: the libraries link and include as cmake/CheckLayering.cmake allows")
endfunction()
