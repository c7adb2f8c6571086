#pragma once
// Inverse kinematics: move a chain of bones so that its effector reaches a target point (thesis ch. 7).
//
// A chain runs from a root bone down to an effector bone (the root is an ancestor of the effector). Its *joints* are
// the chain's bones except the effector (the effector's own rotation does not move its head), so a "k-bone chain"
// has k joints and k + 1 bones; a two-bone limb is shoulder, elbow and wrist. Every solver
//  - starts from the pose it is given and changes only the local rotations of the chain's joints;
//  - leaves every joint inside its DOF limits (the starting pose is clamped first);
//  - minimises the effector–target distance when the target is out of reach (an unconstrained chain ends straight,
//    pointing at the target);
//  - is constructed once (allocates) and solves per frame without allocating, throwing or doing I/O.
// docs/ik.md describes the algorithms, their guarantees and measured behaviour.
#include <cstdint>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/export.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// The bones of a chain, found once. bones[0] is the root, bones.back() the effector, each the parent of the next;
// `ancestors` are the bones above the root, from bone 0 down to the root's parent (their transforms place the chain).
struct IkChain {
  std::vector<std::int32_t> bones;
  std::vector<std::int32_t> ancestors;
  std::size_t joint_count() const noexcept { return bones.empty() ? 0 : bones.size() - 1; }
};

// The chain from `root` to `effector` (bone ids). Throws deform::Error when an id is out of range, when `root` is not
// a proper ancestor of `effector`, or when the chain has more than 256 bones. Cost O(skeleton depth).
DEFORM_RUNTIME_API IkChain make_chain(const Skeleton& skeleton, std::int32_t root, std::int32_t effector);

// The chain's reach from the root's head: the sum of the joints' segment lengths (|translation| of each chain bone
// after the root) in `pose`. A target farther than this from the root's head is out of reach. O(chain).
DEFORM_RUNTIME_API float chain_length(const IkChain& chain, const Pose& pose) noexcept;

// The world position of the effector's head in `pose` (forward kinematics of the ancestors and the chain only).
// The pose must have skeleton.bone_count() entries. O(depth of the effector), no allocation.
DEFORM_RUNTIME_API glm::vec3 effector_position(const Skeleton& skeleton, const IkChain& chain, const Pose& pose) noexcept;

// A joint's DOF limits prepared once for clamping per frame (prepare_limits): the bounds in radians and as unit
// (cos, sin) directions, so that clamp_rotation needs no sin, cos or atan2 call. The solvers hold one per joint.
// The default is free, as DofLimits{}.
struct EulerLimits {
  glm::dvec3 min{-std::numbers::pi}, max{std::numbers::pi};  // radians, DofLimits' bounds
  glm::dvec2 min_dir[3]{{-1.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}};  // (cos, sin) of min per axis
  glm::dvec2 max_dir[3]{{-1.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}};  // (cos, sin) of max per axis
  bool free = true;  // min <= -180° and max >= 180° on every axis: every rotation is within the limits
};

// The prepared form of `limits` (degrees, X·Y·Z as in shared/spec/sk-format.md). O(1), a few sin/cos calls.
DEFORM_RUNTIME_API EulerLimits prepare_limits(const DofLimits& limits) noexcept;

// Normalises `rotation` and clamps it into the limits as Skeleton::clamp_to_limits does (of its two Euler triples the
// one nearer the limits, angles in (-180°, 180°], clamped per axis, converted back), with square roots and a
// polynomial arctangent instead of trigonometric calls: the same rotation to float rounding (the tests allow 4e-6
// rad) in half the time (docs/performance.md, ik/clamp). A rotation within the limits is left as it is. Returns
// true when the rotation was outside the limits and was changed.
DEFORM_RUNTIME_API bool clamp_rotation(const EulerLimits& limits, glm::quat& rotation) noexcept;

// How an iterative solve stops and steps.
struct IkSettings {
  int max_iterations = 64;        // sweeps (CCD) or passes (FABRIK); >= 1
  float tolerance = 1e-3f;        // reached when |effector - target| <= tolerance, model units; >= 0
  float max_step_degrees = 0.0f;  // CCD only: largest rotation of one joint in one update; 0 = unlimited
  // The stall fix (CCD and FABRIK; docs/ik.md): re-aim a joint axis by axis after a clamp, and when a sweep gains
  // less than 10 % of the distance, straighten toward an out-of-reach target, then take damped least-squares steps,
  // then kick the joints randomly within their limits, keeping the best pose seen. false = the plain method.
  bool escape_stalls = true;
};

// What a solve did. The pose it leaves is the best one it found.
struct IkResult {
  bool reached = false;   // distance <= tolerance
  float distance = 0.0f;  // final |effector - target|, model units
  int iterations = 0;     // sweeps or passes run (1 for the two-bone solver)
};

