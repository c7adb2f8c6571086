#pragma once
// Internal: the per-instruction-set entry points of the DirectDeltaMushJob kernel (ddm_kernel.inl; see
// direct_delta_mush.hpp).
#include <cstddef>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/direct_delta_mush.hpp"

namespace deform::detail {

// A DirectDeltaMushJob that passed its checks, over points [begin, end). The optional spans are null when empty.
struct DdmKernelArgs {
  const DirectDeltaMushBinding* binding;
  const glm::mat4* palette;
  const glm::vec3* in_positions;  // or null: the rest points
  const glm::vec3* in_normals;    // null exactly when out_normals is
  glm::vec3* out_positions;
  glm::vec3* out_normals;
  glm::quat* out_rotations;  // or null
  std::size_t begin;
  std::size_t end;
};

// A DirectDeltaMushReducedJob that passed its checks, over points [begin, end). The optional spans are null when empty.
struct DdmReducedKernelArgs {
  const DirectDeltaMushReducedBinding* binding;
  const glm::mat4* palette;
  const DualQuat* dual_quats;     // the same palette's rotations (`real`)
  const glm::vec3* in_positions;  // or null: the rest points
  const glm::vec3* in_normals;    // null exactly when out_normals is
  glm::vec3* out_positions;
  glm::vec3* out_normals;
  glm::quat* out_rotations;  // or null
  std::size_t begin;
  std::size_t end;
};

// Newton steps every point takes (ddm_kernel.inl), then each point whose last step turned it by 1e-3 rad or more
// (angle² ≥ ddm_settled) takes more, up to 16 in all, on its own (the others in its block keep theirs), so that its
// result does not depend on its neighbours'. Newton converges quadratically: after a step of 1e-3 rad what is left is
// of the order of 1e-6 rad, below what the tests against the double-precision reference see (docs/performance.md,
// 2026-11-28 04:45 UTC: the tests' errors unchanged from the 1e-4 rad rule, a third step in fewer blocks).
inline constexpr int ddm_fixed_steps = 2;
inline constexpr float ddm_settled = 1e-6f;

// One copy per instruction set (isa.hpp), each compiled with its own flags: ddm_portable.cpp, and ddm_avx2.cpp,
// ddm_avx512.cpp (x86-64), ddm_neon.cpp (aarch64), ddm_simd128.cpp (WebAssembly with SIMD128).
// The reduced job's kernel is in the same files (direct_delta_mush_reduced_*).
void direct_delta_mush_portable(const DdmKernelArgs& args) noexcept;
void direct_delta_mush_reduced_portable(const DdmReducedKernelArgs& args) noexcept;
#if defined(DEFORM_X86_KERNELS)
void direct_delta_mush_avx2(const DdmKernelArgs& args) noexcept;
void direct_delta_mush_avx512(const DdmKernelArgs& args) noexcept;
void direct_delta_mush_reduced_avx2(const DdmReducedKernelArgs& args) noexcept;
void direct_delta_mush_reduced_avx512(const DdmReducedKernelArgs& args) noexcept;
#endif
#if defined(DEFORM_NEON_KERNELS)
void direct_delta_mush_neon(const DdmKernelArgs& args) noexcept;
void direct_delta_mush_reduced_neon(const DdmReducedKernelArgs& args) noexcept;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
void direct_delta_mush_simd128(const DdmKernelArgs& args) noexcept;
void direct_delta_mush_reduced_simd128(const DdmReducedKernelArgs& args) noexcept;
#endif

}  // namespace deform::detail
