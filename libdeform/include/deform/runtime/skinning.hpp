#pragma once
// Skinning: a mesh deformed by a weighted bone palette, linear blend (LBS) or dual quaternion (DQS) — the per-frame
// kernel of a rigged character (thesis §6, eq. 13; Kavan, Collins, Žára, O'Sullivan 2007).
//
// The shape is ozz-animation's SkinningJob: a SkinningJob points at the caller's buffers (spans with byte strides, so
// AoS vertex structs and separate SoA arrays work alike), validate() says whether the call is well formed and run()
// deforms. Nothing is allocated, nothing is locked, nothing is read outside the spans.
//
// Per frame:  world matrices (compute_world_matrices) -> palette T_C = T_W · T_B⁻¹ (compute_skinning_palette)
//             -> for DQS, compute_dual_quat_palette once -> SkinningJob::run.
// Influences: four per vertex (bone index + weight). Models with more keep the four strongest and renormalise at
// import (the importer and read_skw do). The kernels divide by each vertex's weight sum, so weights that do not sum to
// one are renormalised on the fly; a weight sum of zero is invalid (validate() rejects it).
// Normals: LBS maps each normal by the cofactor of the blended 3×3 matrix (det · M⁻ᵀ: the inverse-transpose rule,
// exact for non-uniform scale and equal in direction to M itself for a rotation), DQS by the blended rotation (and
// the inverse-transpose of the blended scale, see DualQuat); both renormalise the result (a zero normal stays zero).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_precision.hpp>

#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
namespace deform {

class ThreadPool;

enum class SkinningMethod : std::uint8_t {
  lbs,  // linear blend skinning: Σ wᵢ Mᵢ applied to the vertex (fast; candy-wrapper collapse under twist)
  dqs,  // dual quaternion skinning: normalised Σ ±wᵢ q̂ᵢ (keeps volume under twist)
};

// One bone of a DQS palette: the palette matrix M = [R | t] · S split into a unit dual quaternion for the rigid part
// [R | t] (`real` = R, `dual` = ½ (0, t) · real; glm::quat stores x, y, z, w) and the scale/shear S applied before
// it (see compute_dual_quat_palette). DQS blends the rigid parts as dual quaternions and, for scaled bones, the S
// matrices linearly (Kavan et al. 2008, §4 "non-rigid transformations").
struct DualQuat {
  glm::quat real{1.0f, 0.0f, 0.0f, 0.0f};
  glm::quat dual{0.0f, 0.0f, 0.0f, 0.0f};
};

// Converts an LBS palette (affine matrices, bottom row 0 0 0 1) into a DQS palette, once per frame. Each 3×3 part A
// is polar-decomposed A = R · S (R a rotation, S symmetric; a mirroring A gives R = -Q, S = -P so R stays proper);
// `out_scales[i]` = S. `has_scale` is set true when any S differs from the identity by more than 1e-5 — pass
// out_scales to SkinningJob::scales only then (the rigid path is the fast one). `matrices`, `out` and `out_scales`
// must have the same size; returns false (writing nothing) when they differ or a matrix is singular or not finite.
// Cost: O(bones), a few dozen flops per bone; no allocation.
DEFORM_RUNTIME_API bool compute_dual_quat_palette(std::span<const glm::mat4> matrices, std::span<DualQuat> out,
                                          std::span<glm::mat3> out_scales, bool& has_scale) noexcept;

// The skinning job. Vertex i reads 3 floats at byte offset i·stride of each input span and writes 3 floats at i·stride
// of each output span. The vertex count is bone_indices.size().
struct DEFORM_RUNTIME_API SkinningJob {
  SkinningMethod method = SkinningMethod::lbs;
  Isa isa = Isa::automatic;  // the kernel copy: isa.hpp

