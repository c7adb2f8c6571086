#pragma once
// Private to libdeform: what the three IK solvers share — chain forward kinematics on rigid frames, the shortest-arc
// rotation, joint clamping and the stall escape (random perturbation within the limits, keeping the best pose).
#include <cmath>
#include <cstdint>
#include <span>

#include "deform/ik.hpp"

namespace deform::detail {

// A rigid world transform: p_world = rotation * p + translation.
struct Frame {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 translation{0.0f};
};

inline bool finite(glm::vec3 v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// True when `pose` has an entry per bone of `skeleton`.
bool pose_fits(const Skeleton& skeleton, const Pose& pose) noexcept;

// World frame of the root's parent (identity for the skeleton root). O(ancestors).
Frame base_frame(const IkChain& chain, const Pose& pose) noexcept;

// World rotation and head of every chain bone, from the base frame. Spans have chain.bones.size() entries.
void chain_fk(const IkChain& chain, const Pose& pose, const Frame& base, std::span<glm::quat> rotations,
              std::span<glm::vec3> heads) noexcept;

// The shortest-arc unit rotation turning direction `from` onto direction `to` (angle from the dot product, axis from
// the cross product); identity when either is (nearly) zero; a half turn about a perpendicular axis when opposite.
// With max_radians > 0 the angle is capped to it.
glm::quat rotation_between(glm::vec3 from, glm::vec3 to, float max_radians = 0.0f) noexcept;

// Clamps a joint's local rotation into its DOF limits (Skeleton::clamp_to_limits), skipping joints free on every axis.
// Returns true when the clamp changed the rotation.
bool clamp_joint(const Skeleton& skeleton, Pose& pose, std::int32_t bone) noexcept;

// Re-aims a joint after a clamp: turns one Euler axis at a time (x, then y, then z, each to its best angle within its
// limits, a 1-D problem with a closed form) so that `point` — a world point carried by the joint, such as the
// effector — comes as close to `goal` as the limits allow. `parent` is the world rotation of the joint's parent and
// `head` the joint's world head; `point` is where the current rotation puts it. The rotation stays within the limits.
void reaim_joint(const Skeleton& skeleton, Pose& pose, std::int32_t bone, glm::quat parent, glm::vec3 head,
                 glm::vec3 point, glm::vec3 goal) noexcept;

// Points every segment at `target`, root first (each joint the smallest turn of its segment, clamped and re-aimed):
// for an out-of-reach target this is the straight chain, the answer an unconstrained chain minimises the distance
// with, which CCD only approaches slowly (the distance is second order in the joints' deviation from it).
// `frames` and `heads` hold the chain's FK for `pose` on entry and are updated.
void point_segments_at(const Skeleton& skeleton, const IkChain& chain, Pose& pose, glm::quat base,
                       std::span<glm::quat> frames, std::span<glm::vec3> heads, glm::vec3 target) noexcept;

// One damped least-squares step (Wampler 1986; Buss 2004, "Introduction to inverse kinematics with Jacobian transpose,
// pseudoinverse and damped least squares methods") on the joints' Euler angles: Δθ = Jᵀ (J Jᵀ + λ² I)⁻¹ (target −
// effector), a 3×3 solve, then each joint is clamped into its limits. `heads` and `frames` hold the chain's FK for
// `pose` on entry (they are not updated); `angles` and `columns` are scratch of 3 × joint_count() entries.
void damped_least_squares_step(const Skeleton& skeleton, const IkChain& chain, Pose& pose, glm::quat base,
                               std::span<const glm::quat> frames, std::span<const glm::vec3> heads, glm::vec3 target,
                               float lambda, std::span<glm::vec3> angles, std::span<glm::vec3> columns) noexcept;

// Copies the chain joints' local rotations from `pose` to `saved` (joint_count() entries) or back.
void save_joints(const IkChain& chain, const Pose& pose, std::span<glm::quat> saved) noexcept;
void load_joints(const IkChain& chain, std::span<const glm::quat> saved, Pose& pose) noexcept;

// Rotates every joint by up to `degrees` per Euler axis at random (xorshift32 on `state`), then clamps it.
void perturb_joints(const Skeleton& skeleton, const IkChain& chain, Pose& pose, std::uint32_t& state,
                    float degrees) noexcept;

// A solve's settings check: finite target, max_iterations >= 1, finite non-negative tolerance and step.
bool settings_valid(glm::vec3 target, const IkSettings& settings) noexcept;

// A sweep that shortens the distance (above the out-of-reach floor) by less than this fraction is a stall.
inline constexpr float stall_gain = 0.1f;
// Damping of the stall escape's least-squares steps, as a fraction of the chain length.
inline constexpr float damping_fraction = 0.05f;
// How far a stall escape perturbs each joint axis, degrees.
inline constexpr float escape_degrees = 180.0f;

}  // namespace deform::detail
