# Debian splits OpenCV into per-module -dev packages; only the libopencv-dev meta package
# (which pulls VTK, MPI and the contrib modules) ships OpenCVConfig.cmake. Use the config when
# present, else define imported targets opencv_<module> from the per-module packages.
find_package(OpenCV QUIET COMPONENTS ${OpenCVModules_FIND_COMPONENTS})
if(OpenCV_FOUND)
  set(OpenCVModules_FOUND TRUE)
  return()
endif()

find_path(OpenCVModules_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
set(OpenCVModules_FOUND TRUE)
if(NOT OpenCVModules_INCLUDE_DIR)
  set(OpenCVModules_FOUND FALSE)
endif()
foreach(module ${OpenCVModules_FIND_COMPONENTS})
  find_library(OpenCVModules_${module}_LIBRARY opencv_${module})
  if(NOT OpenCVModules_${module}_LIBRARY)
    set(OpenCVModules_FOUND FALSE)
    message(SEND_ERROR "OpenCV module ${module} not found (install libopencv-${module}-dev)")
  elseif(NOT TARGET opencv_${module})
    add_library(opencv_${module} UNKNOWN IMPORTED)
    set_target_properties(opencv_${module} PROPERTIES
      IMPORTED_LOCATION "${OpenCVModules_${module}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${OpenCVModules_INCLUDE_DIR}")
  endif()
endforeach()
if(OpenCVModules_FIND_REQUIRED AND NOT OpenCVModules_FOUND)
  message(FATAL_ERROR "OpenCV headers or modules not found: run scripts/install-deps.sh")
endif()
