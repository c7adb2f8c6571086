#pragma once
// Internal: the corner angle shared by the vertex-normal code, and the per-instruction-set entry points of the
// VertexNormalsJob kernel (mesh_normals_kernel.inl; see normals.hpp).
#include <cstddef>
#include <cstdint>
#include <numbers>

#include <glm/glm.hpp>

#include "deform/runtime/normals.hpp"
#include "lanes.hpp"

namespace deform::detail {

// atan(t) ≈ t · P(t²) on [0, 1], P of degree 7 in t²: minimax for the absolute error, fitted for libdeform by Remez
// exchange in long double. Max error 3.7e-8 in exact arithmetic, 1.4e-7 evaluated in float (checked on every float of
// [0, 1]).
inline constexpr float atan_coefficients[8] = {9.999993443e-01f,  -3.332985938e-01f, 1.994656622e-01f,
                                               -1.390862912e-01f, 9.642197192e-02f,  -5.591232702e-02f,
                                               2.186295763e-02f,  -4.054567311e-03f};

// atan2(y, x) for y > 0: the angle at a triangle corner whose edges e1, e2 give y = |e1 × e2| and x = e1 · e2, in
// (0, π), within 5e-7 rad of the exact angle (polynomial, the rounding of the ratio and of π). Cost: one division and
// 9 multiply-adds; its conditions are selects, so a loop of it over lanes vectorises. Static: each instruction set's
// copy of the kernel keeps its own instance.
static inline float corner_angle(float y, float x) noexcept {
  constexpr float pi = std::numbers::pi_v<float>;
  const float abs_x = x < 0.0f ? -x : x;
  const float t = (abs_x < y ? abs_x : y) / (abs_x < y ? y : abs_x);  // in [0, 1]
  const float t2 = t * t;
  float p = mul_add(t2, atan_coefficients[7], atan_coefficients[6]);
  DEFORM_UNROLL
  for (int k = 5; k >= 0; --k) p = mul_add(p, t2, atan_coefficients[k]);
  const float atan_t = p * t;
  const float from_axis = abs_x < y ? pi / 2 - atan_t : atan_t;  // atan2(y, |x|)
  return x < 0.0f ? pi - from_axis : from_axis;
}

// A VertexNormalsJob that passed its checks, over points [begin, end).
struct NormalsKernelArgs {
  const VertexNormalsBinding* binding;
  const glm::vec3* positions;
  glm::vec3* normals;
  glm::vec4* scratch;  // per point, then per corner
  std::size_t begin;
  std::size_t end;
};

// The normals of points [begin, end): the triangles at them (angle-weighted unit normals per corner, into the
// corners' scratch slots), then each point's corners summed, normalised and written to its render vertices.
// One copy per instruction set (isa.hpp): mesh_normals_portable.cpp, mesh_normals_avx2.cpp and
// mesh_normals_avx512.cpp (x86-64 builds, each compiled with its own flags).
void vertex_normals_portable(const NormalsKernelArgs& args) noexcept;
#if defined(DEFORM_X86_KERNELS)
void vertex_normals_avx2(const NormalsKernelArgs& args) noexcept;
void vertex_normals_avx512(const NormalsKernelArgs& args) noexcept;
#endif
#if defined(DEFORM_NEON_KERNELS)
void vertex_normals_neon(const NormalsKernelArgs& args) noexcept;  // mesh_normals_neon.cpp (aarch64 builds)
#endif
#if defined(DEFORM_SIMD128_KERNELS)
void vertex_normals_simd128(const NormalsKernelArgs& args) noexcept;  // mesh_normals_simd128.cpp (WebAssembly)
#endif

// Below this length a point's sum of contributions (radians times unit normals) has cancelled: a point between
// opposite faces, whose direction would be rounding noise.
inline constexpr float cancelled_normal_sum = 1e-5f;

}  // namespace deform::detail
