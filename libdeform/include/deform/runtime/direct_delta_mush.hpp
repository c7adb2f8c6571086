#pragma once
// Direct Delta Mush (Le and Lewis 2019, "Direct Delta Mush Skinning and Variants"): Delta Mush's smoothing folded into
// per-point, per-bone weights computed once, so that a frame is one pass over the points like linear blend skinning.
//
// Bind time (offline/direct_delta_mush.hpp, bind_direct_delta_mush): each bone's weights, and the rest points' first
// and second moments under them, are smoothed over the mesh by an implicit Laplacian. For point i and bone j that
// gives a symmetric 4×4 moment matrix Ωᵢⱼ = Σₖ Bᵢₖ wₖⱼ p̃ₖ p̃ₖᵀ (B the smoothing operator, p̃ₖ the rest point k,
// homogeneous, here taken relative to the rest point i so that no float sum cancels the model's distance from the
// origin). Per frame (DirectDeltaMushJob): Qᵢ = Σⱼ Mⱼ Ωᵢⱼ is what the bones do to point i's smoothed neighbourhood; its
// 3×3 cross-covariance gives the point's rotation Rᵢ (the rotation closest to it: a polar decomposition, always
// proper), its last column and row the neighbourhood's deformed and rest centroids, and the point goes where Rᵢ carries
// it about them. Normals turn by Rᵢ.
//
// The rest pose: at identity matrices every Qᵢ is the rest moments, whose cross-covariance is symmetric and (the
// smoothing has no negative entries) positive semi-definite, so Rᵢ is the identity and every point stays put. So that
// the rotation is unique even where a neighbourhood is flat, a line or a single point (a lone triangle, a point
// without neighbours), the binder adds a small isotropic spread to every moment (each rest point a small ball of
// variance σᵢ², DirectDeltaMushSettings::regularization): the covariance is then positive definite at rest. Under a
// pose the spread adds σᵢ² Σⱼ ψᵢⱼ Aⱼ (the linear blend of the bones' 3×3 parts), which settles the directions the
// neighbourhood cannot, as linear blend skinning would. Rᵢ is a unit quaternion: never a reflection.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/skinning.hpp"

namespace deform {

class ThreadPool;

// One influence's moments Ωᵢⱼ, relative to the rest point i: the second moments P (symmetric 3×3: xx, xy, xz, yy, yz,
// zz), the first moments p (x, y, z) and the smoothed weight ψ (w).
struct DirectDeltaMushMoments {
  float xx = 0.0f, xy = 0.0f, xz = 0.0f, yy = 0.0f, yz = 0.0f, zz = 0.0f;
  float x = 0.0f, y = 0.0f, z = 0.0f;
  float w = 0.0f;
};

// A binding's rows laid out for its job's kernel (pack_direct_delta_mush builds it from the rows; derived data, never
// edited by hand). Points go in blocks of `width` (point width · k + l is lane l of block k), a block's influences in
// rounds of one influence per lane (or none: zero moments): first its `shared` rounds, in each of which every lane
// takes the same bone (the kernel reads that bone's matrix once for the block), then rounds with a bone per lane, each
// lane's other influences in row order. The packer picks the shared bones per block to minimise the rounds' cost; the
// kernel streams the moments, already in lanes (the full form's 10 floats a slot, the reduced form's 4: a copy of the
// rows' that the kernel reads as vectors; reading the rows through `influence` instead, one lane at a time, measured
// 1.7× slower for the reduced job). A point's sums are taken in its block's round order, which the binding fixes, so
// its result does not depend on the range it is run in.
struct DirectDeltaMushLanes {
  static constexpr std::size_t width = 16;
  std::size_t point_count = 0;           // the rows' point count when packed
  std::vector<std::uint32_t> rounds;     // block k's rounds: [rounds[k], rounds[k + 1]); blocks + 1 entries
  std::vector<std::uint32_t> shared;     // per block: how many of its first rounds share one bone
  std::vector<std::uint32_t> start;      // per block and lane: the shared round of its strongest bone, or `none`
  std::vector<std::uint32_t> influence;  // per round and lane (width per round): the row's influence, or `none`
  std::vector<std::uint16_t> bones;      // per round and lane: the palette entry (a shared round's in every lane)
  std::vector<float> moments;            // per round: the moments (the full form's 10 in declaration order, the
                                         // reduced form's x, y, z, w) × width lanes, 0 for none
  static constexpr std::uint32_t none = 0xffffffffu;
};

// What bind_direct_delta_mush builds: read-only data for DirectDeltaMushJob, compressed rows by point, and the same
// laid out for the kernel (`lanes`: after changing the rows, call pack_direct_delta_mush again, or validate() refuses).
struct DirectDeltaMushBinding {
  std::vector<glm::vec3> rest;                  // the rest points, the origin of each point's moments
  std::vector<std::uint32_t> offsets;           // point i's influences: [offsets[i], offsets[i + 1]); point_count() + 1
  std::vector<std::uint16_t> bones;             // per influence: the palette entry; the largest ψ first in each row
  std::vector<DirectDeltaMushMoments> moments;  // per influence
  std::uint32_t bone_count = 0;                 // the palette size the influences need (largest bone + 1)
  DirectDeltaMushLanes lanes;                   // the rows for the kernel (pack_direct_delta_mush)

