#pragma once
// Private to libdeform: what the three IK solvers share — chain forward kinematics on rigid frames, the shortest-arc
// rotation, joint clamping and the stall escape (random perturbation within the limits, keeping the best pose).
#include <cmath>
#include <cstdint>
#include <span>

#include "deform/runtime/ik.hpp"
#include "finite.hpp"
namespace deform::detail {

using Frame = RigidTransform;

// The pose a solve reads and writes: a Pose's spans, indexed by bone id, checked to hold every chain bone.
struct PoseView {
  std::span<glm::quat> rotations;
  std::span<const glm::vec3> translations;
};

// The scratch of one iterative solve, carved from the job's bytes (IkJob::scratch_size).
struct Scratch {
  std::span<glm::dvec3> angles;    // Euler angles per joint (stall escape)
  std::span<glm::quat> frames;     // model-space rotation per chain bone
  std::span<glm::quat> best;       // best joint rotations seen
  std::span<glm::vec3> heads;      // model-space head per chain bone
  std::span<glm::vec3> columns;    // Jacobian columns, 3 per joint (stall escape)
  std::span<glm::vec3> goals;      // FABRIK's joint positions, per chain bone
  std::span<float> lengths;        // FABRIK's segment lengths, per joint
  std::span<glm::quat> input;      // the joints' input rotations (a weight below 1 blends back toward them)
  std::span<glm::quat> first;      // the first solve's joint rotations, while a pole seeds a second
  std::span<glm::vec4> axis_dirs;  // per joint, the X and Y Euler directions a least-squares step left (the next's)
};

// The pole swivel (IkJob::pole): turns the root joint about the line root head → effector so that the chain's
// middle moves toward `pole`, as far as the root's limits allow without losing the solve's distance; while the middle
// is still not on the pole's side, the next joint turns the rest of the chain about its own line to the effector.
// With `whole`, each turn is applied entire (clamped) whatever it does to the distance: the seed of a second solve.
// `frames` and `heads` hold the chain's FK for `pose` on entry and on return; returns the new effector–target
// distance.
float swivel_toward_pole(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target, glm::vec3 pole,
                         float distance, float tolerance, std::span<glm::quat> frames, std::span<glm::vec3> heads,
                         bool whole = false) noexcept;
// Whether the chain's middle (the mean of the heads after the root) lies on the pole's side of the line root →
// effector (or the question has no answer: a straight chain, a pole on the line). `heads` from chain_fk.
bool faces_pole(const IkChain& chain, std::span<const glm::vec3> heads, glm::vec3 pole) noexcept;

// The two iterative solves; the job has checked every input. `random_state` is the stall escape's generator state;
// `length` is chain_length of the pose.
IkResult solve_ccd(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target, const IkSettings& settings,
                   float length, const Scratch& scratch, std::uint32_t& random_state) noexcept;
IkResult solve_fabrik(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target,
                      const IkSettings& settings, const Scratch& scratch, std::uint32_t& random_state) noexcept;

// The small helpers below are defined here so that they inline into the solvers' per-solve code (a two-bone solve
// is ~200 ns: a call each would show).

// Model-space rotation and head of every chain bone, from the base frame. Spans have chain.bones.size() entries.
void chain_fk(const IkChain& chain, PoseView pose, const Frame& base, std::span<glm::quat> rotations,
              std::span<glm::vec3> heads) noexcept;

// A cap on the angle of one rotation, prepared so that applying it needs no trigonometry. The default caps nothing.
struct StepCap {
  float cos_angle = -1.0f;     // cos of the largest angle
  glm::vec2 half{0.0f, 1.0f};  // (cos, sin) of half of it
};
StepCap cap_for(float max_radians) noexcept;  // max_radians <= 0 or >= π: no cap

// The shortest-arc unit rotation turning direction `from` onto direction `to` (angle from the dot product, axis from
// the cross product), its angle capped by `cap`; identity when either is (nearly) zero; a half turn (or the cap)
// about a perpendicular axis when opposite.
inline glm::quat rotation_between(glm::vec3 from, glm::vec3 to, const StepCap& cap = {}) noexcept {
  // With |from| |to| = r: (r + from · to, from × to) normalised is the rotation by the angle between them about
  // their normal: two square roots, no trigonometry. In double so that r² neither underflows nor overflows.
  const glm::dvec3 a(from), b(to);
  const double aa = glm::dot(a, a), bb = glm::dot(b, b);
  if (!(aa > 1e-24) || !(bb > 1e-24)) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const double r = std::sqrt(aa * bb), cosine = glm::dot(a, b);  // cosine and axis are scaled by r
  const glm::dvec3 axis = glm::cross(a, b);
  const double sine2 = glm::dot(axis, axis);
  if (sine2 < 1e-14 * aa * bb) {
    if (cosine > 0.0) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    // Opposite: any axis perpendicular to `from` does; take the one from the coordinate axis least aligned with it.
    const glm::dvec3 helper = std::abs(a.x) < 0.6 * std::sqrt(aa) ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::vec3 normal(glm::normalize(glm::cross(a, helper)) * static_cast<double>(cap.half.y));
    return glm::quat(cap.half.x, normal.x, normal.y, normal.z);
  }
  if (cosine < static_cast<double>(cap.cos_angle) * r) {
    const glm::vec3 normal(axis * (static_cast<double>(cap.half.y) / std::sqrt(sine2)));
    return glm::quat(cap.half.x, normal.x, normal.y, normal.z);
  }
  const glm::dquat q(r + cosine, axis.x, axis.y, axis.z);
  return glm::quat(q * (1.0 / std::sqrt(glm::dot(q, q))));
}

// A joint rotation as Euler angles X·Y·Z: per axis the angle (radians) and its direction (cos, sin) times length[axis]
// (1 unless limit_euler was asked for raw directions).
struct EulerAngles {
  glm::dvec3 angle{0.0};
  glm::dvec2 dir[3]{};
  glm::dvec3 length{1.0};
};

// The Euler triple of `rotation` that `limits` mean — of its two triples, angles in (-π, π], the one nearer the
// limits (as Skeleton::clamp_to_limits) — clamped into them. Returns true when clamping changed it. Without
// `angles_needed`, a rotation within the limits returns false at once, leaving `euler` unset (no arctangent). With
// `raw_directions` as well, a clamped one's unclamped axes keep the rotation matrix's unnormalised directions, with
// their lengths: for the clamp's quaternion alone, which then no longer waits for their square root and division
// (the clamp's critical path is a chain of them). Otherwise every direction is unit.
bool limit_euler(const EulerLimits& limits, glm::quat rotation, EulerAngles& euler, bool angles_needed = true,
                 bool raw_directions = false) noexcept;

// The unit quaternion qx · qy · qz of Euler angles (radians, each within [-π, π]), from polynomial (cos, sin) of
// the half angles (within 2e-12, no trigonometric call, no normalisation), and in `xy_dirs` the (cos, sin) of the X
// and Y angles as floats (x.x, x.y, y.x, y.y). An angle at a limit gives the limit's rotation to that precision,
// far below the float rotation's rounding.
glm::quat quat_at(glm::dvec3 angle, glm::vec4& xy_dirs) noexcept;

// (cos, sin) of half the angle of the non-zero direction `d` of the given length, times a positive factor, the
// half angle in (-90°, 90°]: the quaternion (h.x, h.y · axis) of a turn whose cosine and sine are known, without
// trigonometry, normalised by whoever uses it.
inline glm::dvec2 scaled_half_angle(glm::dvec2 d, double length) noexcept {
  // (r + cos, sin), or near ±180°, where that cancels, the parallel (|sin|, ±(r − cos)).
  return d.x >= 0.0 ? glm::dvec2(length + d.x, d.y) : glm::dvec2(std::abs(d.y), std::copysign(length - d.x, d.y));
}

// Re-aims a clamped joint: turns one Euler axis at a time (x, then y, then z, each to its best angle within its
// limits, a 1-D problem with a closed form) so that `carried` — a point in the joint's own frame relative to its
// head, such as the effector — comes as close to `wanted` — in the parent's frame, relative to the head — as the
// limits allow. `euler` must be within the limits and its directions stay so; only the directions are updated (its
// angles go stale: the clamp's quaternion reads the directions alone), with no arctangent.
void reaim_euler(const EulerLimits& limits, EulerAngles& euler, glm::dvec3 carried, glm::dvec3 wanted) noexcept;

// Joint k's swing-twist limits when it has active ones, else null (its Euler entry applies).
inline const SwingTwistLimits* swing_twist_of(const IkChain& chain, std::size_t k) noexcept {
  return chain.swing_twist.empty() || !chain.swing_twist[k].active ? nullptr : &chain.swing_twist[k];
}
// Joint k's rotation clamped into its limits, whichever kind (clamp_rotation or clamp_swing_twist).
bool clamp_chain_joint(const IkChain& chain, std::size_t k, glm::quat& rotation) noexcept;
// clamp_joint for joint k, whichever kind of limits (a swing-twist joint is projected, not re-aimed).
bool clamp_chain_joint(const IkChain& chain, std::size_t k, glm::quat& local, bool reaim, glm::vec3 carried,
                       glm::vec3 wanted) noexcept;

// Normalises a joint's local rotation and clamps it into its limits; when it was outside and `reaim` is set, the
// clamped rotation is re-aimed (reaim_euler) with `carried` and `wanted`. Returns true when it was outside.
bool clamp_joint(const EulerLimits& limits, glm::quat& local, bool reaim, glm::vec3 carried, glm::vec3 wanted) noexcept;

// Points every segment at `target`, root first (each joint the smallest turn of its segment, clamped and re-aimed):
// for an out-of-reach target this is the straight chain, the answer an unconstrained chain minimises the distance
// with, which CCD only approaches slowly (the distance is second order in the joints' deviation from it).
// `frames` and `heads` hold the chain's FK for `pose` on entry and are updated.
void point_segments_at(const IkChain& chain, PoseView pose, glm::quat base, std::span<glm::quat> frames,
                       std::span<glm::vec3> heads, glm::vec3 target) noexcept;

// One damped least-squares step (Wampler 1986; Buss 2004, "Introduction to inverse kinematics with Jacobian transpose,
// pseudoinverse and damped least squares methods") on the joints' Euler angles: Δθ = Jᵀ (J Jᵀ + λ² I)⁻¹ (target −
// effector), a 3×3 solve, then each joint is clamped into its limits. `heads` and `frames` hold the chain's FK for
// `pose` on entry (they are not updated). `angles` (joint_count()) receives the joints' new Euler angles and
// `axis_dirs` (joint_count()) the (cos, sin) of their X and Y angles, as floats (x.x, x.y, y.x, y.y); with
// `angles_current` both hold the current ones on entry (the previous step was this one), which saves reading the
// angles from the pose and evaluating their directions again. `columns` (3 × joint_count()) is scratch.
void damped_least_squares_step(const IkChain& chain, std::span<const EulerLimits> limits, PoseView pose, glm::quat base,
                               std::span<const glm::quat> frames, std::span<const glm::vec3> heads, glm::vec3 target,
                               float lambda, bool angles_current, std::span<glm::dvec3> angles,
                               std::span<glm::vec4> axis_dirs, std::span<glm::vec3> columns) noexcept;

// Copies the chain joints' local rotations from `pose` to `saved` (joint_count() entries) or back.
void save_joints(const IkChain& chain, PoseView pose, std::span<glm::quat> saved) noexcept;
void load_joints(const IkChain& chain, std::span<const glm::quat> saved, PoseView pose) noexcept;

// Rotates every joint by up to `degrees` per Euler axis at random (xorshift32 on `state`), then clamps it.
void perturb_joints(const IkChain& chain, PoseView pose, std::uint32_t& state, float degrees) noexcept;

// A CCD sweep or FABRIK pass that fails to shorten the distance above the out-of-reach floor by this fraction has
// slowed to a crawl: damped least-squares steps take over (chosen by measurement, docs/ik.md and
// docs/performance.md). CCD's first sweeps hand over unless a sweep removed nearly all of it: a least-squares step
// costs less than a sweep and converges faster near the target (ik/ccd/4's median solve −16 %). After a random kick
// CCD keeps sweeping longer, into the new basin: with 0.95 there too, a few hard targets of ik/ccd/4's set were
// reached less often. FABRIK at 0.95 reached less often, so it keeps 0.7.
inline constexpr float ccd_handover_gain = 0.95f;
inline constexpr float ccd_kicked_handover_gain = 0.6f;
inline constexpr float fabrik_handover_gain = 0.7f;
// Least-squares steps that shorten it by less than this fraction have stalled: a random kick follows.
inline constexpr float stall_gain = 0.1f;
// Damping of the stall escape's least-squares steps, as a fraction of the chain length.
inline constexpr float damping_fraction = 0.05f;
// How far a stall escape perturbs each joint axis, degrees.
inline constexpr float escape_degrees = 180.0f;

}  // namespace deform::detail
