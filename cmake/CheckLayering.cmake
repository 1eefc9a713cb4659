# The layering of the libraries, checked at every configure (issue 15; README "Architecture").
#
# clutterscope_check_layering() compares each library's direct links to libraries of ours with
# the table below (nothing more may appear), and walks every library's transitive links to
# check the rules that keep the layers apart: batch and report link no OpenGL/EGL, the
# estimator core links neither the renderer nor any other library of ours. A violation stops
# the configure with a message naming the edge. `cmake --graphviz=layers.dot build` draws the
# same graph.

set(CLUTTERSCOPE_LAYERS
  "datasets:"
  "batch:datasets"
  "notebooks_export:"
  "report:batch,notebooks_export,estimator"
  "render:datasets"
  "visibility:datasets,render,batch"
  "estimator:"
  "scene_estimation:datasets,render,visibility,estimator,batch,report"
  "simulation:datasets,scene_estimation,report"
  "jobs:datasets,batch,notebooks_export,report,render,visibility,estimator,scene_estimation,simulation"
  "cli:datasets,batch,notebooks_export,report,render,visibility,estimator,scene_estimation,simulation,jobs")

# Entries are "library:dependency,dependency".
# The libraries whose transitive links must not contain the given targets.
set(CLUTTERSCOPE_FORBIDDEN
  "batch:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render"
  "report:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render"
  "estimator:OpenGL::OpenGL,OpenGL::EGL,OpenGL::GL,clutterscope_render,clutterscope_datasets")

# The direct link items of `target` (LINK_LIBRARIES and INTERFACE_LINK_LIBRARIES, with
# $<LINK_ONLY:...> unwrapped and aliases resolved) in *out.
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
    if(TARGET ${item})
      get_target_property(aliased ${item} ALIASED_TARGET)
      if(aliased)
        set(item ${aliased})
      endif()
    endif()
    list(APPEND result ${item})
  endforeach()
  list(REMOVE_DUPLICATES result)
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

function(clutterscope_check_layering)
  set(ours)
  foreach(entry IN LISTS CLUTTERSCOPE_LAYERS)
    string(REGEX REPLACE ":.*" "" name "${entry}")
    list(APPEND ours clutterscope_${name})
  endforeach()
  set(problems)
  foreach(entry IN LISTS CLUTTERSCOPE_LAYERS)
    _clutterscope_split_entry("${entry}" name allowed)
    if(NOT TARGET clutterscope_${name})
      list(APPEND problems "the table names clutterscope_${name}, which does not exist")
      continue()
    endif()
    _clutterscope_direct_links(clutterscope_${name} links)
    foreach(link IN LISTS links)
      if(link IN_LIST ours)
        string(REGEX REPLACE "^clutterscope_" "" linked_name "${link}")
        if(NOT linked_name IN_LIST allowed)
          list(APPEND problems "${name} links ${linked_name}, which the layer table does not allow")
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
  message(STATUS "Layering check: the libraries link as cmake/CheckLayering.cmake allows")
endfunction()
