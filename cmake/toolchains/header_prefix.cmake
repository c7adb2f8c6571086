# Makes a package prefix of the header-only dependencies of the libraries and tests (GLM, nlohmann-json, Eigen,
# doctest, fast_float, dragonbox) from the host's Debian packages, for a cross build that has no prefix of its own
# (scripts/test's Windows and WebAssembly passes):
#   cmake -DPREFIX=build-mingw/prefix -P cmake/toolchains/header_prefix.cmake
# PREFIX/include holds links to the packages' header folders only (not the host's whole /usr/include, whose C
# library headers would shadow the target's), and PREFIX/lib/cmake/<package> a config file making the target the
# project finds (glm::glm, nlohmann_json::nlohmann_json,
# Eigen3::Eigen, doctest::doctest, FastFloat::fast_float, dragonbox::dragonbox). An engine's own prefix replaces it.
# With -DCOPY=ON the header folders are copied instead of linked (about 14 MB): a prefix of its own, as an engine's is,
# so that a check of which headers a build read (tests/engine) can tell it from the host's /usr/include. GCC names
# headers found through a link by their resolved path in its dependency files.
cmake_minimum_required(VERSION 3.25)
if(NOT PREFIX)
  message(FATAL_ERROR "usage: cmake -DPREFIX=<folder> -P header_prefix.cmake")
endif()
get_filename_component(prefix "${PREFIX}" ABSOLUTE)
set(HOST_INCLUDE /usr/include CACHE PATH "where the host's header-only packages are")
file(MAKE_DIRECTORY "${prefix}/include")
# package|version|target|header folder|include directory under PREFIX/include (Eigen's headers are in eigen3/Eigen,
# dragonbox's in dragonbox-1.1.3/dragonbox)
set(packages
  "glm|0.9.9.8|glm::glm|glm|"
  "nlohmann_json|3.11.2|nlohmann_json::nlohmann_json|nlohmann|"
  "Eigen3|3.4.0|Eigen3::Eigen|eigen3|/eigen3"
  "doctest|2.4.9|doctest::doctest|doctest|"
  "FastFloat|3.9.0|FastFloat::fast_float|fast_float|"
  "dragonbox|1.1.3|dragonbox::dragonbox|dragonbox-1.1.3|/dragonbox-1.1.3")
foreach(entry IN LISTS packages)
  string(REPLACE "|" ";" fields "${entry}")
  list(GET fields 0 package)
  list(GET fields 1 version)
  list(GET fields 2 target)
  list(GET fields 3 folder)
  list(GET fields 4 subfolder)
  if(NOT IS_DIRECTORY "${HOST_INCLUDE}/${folder}")
    message(FATAL_ERROR "${HOST_INCLUDE}/${folder} is missing: install the Debian package of ${package}")
  endif()
  file(REMOVE_RECURSE "${prefix}/include/${folder}")
  if(COPY)
    file(COPY "${HOST_INCLUDE}/${folder}" DESTINATION "${prefix}/include" FOLLOW_SYMLINK_CHAIN)
  else()
    file(CREATE_LINK "${HOST_INCLUDE}/${folder}" "${prefix}/include/${folder}" SYMBOLIC)
  endif()
  string(REPLACE "::" ";" names "${target}")
  file(WRITE "${prefix}/lib/cmake/${package}/${package}Config.cmake"
"# Made by header_prefix.cmake: the header-only ${package} from ${HOST_INCLUDE}/${folder}.
if(NOT TARGET ${target})
  add_library(${target} INTERFACE IMPORTED)
  set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES \"${prefix}/include${subfolder}\")
endif()
")
  file(WRITE "${prefix}/lib/cmake/${package}/${package}ConfigVersion.cmake"
"set(PACKAGE_VERSION ${version})
if(PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION)
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
else()
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
endif()
")
endforeach()
