# Cross build for aarch64 Linux with Debian's g++-aarch64-linux-gnu; ctest runs the tests under qemu-user
# (Debian's qemu-user). Usage (docs/platforms.md):
#   cmake -S . -B build-aarch64 --toolchain cmake/toolchains/aarch64-linux-gnu.cmake \
#     -DCMAKE_PREFIX_PATH=<a prefix holding GLM, nlohmann-json (and Eigen, doctest for the tests)> ...
# The header-only packages are the same files for every CPU: an engine points CMAKE_PREFIX_PATH at its own prefix;
# without one, cmake/toolchains/header_prefix.cmake makes one from the host's Debian packages. Never the host's
# /usr/include itself: its x86-64 C library headers would shadow the target's.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/usr/aarch64-linux-gnu)

# Libraries and packages come from the target's root and the prefixes in CMAKE_PREFIX_PATH (each a root of its own)
# only, programs (nm, python3) from the host.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu ${CMAKE_PREFIX_PATH})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config too: only the target's .pc files (a host package's would put x86-64 libraries on the link line).
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/aarch64-linux-gnu/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
