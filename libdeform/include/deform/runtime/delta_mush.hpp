#pragma once
// Delta Mush (Mancewicz, Derksen, Rijpkema, Wilson 2014, "Delta Mush: smoothing deformations while preserving
// detail"): a smoothing stage after skinning and the lattices that removes what linear blend skinning collapses and
// creases (elbows, knees, the stretched rubber's folds) while keeping the surface's detail.
//
// Bind time (offline/delta_mush.hpp, bind_delta_mush): the rest points are smoothed by `iterations` Laplacian steps
// of size `step` over the point adjacency; each point's delta from its smoothed position is stored in a local frame of
// the smoothed surface (normal from the triangles around the point, tangent toward one neighbour).
// Per frame (DeltaMushJob): the deformed points are smoothed the same way, each point's frame rebuilt from the
// smoothed deformed surface, and the delta added back in it. At the rest pose this gives back the rest points; under a
// pose it gives a smooth surface carrying the rest surface's detail.
//
// The elements are the mesh's points (Mesh::positions: UV and normal seams are not edges, so the smoothing keeps them
// closed). A per-point mask, bound with the rest, scales each point's smoothing: 1 fully mushed, 0 the input point kept
// exactly (a hand's fingers stay as skinned), between the two partly smoothed (Blender's Corrective Smooth reads its
// vertex group so).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"

namespace deform {

class ThreadPool;

// The most smoothing iterations a binding takes: beyond, the smoothing has long converged to what the boundaries hold
// and each iteration costs a pass over every point.
inline constexpr std::uint32_t max_delta_mush_iterations = 10000;

// What bind_delta_mush builds: read-only data for DeltaMushJob. Every array is indexed by point (point_count()
// entries) or is a compressed row array (offsets with point_count() + 1 entries, from 0, ascending).
struct DeltaMushBinding {
  std::uint32_t iterations = 0;  // smoothing steps, [0, max_delta_mush_iterations]
  float step = 0.5f;             // λ, (0, 1]: each step moves a point that fraction toward its neighbours' mean

  // One smoothing step: x'ᵢ = smoothing[i].x · xᵢ + smoothing[i].y · Σⱼ xⱼ over ring(i), with (1 − mᵢλ, mᵢλ / |ring|)
  // for mask mᵢ: a point with mask 0 or without neighbours has (1, 0) and does not move.
  std::vector<std::uint32_t> ring_offsets;  // point i's neighbours: rings[ring_offsets[i] .. ring_offsets[i + 1])
  std::vector<std::uint32_t> rings;         // each point's one-ring over triangle edges between points
  std::vector<glm::vec2> smoothing;         // (keep, pull) per point
  // The frame: normal = Σ cross(x_a − xᵢ, x_b − xᵢ) over the triangles (i, a, b) around i, in their winding (twice the
  // area-weighted normal); tangent = x_t − xᵢ without its normal part, t = tangent_neighbour[i]; bitangent =
  // normal × tangent.
  std::vector<std::uint32_t> fan_offsets;  // point i's triangles: pairs fans[2·fan_offsets[i] .. 2·fan_offsets[i+1])
  std::vector<std::uint32_t> fans;         // (a, b) per triangle around the point
  std::vector<std::uint32_t> tangent_neighbour;  // per point; no_frame for a pinned point
  // The rest point minus its smoothed rest position, in the frame's (tangent, bitangent, normal) coordinates (0 for a
  // pinned point).
  std::vector<glm::vec3> deltas;
  // 1 where the job copies the input point unchanged: the mask is 0, or the point's smoothed rest neighbourhood gives
  // no frame that rounding cannot turn (bind_delta_mush says when).
  std::vector<std::uint8_t> pinned;

  static constexpr std::uint32_t no_frame = 0xffffffffu;

