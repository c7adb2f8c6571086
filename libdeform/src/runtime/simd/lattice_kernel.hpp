#pragma once
// Internal: the arguments of the lattice evaluation kernel and its per-instruction-set entry points.
#include <cstddef>
#include <span>

#include "deform/runtime/lattice.hpp"
#include "lattice_cells.hpp"
namespace deform::detail {

// A LatticeEvaluateJob that passed its checks, over blocks [begin_block, end_block) of the binding; normals_in and
// normals_out both null or both set.
struct KernelArgs {
  const LatticeBinding* binding;
  const glm::vec3* control_points;
  glm::vec3* positions;  // null: normals only
  const glm::vec3* normals_in;
  glm::vec3* normals_out;
  const float* weights;  // null: positions and normals written, not blended
  std::size_t begin_block;
  std::size_t end_block;
  glm::mat3 jacobian_offset;  // LatticeEvaluateJob::normals_jacobian_offset
  glm::mat3 normal_basis;     // the binding's normal_basis · LatticeEvaluateJob::normals_in_to_binding
};

// One copy of lattice_kernel.inl per instruction set (isa.hpp): lattice_evaluate_portable.cpp,
// lattice_evaluate_avx2.cpp and lattice_evaluate_avx512.cpp (x86-64 builds, each compiled with its own flags),
// lattice_evaluate_neon.cpp (aarch64 builds), lattice_evaluate_simd128.cpp (WebAssembly builds with SIMD128).
void evaluate_lattice_portable(const KernelArgs& args);
#if defined(DEFORM_X86_KERNELS)
void evaluate_lattice_avx2(const KernelArgs& args);
void evaluate_lattice_avx512(const KernelArgs& args);
#endif
#if defined(DEFORM_NEON_KERNELS)
void evaluate_lattice_neon(const KernelArgs& args);  // lattice_evaluate_neon.cpp (aarch64 builds)
#endif
#if defined(DEFORM_SIMD128_KERNELS)
void evaluate_lattice_simd128(const KernelArgs& args);  // lattice_evaluate_simd128.cpp (WebAssembly builds)
#endif

// Scalar bases for one point. bernstein: B_0..n,n(t) in b[0..n] (de Casteljau's triangle), the degree n − 1 basis in
// `lower` when not null. bspline_basis: the 4 uniform cubic B-spline weights of a segment at t and (when `d` is not
// null) their derivatives in t.
void bernstein(int n, float t, float* b, float* lower) noexcept;
void bspline_basis(float t, float* b, float* d) noexcept;

}  // namespace deform::detail