// Cyclic coordinate descent (thesis §7.4.3): sweeps from the joint nearest the effector back to the root, rotating
// each joint by the quaternion that turns joint→effector onto joint→target (angle from the dot product, axis from the
// cross product), then clamping it into its Euler DOF limits (convert, clamp, convert back; §7.4.4).
class DEFORM_RUNTIME_API CcdSolver {
 public:
  // Finds the chain (throws deform::Error as make_chain does) and sizes the scratch buffers. `skeleton` must outlive
  // the solver.
  CcdSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector);

  // Moves the chain of `pose` toward `target` (world space). Returns false and leaves `pose` and `result` untouched
  // when the target or a setting is not finite or out of range, or the pose does not have bone_count() entries.
  // Cost: O(iterations × joints), no allocation.
  bool solve(Pose& pose, glm::vec3 target, const IkSettings& settings, IkResult& result);

  const IkChain& chain() const noexcept { return chain_; }

 private:
  void sweep(Pose& pose, glm::vec3 target, glm::quat base, float max_step_radians, bool reaim);  // one CCD sweep

  const Skeleton* skeleton_;
  IkChain chain_;
  std::vector<EulerLimits> limits_;  // per joint
  std::vector<glm::quat> frames_;    // world rotation per chain bone
  std::vector<glm::vec3> heads_;     // world head per chain bone
  std::vector<glm::quat> best_;      // best joint rotations seen
  std::vector<glm::dvec3> angles_;   // Euler angles per joint (stall escape)
  std::vector<glm::vec3> columns_;   // Jacobian columns, 3 per joint (stall escape)
  std::uint32_t random_state_ = 0x9e3779b9u;
};

// FABRIK (Aristidou & Lasenby 2011, "FABRIK: a fast, iterative solver for the inverse kinematics problem"): a
// backward and a forward pass over the joint positions, then the positions are turned back into local rotations joint
// by joint from the root (each the smallest rotation that points its segment at the new position), clamped into the
// DOF limits, and the chain is re-evaluated, so every pass starts from a pose within the limits.
class DEFORM_RUNTIME_API FabrikSolver {
 public:
  // As CcdSolver's constructor.
  FabrikSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector);

  // As CcdSolver::solve (max_step_degrees is ignored). Cost: O(iterations × joints), no allocation.
  bool solve(Pose& pose, glm::vec3 target, const IkSettings& settings, IkResult& result);

  const IkChain& chain() const noexcept { return chain_; }

 private:
  // One FABRIK pass and its conversion back to clamped rotations; leaves frames_ and heads_ as the new pose's FK.
  void pass(Pose& pose, glm::vec3 target, glm::quat base, float reach_length, bool reaim);

  const Skeleton* skeleton_;
  IkChain chain_;
  std::vector<EulerLimits> limits_;
  std::vector<glm::quat> frames_;
  std::vector<glm::vec3> heads_;
  std::vector<glm::vec3> goals_;   // FABRIK's joint positions
  std::vector<float> lengths_;     // segment lengths
  std::vector<glm::quat> best_;
  std::vector<glm::dvec3> angles_;
  std::vector<glm::vec3> columns_;
  std::uint32_t random_state_ = 0x9e3779b9u;
};

// The closed-form two-bone solver (thesis eqs. 14–28, generalised to 3D): the law of cosines gives the angle at the
// middle joint, the root turns the effector onto the target, and a twist about root→target puts the middle joint on
// the side of `pole`. Exact (to float rounding) for an unconstrained limb and a reachable target; an out-of-reach
// target gives the straight limb pointing at it (or, when the bones differ in length, the limb folded toward it).
// The DOF limits are applied after the closed form, so a limb whose limits cut the closed-form answer off gets the
// clamped pose, which is then not exact: `reached` says whether it still is within tolerance.
class DEFORM_RUNTIME_API TwoBoneSolver {
 public:
  // The chain root → middle → effector, each the parent of the next. Throws deform::Error as make_chain does, or when
  // the chain does not have exactly two joints.
  TwoBoneSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector);

  // Solves in one step. `pole` is a world-space direction the middle joint should bend toward (its part across the
  // line root→target counts); a zero pole, or one along that line, keeps the limb's current bend plane. A target on
  // the root folds the limb as far as it goes. Returns false and changes nothing when `target` or `pole` is not finite,
  // `tolerance` < 0, or the pose does not have bone_count() entries. O(1), no allocation.
  bool solve(Pose& pose, glm::vec3 target, glm::vec3 pole, float tolerance, IkResult& result) const;

  const IkChain& chain() const noexcept { return chain_; }

 private:
  const Skeleton* skeleton_;
  IkChain chain_;
  EulerLimits limits_[2];  // root, middle
};

}  // namespace deform