  std::size_t point_count() const noexcept { return rest.size(); }
  std::size_t influence_count() const noexcept { return bones.size(); }
};

// The Direct Delta Mush job: one palette (affine matrices, the LBS palette T_W · T_B⁻¹) in, points out. Shape as
// SkinningJob: validate() once at bind time, run() or run(begin, end) per frame (run_parallel splits it), caller-owned
// spans, no allocation, no throw; a point's result does not depend on the range it is run in.
struct DEFORM_RUNTIME_API DirectDeltaMushJob {
  const DirectDeltaMushBinding* binding = nullptr;
  std::span<const glm::mat4> matrices;  // at least binding->bone_count, affine (bottom row 0 0 0 1)

  // Optional input points, one per point: empty deforms the binding's rest points; else each point's offset from its
  // rest point (a morph target's, say) is carried by the point's rotation: out = xᵢ(rest) + Rᵢ (inᵢ − restᵢ).
  std::span<const glm::vec3> in_positions;
  std::span<glm::vec3> out_positions;  // one per point, required
  // Optional normals, one per point: both empty, or both one per point (out = Rᵢ inᵢ renormalised; zero stays zero).
  std::span<const glm::vec3> in_normals;
  std::span<glm::vec3> out_normals;
  // Optional: each point's rotation Rᵢ (unit quaternion), for render-vertex normals or tangents of a mesh whose
  // vertices split its points (seams): one per point, or empty.
  std::span<glm::quat> out_rotations;
  Isa isa = Isa::automatic;  // the kernel copy (isa.hpp); the copies differ in rounding only (fused multiply-adds)

  static constexpr std::size_t split_multiple = 16;
  // A point costs about as much as a few dozen LBS vertices, so smaller chunks than SkinningJob's pay a thread.
  static constexpr std::size_t min_parallel_chunk = 1024;

  // Ok when the call is well formed, else why not: a binding ("no binding"), its arrays consistent ("binding is
  // malformed: ..."), its moments and rest points finite ("binding is not finite"), a palette of at least bone_count
  // matrices ("palette is too small"), every matrix finite ("palette matrix is not finite"), the spans one per point
  // ("positions are not one per point", "normals are not one per point", "rotations are not one per point"), the
  // instruction set available ("instruction set not available"), and its lanes packed from its rows as they are now
  // ("binding is malformed: lanes not packed from its rows": pack_direct_delta_mush).
  // O(points + influences + bones): call it when binding, not every frame.
  Status validate() const noexcept;

  std::size_t count() const noexcept { return binding ? binding->point_count() : 0; }

