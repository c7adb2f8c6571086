# Compiler flags shared by every target of the project (not exported to users).
add_library(deform_warnings INTERFACE)
target_compile_options(deform_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>
  # GCC 12 reports std::string concatenation at -O3 as overlapping memcpy (GCC bug 105651, a false positive).
  $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>
  # No fused multiply-add but where the source asks for one (lanes.hpp's mul_add, the SIMD copies' fma). GCC fuses
  # a·b − c·d on its own wherever the target has FMA (every aarch64 CPU): an exact zero such as the cross product of
  # two equal edges becomes the rounding error of one product, so that a degenerate triangle got a normal on aarch64
  # (test_normals), and results differed from x86-64's. On x86-64 the base ISA has no FMA: only the kernel copies
  # built with -mfma could fuse, and the lane kernels among them already say -ffp-contract=off themselves.
  $<$<AND:$<CXX_COMPILER_ID:GNU,Clang>,$<NOT:$<STREQUAL:${CMAKE_SYSTEM_PROCESSOR},x86_64>>>:-ffp-contract=off>)

if(DEFORM_SANITIZE)
  # _GLIBCXX_ASSERTIONS: libstdc++ checks operator[] and front()/back(), so an accessor's index precondition
  # (DeformerHierarchy::spec(l), l < lattice_count()) is checked here, where release builds take it on trust.
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
                      -D_GLIBCXX_ASSERTIONS)
  add_link_options(-fsanitize=address,undefined)
endif()

# Coverage-guided fuzzing (tests/fuzz): with Clang and the sanitizers, every target is compiled with libFuzzer's
# coverage instrumentation and the harnesses are linked with its driver.
include(CheckCXXSourceCompiles)
set(deform_fuzz_default OFF)
if(DEFORM_SANITIZE AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  set(deform_fuzz_default ON)
endif()
option(DEFORM_FUZZ "Build the libFuzzer harnesses of the readers (Clang)" ${deform_fuzz_default})
if(DEFORM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "DEFORM_FUZZ needs Clang (libFuzzer)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
