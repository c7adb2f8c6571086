# Windows x86-64 with Debian's mingw-w64 (g++-mingw-w64-x86-64-posix), the tests run under wine (wine64):
#   cmake -S . -B build-mingw -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/x86_64-w64-mingw32.cmake \
#         -DCMAKE_PREFIX_PATH=<a prefix holding GLM, nlohmann-json and doctest for this target>
# The posix-threads variant of the compilers: the win32 one has no std::thread. libgcc, libstdc++ and winpthread are
# linked statically, so an .exe runs under wine (or on Windows) without the compiler's DLLs beside it.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(deform_mingw x86_64-w64-mingw32)
set(CMAKE_C_COMPILER ${deform_mingw}-gcc-posix)
set(CMAKE_CXX_COMPILER ${deform_mingw}-g++-posix)
set(CMAKE_RC_COMPILER ${deform_mingw}-windres)
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static -static-libgcc -static-libstdc++")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-static-libgcc -static-libstdc++")

# Test executables (ctest, try_run) run under wine: Debian's `wine` starts a 64-bit program with its wine64 loader;
# elsewhere the loader may be on PATH as wine64.
find_program(DEFORM_WINE NAMES wine wine64)
if(DEFORM_WINE)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${DEFORM_WINE})
endif()

# Libraries, headers and packages only from the target's root and the prefixes given in CMAKE_PREFIX_PATH (each a
# root of its own), never from the host's /usr; programs (wine, nm) from the host.
set(CMAKE_FIND_ROOT_PATH /usr/${deform_mingw} ${CMAKE_PREFIX_PATH})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config searches the target's folder only (the host's .pc files name host headers and libraries).
set(ENV{PKG_CONFIG_LIBDIR} /usr/${deform_mingw}/lib/pkgconfig)
set(ENV{PKG_CONFIG_SYSROOT_DIR} "")
