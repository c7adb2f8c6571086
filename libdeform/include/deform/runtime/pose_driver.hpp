#pragma once
// Pose-space correctives' driver (docs/skinning.md, "Pose-space correctives"): a radial basis function interpolation
// from a few bones' rotations to the weights of corrective shapes, as Unreal's Pose Driver and the pose readers of
// Maya rigs do. An artist sculpts a shape at a few sample poses (an elbow bent 90° and 150°, a shoulder raised); at
// any other pose each shape's weight is the interpolation of the samples, smooth and exact at the samples.
//
// Bind time (offline/pose_driver.hpp, bind_pose_driver) solves Φ C = T once: Φₖₗ = φ(d(pose k, pose l)) over the
// sample poses, T their target weights, C the coefficients. Per frame (PoseDriverJob) weight s = Σₖ φ(d(pose,
// pose k)) Cₖₛ: one distance per sample and driver bone, one kernel value per sample; no allocation, no solve.
//
// The distance between two rotations of a bone is split into swing (the bone's axis turning) and twist (about it),
// as artists think of a joint: d² = swing² + (twist_weight · twist)², each the chord 2·sin(angle / 2) of its angle
// (within 1% of the angle up to 30°, monotone up to 180°, and free of inverse trigonometry). Over several driver
// bones the squared distances add.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"

namespace deform {

// The radial function φ of a distance d at radius r: both are positive definite, so the bind-time solve has one
// answer for any set of distinct sample poses.
//  - gaussian: exp(−(d / r)²), local: a sample's influence fades within a few radii;
//  - inverse_multiquadric: 1 / sqrt(1 + (d / r)²), wider: falls off as 1 / d far from every sample.
enum class RbfKernel : std::uint8_t { gaussian, inverse_multiquadric };

// What bind_pose_driver builds: read-only data for PoseDriverJob.
struct PoseDriverBinding {
  std::vector<std::int32_t> bones;      // the driver bones (skeleton ids)
  std::vector<glm::vec3> twist_axes;    // per driver bone: its axis in its own local frame, unit
  std::vector<glm::quat> sample_poses;  // [k · bones + b]: sample pose k's local rotation of driver bone b, unit
  std::vector<float> coefficients;      // [k · shapes + s]: C, solved at bind time
  std::size_t shape_count = 0;
  RbfKernel kernel = RbfKernel::gaussian;
  float radius = 1.0f;        // of the kernel, in the distance's units (chord length, 2 at a half turn); > 0
  float twist_weight = 1.0f;  // how much a twist counts against a swing of the same angle; >= 0
  bool clamp = true;          // weights clamped into [0, 1], as corrective shapes are authored for

  std::size_t pose_count() const noexcept { return bones.empty() ? 0 : sample_poses.size() / bones.size(); }
};

// The swing-twist distance of rotation `b` from `a` about `axis` (unit, in the frame both rotations are local to):
// r = a⁻¹ b split into twist (about axis) and swing; returns swing_chord² + (twist_weight · twist_chord)². Unit or
// near-unit quaternions; O(1), no branches but a sign.
DEFORM_RUNTIME_API float swing_twist_distance_squared(glm::quat a, glm::quat b, glm::vec3 axis,
                                                      float twist_weight) noexcept;

// φ(d) for a squared distance d² (see RbfKernel), radius > 0.
DEFORM_RUNTIME_API float rbf_kernel(RbfKernel kernel, float distance_squared, float radius) noexcept;

// The per-frame job: the driver bones' local rotations in, the shapes' weights out.
struct DEFORM_RUNTIME_API PoseDriverJob {
  const PoseDriverBinding* binding = nullptr;
  std::span<const glm::quat> rotations;  // local rotations, index = bone id (a Pose's), every driver bone in range
  std::span<float> weights;              // out: one per shape (binding->shape_count)
  // The binding is set and consistent (as many axes as bones, sample poses and coefficients a whole number of rows,
  // radius > 0 and finite, twist_weight >= 0), every driver bone within `rotations`, and `weights` one per shape.
  // O(bones + samples · shapes).
  Status validate() const noexcept;
  // The O(1) size checks, then the weights; on failure writes nothing. O(samples · (bones + shapes)), no allocation.
  Status run() const noexcept;
  // The elements are the shapes: run(begin, end) writes weights [begin, end) only, each as run() gives it (every
  // range measures the distances again: at a microsecond for a whole driver, splitting it pays only for hundreds of
  // shapes).
  Status run(std::size_t begin, std::size_t end) const noexcept;
  // The shape count, 0 without a binding.
  std::size_t count() const noexcept { return binding == nullptr ? 0 : binding->shape_count; }
};

}  // namespace deform
