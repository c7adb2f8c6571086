#pragma once
// Morph targets (blend shapes): a mesh's rest positions (and normals) plus Σ wₖ · Δₖ, the per-frame step before
// skinning (glTF and three.js apply morphs in bind space, then skin the morphed points).
//
// A target stores sparse deltas: only the points it moves, in ascending point order. MorphJob writes the morphed
// points into a caller-owned array that then feeds SkinningJob::in_positions (and in_normals). Its weights come from
// the target's default weight, an Animation's morph channels (sample_morph_weights in animation.hpp), or the caller.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"

namespace deform {

// One named target. `points` are point indices, strictly ascending; `position_deltas` has one entry per point;
// `normal_deltas` is empty (the target leaves normals alone) or has one per point. The morphed normal is the rest
// normal plus the weighted normal deltas, renormalised by whoever uses it (skinning renormalises).
struct MorphTarget {
  std::string name;             // may be empty; the CLI names targets by it
  std::string mesh;             // the name of the mesh (glTF mesh) the target belongs to, for listings
  float default_weight = 0.0f;  // the weight when nothing animates or overrides it
  std::vector<std::uint32_t> points;
  std::vector<glm::vec3> position_deltas;
  std::vector<glm::vec3> normal_deltas;
  bool operator==(const MorphTarget&) const = default;
};

// Checks targets against a mesh of `point_count` points: points strictly ascending and in range, deltas sized as
// above and finite. Throws deform::Error naming `source` and the target.
DEFORM_RUNTIME_API void require_valid_morph_targets(std::span<const MorphTarget> targets, std::size_t point_count,
                                                    const std::string& source = "<memory>");

// The morph job: out[i] = rest[i] + Σₖ weights[k] · Δₖ[i] over the targets that move point i, for positions and,
// when both normal spans are given, normals (not renormalised). The elements are the points: run(begin, end) writes
// points [begin, end) only, so disjoint ranges run on different threads. Targets are added in order, each in float,
// so a point's result does not depend on the range it is run in. Outputs must not overlap the rest arrays.
// No allocation, no locks, no I/O.
struct DEFORM_RUNTIME_API MorphJob {
  std::span<const MorphTarget> targets;
  std::span<const float> weights;  // one per target; a zero weight skips its target
  std::span<const glm::vec3> rest_positions;
  std::span<const glm::vec3> rest_normals;  // optional: empty, or one per point (both normal spans or neither)
  std::span<glm::vec3> out_positions;       // one per point
  std::span<glm::vec3> out_normals;

  // Ok when well formed, else why not: weights as many as targets ("weights and targets differ in count") and
  // finite ("weight is not finite"), outputs as long as the rest positions, normals both or neither and sized alike,
  // every target valid for the point count (as require_valid_morph_targets: "target is malformed"). Cost: O(points +
  // deltas) — call it when binding, not every frame.
  Status validate() const noexcept;
  // The O(1) checks (sizes, range: "range outside the job") and the weights' finiteness (O(targets)); on failure
  // writes nothing. O(range + Σ deltas in range + targets · log deltas).
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  std::size_t count() const noexcept { return rest_positions.size(); }
};

// The index of the first target named `name`, or -1.
DEFORM_RUNTIME_API std::int32_t find_morph_target(std::span<const MorphTarget> targets, std::string_view name) noexcept;

}  // namespace deform
