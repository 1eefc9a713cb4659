# `cmake --install` and CPack (issue 27): the executable, every library of ours but the CLI's
# (a front end, whose header needs CLI11), their public headers, the bundled sample datasets and
# a CMake package: `find_package(clutterscope CONFIG)` gives clutterscope::<library>, with the
# third-party packages they link found by clutterscopeConfig.cmake.
#
# Two components, two Debian packages: `runtime` (the executable, the samples and — where built —
# the Python module) depends only on Debian's runtime libraries, Mesa's EGL and llvmpipe
# included, so a machine without a GPU renders; `development` (static libraries, headers, the
# CMake package) adds the -dev packages a consumer compiles against.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CLUTTERSCOPE_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/clutterscope")

function(clutterscope_install)
  get_property(libraries GLOBAL PROPERTY CLUTTERSCOPE_LIBRARIES)
  get_property(include_dirs GLOBAL PROPERTY CLUTTERSCOPE_INCLUDE_DIRS)
  list(REMOVE_ITEM libraries cli)
  list(REMOVE_ITEM include_dirs "${PROJECT_SOURCE_DIR}/tools/cli/include")
  set(targets)
  foreach(library IN LISTS libraries)
    list(APPEND targets clutterscope_${library})
  endforeach()

  install(TARGETS clutterscope RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}" COMPONENT runtime)
  install(DIRECTORY "${PROJECT_SOURCE_DIR}/datasets/samples/"
          DESTINATION "${CMAKE_INSTALL_DATADIR}/clutterscope/samples" COMPONENT runtime)

  install(TARGETS ${targets} EXPORT clutterscopeTargets
          ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}" COMPONENT development
          INCLUDES DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
  foreach(dir IN LISTS include_dirs)
    install(DIRECTORY "${dir}/" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}" COMPONENT development)
  endforeach()
  install(EXPORT clutterscopeTargets NAMESPACE clutterscope::
          DESTINATION "${CLUTTERSCOPE_INSTALL_CMAKEDIR}" COMPONENT development)
  configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/clutterscopeConfig.cmake.in"
    "${PROJECT_BINARY_DIR}/clutterscopeConfig.cmake"
    INSTALL_DESTINATION "${CLUTTERSCOPE_INSTALL_CMAKEDIR}")
  write_basic_package_version_file("${PROJECT_BINARY_DIR}/clutterscopeConfigVersion.cmake"
    COMPATIBILITY SameMinorVersion)
  install(FILES "${PROJECT_BINARY_DIR}/clutterscopeConfig.cmake"
                "${PROJECT_BINARY_DIR}/clutterscopeConfigVersion.cmake"
                "${PROJECT_SOURCE_DIR}/cmake/FindOpenCVModules.cmake"
          DESTINATION "${CLUTTERSCOPE_INSTALL_CMAKEDIR}" COMPONENT development)
endfunction()

# `cpack -G DEB` in the build folder: clutterscope_<version>_<arch>.deb (runtime) and
# clutterscope-dev_<version>_<arch>.deb. The runtime package's library dependencies come from
# dpkg-shlibdeps over the executable; Mesa's EGL vendor and llvmpipe are loaded at run time
# (libglvnd dlopens them), so they are named by hand.
set(CPACK_PACKAGE_NAME clutterscope)
set(CPACK_PACKAGE_VENDOR "clutterscope")
set(CPACK_PACKAGE_CONTACT "clutterscope developers <clutterscope@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Visibility and pose-uncertainty analysis of cluttered scenes (BOP datasets)")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime development)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME clutterscope)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "libegl-mesa0, libgl1-mesa-dri")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION science)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_NAME clutterscope-dev)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_DEPENDS
    "clutterscope (= ${PROJECT_VERSION}), libeigen3-dev, nlohmann-json3-dev, libopencv-core-dev, libopencv-imgproc-dev, libopencv-imgcodecs-dev, libassimp-dev, libegl-dev, libgl-dev")
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_SECTION libdevel)
include(CPack)
