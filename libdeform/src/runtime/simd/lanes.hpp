#pragma once
// Internal: lane storage and helpers for the block kernels (lattice_kernel.inl, mesh_normals_kernel.inl), standard
// C++. A kernel works on blocks of N elements (vertices, triangles) in structure-of-arrays form, Lanes<N> per value,
// and writes its arithmetic as loops over the lanes around scalar code; GCC and Clang turn each such loop into vector
// instructions at -O3 for whatever target the including file is compiled for (SSE2 for the portable copies on x86-64,
// AVX2 or AVX-512 for the copies built with those flags, NEON on ARM); other compilers get correct scalar loops.
//
// Why loops around scalar code rather than element-wise operators on Lanes: GCC keeps a Lanes object in memory (it
// does not split arrays into vector registers), so a chain of operators stores and reloads every intermediate, and a
// running sum waits for the store buffer at every step. A loop over the lanes whose body is a whole computation keeps
// its scalars, hence its vectors, in registers. Measured on the lattice kernel: 2× (AVX2) to 6× (with normals).
//
// Everything here has internal linkage on purpose: each kernel copy compiles it with its own -m flags, and a shared
// (inline, external) definition could be merged at link time with a copy that uses instructions the CPU lacks.
#include <cmath>

// DEFORM_UNROLL (portable.hpp) before the fixed-length loops inside a loop over the lanes: the vectoriser only takes
// such a loop when nothing but straight-line code is left in it.
#include "deform/runtime/portable.hpp"

namespace {

// a·b + c, fused (one rounding) in the copies compiled for FMA hardware, else a multiply and an add. The kernel files
// are compiled with -ffp-contract=off and fuse only where this is written: the compiler's own contraction depends on
// the shape of the code around an expression, so that the same sum could round differently in two instantiations (a
// lattice's positions with and without normals) or two loops of one copy. The portable copies define
// DEFORM_LANES_UNFUSED and never fuse, although aarch64's baseline has FMA: fusing is what the NEON copy adds there,
// as the AVX2 copy does on x86-64, and the portable copy rounds each product and sum alike on every CPU.
inline float mul_add(float a, float b, float c) noexcept {
#if (defined(__FMA__) || defined(__ARM_FEATURE_FMA)) && !defined(DEFORM_LANES_UNFUSED)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// N floats, one per lane.
template <int N>
struct Lanes {
  float lane[N];

  // Copies, fills, loads and stores are lane loops too, so that they become vector moves of the kernel's width: an
  // aggregate copy or a memcpy is expanded by GCC in 16-byte pieces, and a 32- or 64-byte load of what 16-byte stores
  // just wrote cannot be forwarded from the store buffer (a stall of a dozen cycles per vector; it cost the AVX2
  // lattice kernel half its speed). The files including this are compiled so that GCC keeps these loops loops
  // (CMakeLists.txt).
  Lanes() noexcept = default;
  Lanes(const Lanes& b) noexcept {
    for (int i = 0; i < N; ++i) lane[i] = b.lane[i];
  }
  Lanes& operator=(const Lanes& b) noexcept {
    for (int i = 0; i < N; ++i) lane[i] = b.lane[i];
    return *this;
  }

  static Lanes filled(float x) noexcept {
    Lanes r;
    for (int i = 0; i < N; ++i) r.lane[i] = x;
    return r;
  }
  // N consecutive floats from p (no alignment needed).
  static Lanes load(const float* p) noexcept {
    Lanes r;
    for (int i = 0; i < N; ++i) r.lane[i] = p[i];
    return r;
  }

  float& operator[](int i) noexcept { return lane[i]; }
  float operator[](int i) const noexcept { return lane[i]; }
};

}  // namespace
