# WebAssembly with Debian's emscripten (3.1.6), the test executables run by ctest under Node.js:
#   cmake -DPREFIX=build-wasm/prefix -P cmake/toolchains/header_prefix.cmake
#   cmake -S . -B build-wasm --toolchain cmake/toolchains/wasm32-emscripten.cmake \
#     -DCMAKE_PREFIX_PATH=<a prefix holding GLM, nlohmann-json, doctest, fast_float and dragonbox> ...
# Emscripten's own platform file does the rest (compilers, the sysroot as the only root searched). What this file
# adds is what libdeform's libraries and tests need from it:
# - threads (ThreadPool): -pthread, with a pool of 8 workers started before main, since a Web Worker started later
#   only begins once the main thread returns to the event loop, which a parallel_for waiting for it never does;
# - exceptions (every reader throws deform::Error): -fexceptions, emscripten's JavaScript-based ones (its
#   WebAssembly exceptions went uncaught in a -pthread build of 3.1.6 under Node.js 20);
# - files (the tests read tests/data and write to the temporary folder): NODERAWFS, Node.js's file system as is.
#   A program for a browser links without it (and without EXIT_RUNTIME): remove those from the linker flags.
# The SIMD128 copies of the kernels are a CMake option, DEFORM_WASM_SIMD128 (docs/platforms.md).
include(/usr/share/emscripten/cmake/Modules/Platform/Emscripten.cmake)

set(CMAKE_C_FLAGS_INIT "-pthread -fexceptions")
set(CMAKE_CXX_FLAGS_INIT "-pthread -fexceptions")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-pthread -fexceptions -sPTHREAD_POOL_SIZE=8 -sALLOW_MEMORY_GROWTH=1 \
-Wno-pthreads-mem-growth -sNODERAWFS=1 -sEXIT_RUNTIME=1")
# emcc runs its JavaScript optimiser with Node.js, which needs Debian's node-acorn from /usr/share/nodejs: a Node.js
# that is not Debian's own does not look there.
set(CMAKE_C_LINKER_LAUNCHER env NODE_PATH=/usr/share/nodejs)
set(CMAKE_CXX_LINKER_LAUNCHER env NODE_PATH=/usr/share/nodejs)
# The test programs under Node.js. Emscripten 3.1.6 loads its .wasm with fetch() wherever fetch exists, and Node.js
# 18 and later have one that takes no file paths: --no-experimental-fetch makes it read the file instead.
find_program(DEFORM_NODE NAMES node nodejs REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR ${DEFORM_NODE};--no-experimental-fetch CACHE STRING "runs a test program" FORCE)

# Packages from the sysroot and from the prefixes in CMAKE_PREFIX_PATH (each a root of its own), never the host's.
list(APPEND CMAKE_FIND_ROOT_PATH ${CMAKE_PREFIX_PATH})
# pkg-config too: only the sysroot's .pc files (the host's stb.pc, found by tests/CMakeLists.txt, would put -lstb,
# an x86-64 library, on a test's link line).
set(ENV{PKG_CONFIG_LIBDIR} "${EMSCRIPTEN_SYSROOT}/local/lib/pkgconfig:${EMSCRIPTEN_SYSROOT}/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
