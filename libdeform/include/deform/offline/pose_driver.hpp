#pragma once
// Binding a pose driver (runtime/pose_driver.hpp; docs/skinning.md, "Pose-space correctives"): the sample poses an
// artist sculpted corrective shapes at, and what each shape's weight is there, become the radial basis function's
// coefficients, solved once. Bind time: allocates and throws.
#include <cstddef>
#include <cstdint>
#include <span>

#include <string>

#include "deform/offline/export.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/pose_driver.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

struct PoseDriverSettings {
  RbfKernel kernel = RbfKernel::gaussian;
  // The kernel's radius (chord units: 2 is a half turn); 0 picks it: the mean, over the sample poses, of the distance
  // to the nearest other sample, so that neighbouring samples' influences overlap (1, about 60°, for one sample).
  float radius = 0.0f;
  float twist_weight = 1.0f;    // >= 0: 0 ignores twist (a pose reader of the swing alone)
  float regularization = 0.0f;  // >= 0: added to Φ's diagonal; > 0 smooths rather than interpolates exactly
  bool clamp = true;            // weights clamped into [0, 1] per frame
};

// Solves the driver for `bones` (distinct skeleton ids, at least one) and `samples` (poses of the skeleton, at least
// one; only the driver bones' rotations are read) whose target weights are `targets`, row-major: samples × shapes
// (shape_count >= 1), typically 1 for the shape sculpted at that pose and 0 for the others. Each bone's twist axis is
// the direction to its first child's bind head (+Y for a bone without a child that is off its head). Throws
// deform::Error (kind argument) naming the field for bad ids, sizes, settings or non-finite input, and naming the two
// samples when two are the same pose for the driver bones (Φ singular). O(samples² · bones + samples³).
DEFORM_OFFLINE_API PoseDriverBinding bind_pose_driver(const Skeleton& skeleton, std::span<const std::int32_t> bones,
                                                      std::span<const Pose> samples, std::span<const float> targets,
                                                      std::size_t shape_count, const PoseDriverSettings& settings = {});

// A corrective shape from a sculpt: the bind-space morph target that, applied before linear blend skinning by
// `palette` (the skinning matrices of the pose the artist sculpted at, e.g. Character::palette()), puts every point of
// `model` where `sculpted` has it (one position per point). For point i skinned by A_i p + t_i (A_i = Σ w_ij M_j's
// 3×3 part), the delta is A_i⁻¹ (sculpted_i − skinned_i): exact under LBS, to float rounding. Points whose delta is
// within `tolerance` (model units) of zero are left out, so the target is sparse. No normal deltas: the morphed
// normals are the rest ones. Throws deform::Error (kind argument) for sizes that do not match, a non-finite input, or
// a point whose blended matrix cannot be inverted (its bones' weights cancel), naming the point.
DEFORM_OFFLINE_API MorphTarget corrective_from_sculpt(const Model& model, std::span<const glm::mat4> palette,
                                                      std::span<const glm::vec3> sculpted, float tolerance = 0.0f,
                                                      const std::string& name = "corrective");

}  // namespace deform