  std::size_t point_count() const noexcept { return deltas.size(); }
};

// The Delta Mush job: out_positions = the mush of in_positions (the skinned, lattice-deformed points). Shape as every
// job (docs/architecture.md): validate() once at bind time, run() per frame, scratch from the caller.
//
// Threading: each smoothing iteration reads every point of the previous one, so the work is `passes()` passes, one per
// iteration plus the final pass (frames and deltas), each a range job over the points with a barrier between passes:
// run_pass(pass, begin, end) for pass 0, 1, ..., passes() − 1 in order, every range of a pass finished before the next
// pass starts (an engine's job system: one dependency per pass). run(pool) does that with a ThreadPool; run() runs
// every pass on this thread. A point's result does not depend on how the passes are split.
struct DEFORM_RUNTIME_API DeltaMushJob {
  const DeltaMushBinding* binding = nullptr;
  std::span<const glm::vec3> in_positions;  // one per point
  std::span<glm::vec3> out_positions;       // one per point; may be in_positions itself (in place), no other overlap
  std::span<glm::vec4> scratch;             // at least scratch_size(binding) entries, not overlapping the positions

  // Scratch entries the job needs: 0 for no iterations, one buffer for one, two for more (the smoothed positions of
  // the last two iterations, padded to 16 bytes so that a neighbour is one vector load), each of point_count() entries.
  static std::size_t scratch_size(const DeltaMushBinding& binding) noexcept {
    return binding.iterations == 0 ? 0 : binding.point_count() * (binding.iterations == 1 ? 1 : 2);
  }

  // Ok when the call is well formed, else why not: a binding ("no binding"), its iterations and step in range
  // ("iterations out of range", "step is not within (0, 1]"), every array sized for its point count and every index in
  // range ("binding is malformed: ..."), deltas and smoothing finite ("binding is not finite"), the positions one per
  // point ("positions are not one per point"), the scratch large enough ("scratch is too small"). O(points + ring and
  // fan entries): call it once when binding, not every frame.
  Status validate() const noexcept;

  // The point count (binding's), the elements of every pass.
  std::size_t count() const noexcept { return binding ? binding->point_count() : 0; }
  // iterations + 1.
  std::size_t passes() const noexcept { return binding ? std::size_t(binding->iterations) + 1 : 0; }

  // Every pass on this thread. Checks only what is O(1) (a binding, the spans' sizes against its point count, the
  // scratch's size) and refuses, writing nothing, when that fails; the O(n) checks are validate()'s. A point whose
  // deformed neighbourhood has collapsed (no usable normal or tangent) keeps its input position. No allocation.
  Status run() const noexcept;
  // Points [begin, end) of one pass: `pass` < iterations smooths into the scratch, the last pass writes out_positions.
  // The same O(1) checks, plus the pass and range ("range outside the job").
  Status run_pass(std::size_t pass, std::size_t begin, std::size_t end) const noexcept;
  // Every pass, each split across the pool in chunks of at least `min_chunk` points (small meshes stay on this
  // thread: a pass over the built-in character's 2,850 points takes a few microseconds, about a thread wake-up).
  Status run(ThreadPool& pool, std::size_t min_chunk = min_parallel_chunk) const noexcept;

  // run(pool) cuts passes at multiples of 16 points (no shared cache lines between threads' outputs).
  static constexpr std::size_t split_multiple = 16;
  static constexpr std::size_t min_parallel_chunk = 16384;

  // Where the last smoothing pass leaves the smoothed points, for the binder, which builds the rest deltas from exactly
  // what the job computes. Empty without iterations (the input is the smoothed surface then) or when the spans do not
  // fit.
  std::span<const glm::vec4> smoothed() const noexcept;
};

// Point `point`'s frame over `smoothed` positions as DeltaMushJob builds it: columns (tangent, bitangent, normal), unit
// and orthogonal. False (frame unchanged) when the point has no_frame or its neighbourhood gives no usable normal or
// tangent. `smoothed` holds one position per point (xyz; w unused). For the binder and the tests; no allocation.
DEFORM_RUNTIME_API bool delta_mush_frame(const DeltaMushBinding& binding, std::span<const glm::vec4> smoothed,
                                         std::uint32_t point, glm::mat3& frame) noexcept;

}  // namespace deform
