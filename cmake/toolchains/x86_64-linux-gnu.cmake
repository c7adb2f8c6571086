# Native x86-64 Linux with the system's GCC, the way an engine pins its own build: packages (GLM, nlohmann-json, and
# any other find_package) come only from the prefixes given in CMAKE_PREFIX_PATH, never from the host's /usr, so
# that the headers an engine ships with are the ones it builds with:
#   cmake -S <engine> -B build-x86_64 --toolchain cmake/toolchains/x86_64-linux-gnu.cmake \
#     -DCMAKE_PREFIX_PATH=<the engine's prefix>
# Not a cross build (no CMAKE_SYSTEM_NAME): programs run as they are, and the C library and system headers are the
# host's. tests/engine builds with it (docs/platforms.md).
set(CMAKE_C_COMPILER gcc)
set(CMAKE_CXX_COMPILER g++)

# Each prefix is a root of its own, and the only place packages are looked for. Libraries and headers outside a
# package (the C library, threads) stay the system's.
set(CMAKE_FIND_ROOT_PATH ${CMAKE_PREFIX_PATH})
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