  // LBS palette: one affine matrix per bone, T_C = T_W · T_B⁻¹ (compute_skinning_palette). Used when method == lbs.
  std::span<const glm::mat4> matrices;
  // DQS palette: one per bone (compute_dual_quat_palette). Used when method == dqs.
  std::span<const DualQuat> dual_quats;
  // DQS scale/shear per bone, applied before the dual quaternion: empty for rigid palettes (the fast path), else one
  // per bone. Used when method == dqs.
  std::span<const glm::mat3> scales;

  // Per vertex: four bone indices into the palette and their weights (each >= 0, finite, with a positive sum; an
  // unused slot has weight 0 and any index in range).
  std::span<const glm::u16vec4> bone_indices;
  std::span<const glm::vec4> bone_weights;

  // Positions, required. Byte strides: multiples of 4, from 12 to max_skinning_stride.
  std::span<const float> in_positions;
  std::size_t in_positions_stride = 12;
  std::span<float> out_positions;
  std::size_t out_positions_stride = 12;
  // Normals, optional: both spans empty skips them, else both must cover the vertex count.
  std::span<const float> in_normals;
  std::size_t in_normals_stride = 12;
  std::span<float> out_normals;
  std::size_t out_normals_stride = 12;

  // Streaming (non-temporal) stores for the outputs: they go to memory without first reading each cache line and
  // without keeping it in the caches. For results the CPU will not read again soon — a GPU upload buffer, a mesh
  // much larger than the caches (it saves 24 of the ~96 bytes a vertex moves; docs/performance.md has the measured
  // effect). Taken by the AVX-512 kernels for packed outputs (strides 12) whose positions and normals lie alike on
  // 64-byte lines (as two allocations of the same size do); ignored otherwise. The results are the same bits.
  bool stream_outputs = false;

  // True when the call is well formed: a non-empty palette of at most 65536 bones for the chosen method (and scales
  // empty or of the same size), matching index and weight counts, every index < palette size, every weight finite and
  // >= 0 with a positive sum per vertex, strides valid, each span long enough ((count-1)·stride + 12 bytes), normals
  // both present or both absent, the ISA available. Outputs may alias inputs only in place (an output stream equal to
  // its input stream: same pointer and stride); any other overlap is not detected and gives unspecified results.
  // Cost: O(vertices) (it reads every index and weight): call it when the mesh is bound, not every frame.
  bool validate() const noexcept;

  // Deforms vertices [0, count) — or [begin, end) — on this thread. Checks only what is O(1) (sizes, strides, spans,
  // ISA) and returns false, writing nothing, when that fails: the per-vertex checks of validate() are the caller's to
  // have made once, since indices and weights do not change per frame. No allocation, no locks.
  bool run() const noexcept;
  bool run(std::size_t begin, std::size_t end) const noexcept;
  // Splits the vertex range across the pool's threads in chunks of at least `min_chunk` vertices (small meshes stay
  // on the calling thread), cut at multiples of 16 vertices; the result is bit-identical to run(). Same checks.
  bool run(ThreadPool& pool, std::size_t min_chunk = 16384) const;
};

// Largest byte stride a skinning stream accepts (1 MiB): keeps 16 lanes of offsets inside 32-bit gather indices.
inline constexpr std::size_t max_skinning_stride = std::size_t{1} << 20;

// Views a packed array of vec3 as the float span a SkinningJob takes (stride 12).
inline std::span<const float> as_floats(std::span<const glm::vec3> v) noexcept {
  return {v.empty() ? nullptr : &v[0].x, v.size() * 3};
}
inline std::span<float> as_floats(std::span<glm::vec3> v) noexcept {
  return {v.empty() ? nullptr : &v[0].x, v.size() * 3};
}
inline std::span<const float> as_floats(const std::vector<glm::vec3>& v) noexcept {
  return as_floats(std::span<const glm::vec3>(v));
}
inline std::span<float> as_floats(std::vector<glm::vec3>& v) noexcept { return as_floats(std::span<glm::vec3>(v)); }

}  // namespace deform