  // Points [0, count()) or [begin, end) on this thread. Checks only what is O(1) (the binding's array sizes, the
  // spans, the range: "range outside the job") and refuses, writing nothing, when that fails. No allocation.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  // run_parallel over the pool, in chunks of at least `min_chunk` points.
  Status run(ThreadPool& pool, std::size_t min_chunk = min_parallel_chunk) const noexcept;
};

// The reduced-storage form of a binding (reduce_direct_delta_mush): of each influence's moments Ωᵢⱼ only the smoothed
// weight ψᵢⱼ and first moment p̃ᵢⱼ (relative to the rest point i) are kept, 4 floats and a bone where the full form
// keeps 10 (each form's lanes copy its floats again: on the built-in character 49 bytes an influence in all against
// 102). The per-frame rotation is then not the polar decomposition of the posed second moments (which this form does
// not have) but a blend of the bones' rotations:
//   Rᵢ = the rotation of the unit quaternion normalise(Σⱼ ψᵢⱼ sⱼ qⱼ), qⱼ bone j's rotation (the DQS palette's real
//        part: the rotation of Aⱼ's polar decomposition), sⱼ = ±1 so that sⱼ qⱼ · q₀ >= 0 for q₀ the point's
//        strongest bone (the first of its row), as dual quaternion skinning aligns them;
//   tᵢ = Σⱼ (Aⱼ p̃ᵢⱼ + ψᵢⱼ tⱼ) − Rᵢ pᵢ with pᵢ = Σⱼ p̃ᵢⱼ (Aⱼ, tⱼ: palette matrix j's 3×3 part and translation);
//   out = Rᵢ xᵢ + tᵢ, normals Rᵢ nᵢ renormalised.
// With p̃ relative to the rest point rᵢ (p̃ = p̃ʳ + ψ rᵢ) and Σⱼ ψᵢⱼ = 1 that is out = Σⱼ ψᵢⱼ Mⱼ rᵢ + Σⱼ Aⱼ p̃ʳᵢⱼ +
// Rᵢ (xᵢ − rᵢ − pʳᵢ), which the job evaluates (the first sum relative to M₀ rᵢ, M₀ the strongest bone, so that no
// float sum cancels the model's distance from the origin). Contract: the identity palette gives every point back
// exactly up to the rounding of pʳᵢ's two equal sums (Rᵢ = I, tᵢ = 0); a rigid motion G of every bone moves every
// point by G (the ψ sum to 1); pᵢ is summed per frame, beside the other sums, rather than stored. The job's kernel
// takes a point's influences in its block's round order (`lanes`), not its row's: the sums round accordingly.
struct DirectDeltaMushReducedBinding {
  std::vector<glm::vec3> rest;         // the rest points
  std::vector<std::uint32_t> offsets;  // point i's influences: [offsets[i], offsets[i + 1]); point_count() + 1
  std::vector<std::uint16_t> bones;    // per influence: the palette entry; the largest ψ first in each row
  std::vector<glm::vec4> moments;      // per influence: p̃ʳᵢⱼ (x, y, z) and ψᵢⱼ (w); each row's ψ sum to 1
  std::uint32_t bone_count = 0;        // the palette size the influences need (largest bone + 1)
  // The rows laid out for the kernel, their moments copied (reduce_direct_delta_mush packs them; after changing the
  // rows, call pack_direct_delta_mush again, or validate() refuses).
  DirectDeltaMushLanes lanes;

