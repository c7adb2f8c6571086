#pragma once
// Skinning: a mesh deformed by a weighted bone palette, linear blend (LBS) or dual quaternion (DQS) — the per-frame
// kernel of a rigged character (thesis §6, eq. 13; Kavan, Collins, Žára, O'Sullivan 2007).
//
// The shape is ozz-animation's SkinningJob: a SkinningJob points at the caller's buffers (spans with byte strides, so
// AoS vertex structs and separate SoA arrays work alike), validate() says whether the call is well formed and why
// not, run() deforms, run(begin, end) deforms a range of vertices (run_parallel in parallel.hpp splits it across a
// thread pool). Nothing is allocated, nothing is locked, nothing is read outside the spans.
//
// Per frame:  world matrices (LocalToWorldJob) -> palette T_C = T_W · T_B⁻¹ (LocalToWorldJob::palette)
//             -> for DQS, compute_dual_quat_palette once -> SkinningJob::run.
// Influences: four per vertex (bone index + weight) in the fast kernels. Vertices with more list the rest in the
// optional `extra_*` spans (SkinWeights' compressed rows); run() gives those vertices a general kernel that sums
// every influence, and the four-influence kernels the runs of vertices between them. The kernels divide by each
// vertex's weight sum (all its influences), so weights that do not sum to one are renormalised on the fly;
// validate() asks for sums within [min_skin_weight_sum, max_skin_weight_sum].
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

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
namespace deform {

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
// out_scales to SkinningJob::scales only then (the rigid path is the fast one). Refuses, writing nothing, when the
// sizes differ ("palette sizes differ") or a matrix is not finite or singular ("palette matrix is not finite",
// "palette matrix is singular"). Cost: O(bones), a few hundred flops per bone (double precision); no allocation.
// A function rather than a job with ranges: its input changes every frame and is checked whole before anything is
// written (a per-range check would leave other ranges written when one refuses), `has_scale` is a reduction over
// all bones, and a palette (at most 65536 bones, usually under 200) costs a few microseconds, where a thread wake-up
// would not pay.
DEFORM_RUNTIME_API Status compute_dual_quat_palette(std::span<const glm::mat4> matrices, std::span<DualQuat> out,
                                                    std::span<glm::mat3> out_scales, bool& has_scale) noexcept;

// The weight sum SkinningJob::validate() accepts per vertex: wide around 1 (normalised weights; 255 for byte weights),
// narrow enough that the blended matrices and quaternions, their cofactors and squared lengths stay normal floats.
inline constexpr float min_skin_weight_sum = 1.0f / 65536.0f;
inline constexpr float max_skin_weight_sum = 65536.0f;

// The skinning job. Vertex i reads 3 floats at byte offset i·stride of each input span and writes 3 floats at i·stride
// of each output span. The vertex count is bone_indices.size().
struct DEFORM_RUNTIME_API SkinningJob {
  SkinningMethod method = SkinningMethod::lbs;
  Isa isa = Isa::automatic;  // the kernel copy: isa.hpp

  // LBS palette: one affine matrix per bone, T_C = T_W · T_B⁻¹ (LocalToWorldJob::palette). Used when method == lbs.
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
  // Influences past the fourth, optional (all four empty when no vertex has more than four; SkinWeights::extra_*):
  // the vertices that have them, strictly ascending and < count(); extra_offsets has one entry more, starts at 0,
  // never decreases and ends at extra_bones.size() == extra_weights.size(); vertex extra_vertices[j]'s further
  // influences are extra_bones / extra_weights [extra_offsets[j], extra_offsets[j + 1]), with the rules of the four
  // (indices in the palette, weights finite, >= 0, not denormal; the sum over all of a vertex's influences in range).
  // For DQS the first slot is the antipodality pivot, as in the four-influence kernels. Cost: each such vertex takes
  // the general kernel (portable, one vertex at a time: docs/performance.md has the figures); the vertices between
  // them run the four-influence kernels in runs, so a vertex's result never depends on the range it is run in.
  std::span<const std::uint32_t> extra_vertices;
  std::span<const std::uint32_t> extra_offsets;
  std::span<const std::uint16_t> extra_bones;
  std::span<const float> extra_weights;

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

  // Ranges are cut by run_parallel at multiples of 16 vertices (whole kernel blocks, no shared cache lines), in
  // chunks of at least 16384 by default: below that a thread wake-up costs more than it saves.
  static constexpr std::size_t split_multiple = 16;
  static constexpr std::size_t min_parallel_chunk = 16384;

  // Ok when the call is well formed, else why not: the extra influences consistent ("extra influences are
  // inconsistent": sizes, offsets, vertex order), a palette of 1 to 65536 bones for the chosen method ("palette is
  // empty", "palette has more than 65536 bones"; scales empty or of the same size), every palette entry finite
  // ("palette matrix is not finite", "dual quaternion is not finite", "scale matrix is not finite"), matching index and
  // weight counts, every index < palette size ("bone index out of range"), every weight finite ("weight is not
  // finite"), >= 0 ("weight is negative") and 0 or a normal float ("weight is denormal"), each vertex's sum within
  // [min_skin_weight_sum, max_skin_weight_sum] ("weight sum out of range"), strides valid, each span long enough
  // ((count-1)·stride + 12 bytes), normals both present or both absent, the ISA available ("instruction set not
  // available"). Outputs may alias inputs only in place (an output stream equal to its input stream: same pointer and
  // stride); any other overlap is not detected and gives unspecified results. Cost: O(vertices + bones) (it reads
  // every index, weight and palette entry): call it when the mesh is bound, and again when a palette's source may
  // have gone wrong, not every frame.
  Status validate() const noexcept;

  // The number of vertices, bone_indices.size().
  std::size_t count() const noexcept { return bone_indices.size(); }

  // Deforms vertices [0, count()) — or [begin, end) — on this thread. Checks only what is O(1) (sizes, strides, spans,
  // ISA, the range: "range outside the job") and refuses, writing nothing, when that fails: the per-vertex and
  // per-bone checks of validate() are the caller's to have made. A vertex's result does not depend on the range it is
  // run in. No allocation, no locks.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
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
