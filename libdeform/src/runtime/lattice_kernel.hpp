#pragma once
// Internal: the arguments of the lattice evaluation kernel and its per-instruction-set entry points.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#include "deform/runtime/lattice.hpp"
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

}  // namespace deform::detail

#include <vector>
#include "runtime/finite.hpp"

namespace deform::detail {

// A point chosen for a lattice: its index, the first control point of its cell (0 for Bézier) and its parameters
// within the cell.
struct BoundVertex {
  std::uint32_t vertex;
  std::uint32_t first_point;
  glm::vec3 param;
};

// The candidates (all points when `all`) whose (u, v, w) under `to_lattice` lies in [0, 1]³, with those parameters
// in `param`. Throws deform::Error for a candidate out of range or a non-finite position.
std::vector<BoundVertex> collect_inside(const LatticeFrame& frame, std::span<const glm::vec3> positions,
                                        std::span<const std::uint32_t> candidates, bool all,
                                        const glm::mat4& to_lattice);

// Groups the vertices into blocks (stable by first_point) and fills a binding.
// `parameter_scale` = d(cell parameter)/d(u, v, w) per axis (1 for Bézier, the cell counts for a B-spline).
LatticeBinding make_binding(LatticeKind kind, glm::ivec3 point_counts, const LatticeFrame& frame,
                            glm::vec3 parameter_scale, const glm::mat4& to_lattice, std::vector<BoundVertex> list);

// Scalar bases for one point. bernstein: B_0..n,n(t) in b[0..n] (de Casteljau's triangle), the degree n − 1 basis in
// `lower` when not null. bspline_basis: the 4 uniform cubic B-spline weights of a segment at t and (when `d` is not
// null) their derivatives in t. cell_of: the cell of x ∈ [0, 1] among `cells` (clamped) and t within it.
void bernstein(int n, float t, float* b, float* lower) noexcept;
void bspline_basis(float t, float* b, float* d) noexcept;
// (The last cell owns x = 1; parameters outside [0, 1] stay on the border cells' polynomials.)
inline int cell_of(float x, int cells, float& t) noexcept {
  const float s = x * static_cast<float>(cells);
  const int c = std::clamp(static_cast<int>(std::floor(s)), 0, cells - 1);
  t = s - static_cast<float>(c);
  return c;
}

// Cofactor matrix det(A)·A^-T (maps normals through A up to a positive factor when det A > 0). The rows of det(A)·A⁻¹
// are the cross products of A's columns, so they are the columns of det(A)·A^-T.
inline glm::mat3 cofactor(const glm::mat3& a) noexcept {
  return glm::mat3(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]), glm::cross(a[0], a[1]));
}

}  // namespace deform::detail