  std::size_t point_count() const noexcept { return rest.size(); }
  std::size_t influence_count() const noexcept { return bones.size(); }
};

// Derives the reduced form from a full binding's rows: each row's ψ and first moments divided by the row's ψ sum (the
// pruning leaves it a little under 1; the full job is unchanged by that scale, it normalises its centroids). Refuses
// rows whose arrays are inconsistent ("binding is malformed: ..."), a nonempty row whose ψ do not sum above 0, or a
// moment not finite ("binding is not finite"), leaving `out` empty. Packs out's lanes. Allocates.
DEFORM_RUNTIME_API Status reduce_direct_delta_mush(const DirectDeltaMushBinding& full,
                                                   DirectDeltaMushReducedBinding& out);

// The job of the reduced form, shaped as DirectDeltaMushJob (validate() once, run() / run(begin, end) / run(pool),
// caller-owned spans, no allocation, no throw). A lane kernel in one copy per instruction set, as DirectDeltaMushJob's:
// blocks of 16 points, the bones' matrices and quaternions read once per block for a bone its lanes share.
struct DEFORM_RUNTIME_API DirectDeltaMushReducedJob {
  const DirectDeltaMushReducedBinding* binding = nullptr;
  std::span<const glm::mat4> matrices;   // at least binding->bone_count, affine (bottom row 0 0 0 1)
  std::span<const DualQuat> dual_quats;  // the same palette through compute_dual_quat_palette (its `real` is read)

  // As DirectDeltaMushJob's: optional input points (empty: the rest points), positions out required, normals both or
  // neither, rotations optional.
  std::span<const glm::vec3> in_positions;
  std::span<glm::vec3> out_positions;
  std::span<const glm::vec3> in_normals;
  std::span<glm::vec3> out_normals;
  std::span<glm::quat> out_rotations;
  Isa isa = Isa::automatic;  // the kernel copy (isa.hpp); the copies differ in rounding only (fused multiply-adds)

  static constexpr std::size_t split_multiple = 16;
  static constexpr std::size_t min_parallel_chunk = 4096;

  // Ok when the call is well formed, else why not: "no binding", "binding is malformed: ..." (array sizes, offsets
  // ascending from 0, a bone out of range, a nonempty row whose ψ do not sum above 0 or whose first ψ is not positive),
  // "binding is not finite", "palette is too small" (matrices or dual_quats under bone_count), "palette matrix is not
  // finite", "dual quaternion is not finite", the spans as DirectDeltaMushJob's, "instruction set not available", and
  // "binding is malformed: lanes not packed from its rows" (pack_direct_delta_mush). O(points + influences + bones).
  Status validate() const noexcept;

  std::size_t count() const noexcept { return binding ? binding->point_count() : 0; }

  // As DirectDeltaMushJob's: O(1) checks, then points [begin, end); no allocation. An empty row leaves its point as
  // it comes in (R = I, t = 0).
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  Status run(ThreadPool& pool, std::size_t min_chunk = min_parallel_chunk) const noexcept;
};

// Builds binding.lanes from its rows (rest, offsets, bones, moments). bind_direct_delta_mush calls it; call it again
// after editing the rows. Refuses rows whose arrays are inconsistent ("binding is malformed: arrays differ in size",
// "... offsets do not ascend from 0"), leaving the lanes empty (the job then refuses the binding). Allocates; cost
// O(influences · bones in a block of 16 points) and 46 bytes per influence slot (an empty slot of a lane with
// fewer influences than its block's rounds counts).
DEFORM_RUNTIME_API Status pack_direct_delta_mush(DirectDeltaMushBinding& binding);
// The same for a reduced binding's rows: reduce_direct_delta_mush calls it. Refuses as the other; 22 bytes per
// influence slot.
DEFORM_RUNTIME_API Status pack_direct_delta_mush(DirectDeltaMushReducedBinding& binding);

// The proper rotation R maximising trace(Rᵀ C) (the rotation of C's polar decomposition, with a reflection turned into
// the nearest rotation: U diag(1, 1, det UVᵀ) Vᵀ), found by Newton steps on the rotation group from `start`. C must not
// be close to rank 1 for a unique answer (the binder's spread sees to that for the job). The job runs the
// same steps on blocks of points at once (stopping after a step under 1e-3 rad rather than 1e-4: its result
// differs from this one's by about 1e-6 rad); this one is for callers and the tests. No allocation.
DEFORM_RUNTIME_API glm::quat nearest_rotation(const glm::mat3& c, glm::quat start) noexcept;

}  // namespace deform
