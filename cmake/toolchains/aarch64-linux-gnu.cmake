# Cross build for aarch64 Linux with Debian's g++-aarch64-linux-gnu; ctest runs the tests under qemu-user
# (Debian's qemu-user). Usage (docs/platforms.md):
#   cmake -S . -B build-aarch64 --toolchain cmake/toolchains/aarch64-linux-gnu.cmake -DDEFORM_LIBRARY_ONLY=ON \
#     -DDEFORM_BUILD_TESTS=ON -DDEFORM_BUILD_IMPORT=OFF -DDEFORM_BUILD_GPU=OFF
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/usr/aarch64-linux-gnu)

# Libraries and packages come from the target's root only, programs (nm, python3) from the host.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config too: only the target's .pc files (a host package's would put x86-64 libraries on the link line).
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/aarch64-linux-gnu/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# The header-only packages the tested layers need (GLM, nlohmann-json, doctest, Eigen, fast_float, dragonbox) are the
# same files for every CPU, so the host's Debian packages serve. They are taken explicitly, never by searching the
# host: each gets a package configuration of its own in a small prefix under the build folder whose include/ holds
# links to the package's headers alone. Putting the host's /usr/include itself on the include path would let its x86-64 C library
# headers shadow the target's. An engine points the same six at its own prefix instead (CMAKE_PREFIX_PATH).
set(deform_host_headers "${CMAKE_BINARY_DIR}/host-headers")
file(MAKE_DIRECTORY "${deform_host_headers}/include")
foreach(entry glm nlohmann doctest eigen3 fast_float dragonbox-1.1.3)
  if(EXISTS "/usr/include/${entry}" AND NOT EXISTS "${deform_host_headers}/include/${entry}")
    file(CREATE_LINK "/usr/include/${entry}" "${deform_host_headers}/include/${entry}" SYMBOLIC)
  endif()
endforeach()
file(GLOB deform_dragonbox_version /usr/lib/*/cmake/dragonbox-*/dragonboxConfigVersion.cmake)
# package name, imported target, include folder under the prefix, the host's version file
set(deform_host_packages
  "glm|glm::glm|include|/usr/share/cmake/glm/glmConfigVersion.cmake"
  "nlohmann_json|nlohmann_json::nlohmann_json|include|/usr/share/cmake/nlohmann_json/nlohmann_jsonConfigVersion.cmake"
  "doctest|doctest::doctest|include|/usr/lib/cmake/doctest/doctestConfigVersion.cmake"
  "Eigen3|Eigen3::Eigen|include/eigen3|/usr/share/eigen3/cmake/Eigen3ConfigVersion.cmake"
  "FastFloat|FastFloat::fast_float|include|/usr/lib/cmake/FastFloat/FastFloatConfigVersion.cmake"
  "dragonbox|dragonbox::dragonbox|include/dragonbox-1.1.3|${deform_dragonbox_version}")
foreach(package IN LISTS deform_host_packages)
  string(REPLACE "|" ";" fields "${package}")
  list(GET fields 0 name)
  list(GET fields 1 target)
  list(GET fields 2 include)
  list(GET fields 3 version_file)
  set(config "if(NOT TARGET ${target})\n  add_library(${target} INTERFACE IMPORTED)\n  set_target_properties(${target} "
             "PROPERTIES INTERFACE_INCLUDE_DIRECTORIES \"${deform_host_headers}/${include}\")\nendif()\n")
  file(CONFIGURE OUTPUT "${deform_host_headers}/${name}/${name}Config.cmake" CONTENT "${config}" @ONLY)
  file(CONFIGURE OUTPUT "${deform_host_headers}/${name}/${name}ConfigVersion.cmake"
       CONTENT "include(\"${version_file}\")\n" @ONLY)
  set(${name}_DIR "${deform_host_headers}/${name}" CACHE PATH "${name}'s package configuration (host headers)")
endforeach()
