#pragma once
// Instruction sets of the per-frame kernels (skinning, lattice evaluation, vertex normals, Direct Delta Mush), one
// scheme for all of them. Each kernel exists as a portable copy (standard C++, every compiler and CPU) and, in builds
// for x86-64 with GCC or Clang, as copies compiled for AVX2 + FMA and for AVX-512, in builds for aarch64 with GCC or
// Clang as a NEON copy, in WebAssembly builds with DEFORM_WASM_SIMD128 as a SIMD128 copy (docs/platforms.md); the job's
// `isa` field picks one. `automatic` runs the widest copy this CPU supports; the others force a copy (tests compare
// them, benchmarks measure them), and a job refuses to run a forced copy the CPU or the build lacks.
#include <cstdint>

#include "deform/runtime/export.hpp"
namespace deform {

enum class Isa : std::uint8_t {
  automatic,  // the widest available here: isa_best()
  portable,   // standard C++ auto-vectorised for the build's baseline target (SSE2 on x86-64); always available
  avx2,       // AVX2 + FMA (x86-64)
  avx512,     // AVX-512 F, DQ, VL and BW (x86-64)
  neon,       // Advanced SIMD with fused multiply-add (aarch64, where every CPU has it)
  simd128,    // WebAssembly SIMD128 (chosen when the module is built: WebAssembly has no run-time feature query)
};

// True when the copies for `isa` are in this build and the CPU runs them (automatic and portable always are). Reads
// the CPU's features once (the first call, thread-safe) and a cached flag after that.
DEFORM_RUNTIME_API bool isa_available(Isa isa) noexcept;
// What `automatic` runs here: neon on aarch64; simd128 in a WebAssembly build with it; avx512, else avx2, else portable
// on x86-64; else portable.
DEFORM_RUNTIME_API Isa isa_best() noexcept;
// "automatic", "portable", "avx2", "avx512", "neon", "simd128"; "unknown" for a value outside the enum.
DEFORM_RUNTIME_API const char* isa_name(Isa isa) noexcept;

}  // namespace deform
