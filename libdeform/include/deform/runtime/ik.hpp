#pragma once
// Inverse kinematics: move a chain of bones so that its effector reaches a target point (thesis ch. 7).
//
// A chain runs from a root bone down to an effector bone (the root is an ancestor of the effector). Its *joints* are
// the chain's bones except the effector (the effector's own rotation does not move its head), so a "k-bone chain"
// has k joints and k + 1 bones; a two-bone limb is shoulder, elbow and wrist. Two steps, as everywhere in libdeform:
//  - bind (once, allocates): make_chain finds the bones and prepares the joints' DOF limits into an IkChain, a plain
//    movable value that points at nothing;
//  - solve (per frame): an IkJob (CCD or FABRIK) or a TwoBoneIkJob reads the chain, the model-space transform of the
//    root's parent (its base), the pose's local rotations and translations and the target, and writes the joints'
//    local rotations. No allocation, no exceptions, no I/O; scratch memory is the caller's.
// Every solve
//  - starts from the pose it is given and changes only the local rotations of the chain's joints (a two-bone solve
//    also writes its stretched translations, into a span of their own);
//  - leaves every joint inside its DOF limits (the starting pose is clamped first);
//  - minimises the effector–target distance when the target is out of reach (an unconstrained chain ends straight,
//    pointing at the target), unless a two-bone solve is told to soften.
// docs/ik.md describes the algorithms, their guarantees and measured behaviour.
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// A joint's DOF limits prepared once for clamping per frame (prepare_limits): the bounds in radians and as unit
// (cos, sin) directions, so that clamp_rotation needs no sin, cos or atan2 call. An IkChain holds one per joint.
// The default is free, as DofLimits{}.
struct EulerLimits {
  glm::dvec3 min{-std::numbers::pi}, max{std::numbers::pi};      // radians, DofLimits' bounds
  glm::dvec2 min_dir[3]{{-1.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}};  // (cos, sin) of min per axis
  glm::dvec2 max_dir[3]{{-1.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}};  // (cos, sin) of max per axis
  bool free = true;  // min <= -180° and max >= 180° on every axis: every rotation is within the limits
  // Per axis, cos(max − min), or 2 for a range of 360° or more (which every direction lies within): whether a
  // direction lies within the range is then a dot and a cross product, no arctangent (the clamp's test for a
  // rotation that needs no clamping).
  glm::dvec3 cos_width{2.0};
  bool wide[3]{true, true, true};  // max − min > 180°
};

// The prepared form of `limits` (degrees, X·Y·Z as in docs/formats.md). O(1), a few sin/cos calls.
DEFORM_RUNTIME_API EulerLimits prepare_limits(const DofLimits& limits) noexcept;

// Normalises `rotation` and clamps it into the limits as Skeleton::clamp_to_limits does (of its two Euler triples the
// one nearer the limits, angles in (-180°, 180°], clamped per axis, converted back), with square roots and a
// polynomial arctangent instead of trigonometric calls: the same rotation to float rounding (the tests allow 4e-6
// rad) in half the time (docs/performance.md, ik/clamp). A rotation within the limits is left as it is. An axis
// outside goes to its nearer limit around the circle. Returns true when the rotation was outside the limits and was
// changed. A zero or non-finite rotation (NaN) becomes the identity clamped into the limits (true): never NaN.
DEFORM_RUNTIME_API bool clamp_rotation(const EulerLimits& limits, glm::quat& rotation) noexcept;

// Swing-twist limits of a joint, the alternative to Euler min/max. A joint's local rotation q (relative to its parent,
// the identity being its rest, as for Euler limits) is split about the bone's rest axis `axis` (a unit vector in the
// joint's frame; normally the direction of its child's translation) with q taken with w >= 0:
//   twist = the rotation about `axis` by τ = 2 atan2(q.xyz · axis, q.w), in (-180°, 180°] (identity when q is a
//           half turn about an axis perpendicular to `axis`, where the split is not defined);
//   swing = q · twist⁻¹, a rotation by θ in [0°, 180°] about a unit axis u perpendicular to `axis`; q = swing · twist.
// The swing's rotation vector θ u has components (s1, s2) = θ (u · reference, u · (axis × reference)); the swing is
// within the elliptical cone when (s1 / swing1)² + (s2 / swing2)² <= 1 (swing1 = swing2: a circular cone of that
// half-angle; a zero half-angle allows no swing about that direction); the twist when τ is within [twist_min,
// twist_max]. Projection (clamp_swing_twist) moves (s1, s2) to the nearest point of the ellipse in that plane (for a
// circular cone: the same swing axis, the angle cut to the cone) and τ to its nearer limit around the circle.
struct SwingTwistLimits {
  glm::vec3 axis{1.0f, 0.0f, 0.0f};                                                     // unit, the joint's frame
  glm::vec3 reference{0.0f, 1.0f, 0.0f};                                                // unit, perpendicular to axis
  float swing1 = std::numbers::pi_v<float>, swing2 = std::numbers::pi_v<float>;         // radians, [0, π]
  float twist_min = -std::numbers::pi_v<float>, twist_max = std::numbers::pi_v<float>;  // radians, within [-π, π]
  bool active = false;  // an IkChain joint uses these instead of its Euler limits
};

// Swing-twist limits about `axis` (any non-zero vector; (1, 0, 0) when zero or not finite) with a reference direction
// chosen perpendicular to it (the coordinate axis least aligned with it, made perpendicular), half-angles and the
// twist range in degrees (clamped to [0, 180] and [-180, 180]; twist_min > twist_max are swapped). active is true.
DEFORM_RUNTIME_API SwingTwistLimits make_swing_twist_limits(glm::vec3 axis, float swing1_degrees, float swing2_degrees,
                                                            float twist_min_degrees, float twist_max_degrees) noexcept;
// Swing-twist limits standing in for Euler ones (`deform ik --limits swing-twist`): about the bone axis `axis`, the
// twist range is the Euler range of the coordinate axis nearest `axis` (X, Y or Z; its sign flips the range), and
// the cone's half-angles (reference = the next coordinate axis in X→Y→Z order, made perpendicular) are the larger
// |bound| of each of the other two axes' ranges, at most 180°: a cone that holds every swing the Euler limits allow
// about those axes alone.
DEFORM_RUNTIME_API SwingTwistLimits swing_twist_from_euler(const DofLimits& limits, glm::vec3 axis) noexcept;
// The swing's rotation-vector components and the twist of `rotation` under `limits`' split: (s1, s2, τ), radians.
// A zero or non-finite rotation reads as the identity.
DEFORM_RUNTIME_API glm::vec3 swing_twist_angles(const SwingTwistLimits& limits, glm::quat rotation) noexcept;
// Normalises `rotation` and projects it onto the limits (see SwingTwistLimits; `active` is not read). A rotation
// within them is left as it is (normalised); projecting is idempotent to float rounding. Returns true when it was
// outside and was changed. A zero or non-finite rotation becomes the identity projected (true). O(1), a Newton
// solve of at most 32 steps for an elliptical cone.
DEFORM_RUNTIME_API bool clamp_swing_twist(const SwingTwistLimits& limits, glm::quat& rotation) noexcept;

// The bones of a chain and its joints' prepared limits, made once (make_chain). bones[0] is the root, bones.back() the
// effector, each the parent of the next; `ancestors` are the bones above the root, from bone 0 down to the root's
// parent (chain_base multiplies their transforms); `limits` has one entry per joint, in chain order.
struct IkChain {
  std::vector<std::int32_t> bones;
  std::vector<std::int32_t> ancestors;
  std::vector<EulerLimits> limits;
  // Empty (every joint has Euler limits), or one entry per joint: a joint whose entry is active is limited by it
  // instead of by its Euler entry, which set_swing_twist makes free (so that the solvers' Euler steps leave the
  // joint alone and the projection decides).
  std::vector<SwingTwistLimits> swing_twist;
  std::int32_t max_bone = -1;  // the largest id in bones and ancestors: pose spans need more entries than this
  std::size_t joint_count() const noexcept { return bones.empty() ? 0 : bones.size() - 1; }
};

// Gives joint `joint` (chain order) the swing-twist `limits` (stored active) and makes its Euler entry free.
// Allocates swing_twist (joint_count() inactive entries) on first use. Throws deform::Error when `joint` is not a
// joint of the chain. (make_chain again restores the skeleton's Euler limits.)
DEFORM_RUNTIME_API void set_swing_twist(IkChain& chain, std::size_t joint, const SwingTwistLimits& limits);

// Most bones a chain may have (255 joints and the effector).
inline constexpr std::size_t max_chain_bones = 256;

// The chain from `root` to `effector` (bone ids) with the skeleton's DOF limits prepared. Throws deform::Error naming
// the effector when an id is out of range, when `root` is not a proper ancestor of `effector`, or when the chain has
// more than max_chain_bones bones. Allocates; O(skeleton depth).
DEFORM_RUNTIME_API IkChain make_chain(const Skeleton& skeleton, std::int32_t root, std::int32_t effector);
// make_chain into `chain`'s own storage, for a caller that switches chains while it runs: no allocation when the
// vectors' capacities hold the chain (reserve max_chain_bones bones and joints and the skeleton's depth in
// ancestors to be sure). Returns a failure, leaving `chain` empty, where make_chain throws. O(skeleton depth).
DEFORM_RUNTIME_API Status assign_chain(IkChain& chain, const Skeleton& skeleton, std::int32_t root,
                                       std::int32_t effector);

// The chain's reach from the root's head: the sum of the joints' segment lengths (|translation| of each chain bone
// after the root). A target farther than this from the root's head is out of reach. `translations` is indexed by
// bone id (a Pose's); 0 when it has max_bone or fewer entries. O(chain).
DEFORM_RUNTIME_API float chain_length(const IkChain& chain, std::span<const glm::vec3> translations) noexcept;

// A rigid model-space transform, p_model = rotation · p + translation: how an IK job places its chain (the transform
// of the chain root's parent, the "base").
struct DEFORM_RUNTIME_API RigidTransform {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // unit
  glm::vec3 translation{0.0f};
  // The rotation (normalised) and translation of a rigid matrix, such as a bone's LocalToWorldJob output.
  static RigidTransform from_matrix(const glm::mat4& matrix) noexcept;
  glm::mat4 matrix() const noexcept;
};

// The model-space transform of the chain root's parent (the identity when the root is bone 0), by forward kinematics
// of the ancestors alone on quaternions: the base for a caller without this frame's world matrices (one with them
// passes RigidTransform::from_matrix(world[parent]), the same transform to float rounding). Spans indexed by bone id;
// fails, writing nothing, when they have max_bone or fewer entries. O(ancestors), no allocation.
DEFORM_RUNTIME_API Status chain_base(const IkChain& chain, std::span<const glm::quat> rotations,
                                     std::span<const glm::vec3> translations, RigidTransform& base) noexcept;

// The model-space position of the effector's head (forward kinematics of the ancestors and the chain only, on
// quaternions, as chain_base), into `position`. Spans indexed by bone id. Refuses, writing nothing, a chain with no
// bones or spans that do not hold every bone of the chain and its ancestors. O(depth of the effector), no allocation.
DEFORM_RUNTIME_API Status effector_position(const IkChain& chain, std::span<const glm::quat> rotations,
                                            std::span<const glm::vec3> translations, glm::vec3& position) noexcept;

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

// The stall escape's random kicks (xorshift32) start from this state unless a job carries its own (random_state).
inline constexpr std::uint32_t ik_random_seed = 0x9e3779b9u;

enum class IkMethod : std::uint8_t {
  // Cyclic coordinate descent (thesis §7.4.3): sweeps from the joint nearest the effector back to the root, rotating
  // each joint by the quaternion that turns joint→effector onto joint→target (angle from the dot product, axis from
  // the cross product), then clamping it into its Euler DOF limits (convert, clamp, convert back; §7.4.4).
  ccd,
  // FABRIK (Aristidou & Lasenby 2011, "FABRIK: a fast, iterative solver for the inverse kinematics problem"): a
  // backward and a forward pass over the joint positions, then the positions are turned back into local rotations
  // joint by joint from the root (each the smallest rotation that points its segment at the new position), clamped
  // into the DOF limits, and the chain is re-evaluated, so every pass starts from a pose within the limits.
  fabrik,
};

// One iterative solve of a chain (the per-frame job). Poses are a Pose's spans (index = bone id); only the chain's
// joints' rotations are written. The solve is one sequential iteration: count() is 1 and run(begin, end) solves when
// the range holds element 0 (an engine runs many chains or characters side by side instead).
struct DEFORM_RUNTIME_API IkJob {
  IkMethod method = IkMethod::ccd;
  const IkChain* chain = nullptr;           // at least one joint
  RigidTransform base;                      // model-space transform of the root's parent (chain_base), finite
  std::span<glm::quat> rotations;           // in/out: local rotations, more than chain->max_bone entries
  std::span<const glm::vec3> translations;  // local translations, as many
  glm::vec3 target{0.0f};                   // model space
  IkSettings settings;
  std::span<std::byte> scratch;  // scratch_size() bytes or more, aligned to scratch_alignment
  // In/out, optional: the stall escape's generator state, carried from solve to solve. Null: every solve starts from
  // ik_random_seed, so equal inputs give equal outputs.
  std::uint32_t* random_state = nullptr;
  IkResult* result = nullptr;  // out, optional
  // Optional pole (hint), model space, used when `use_pole`: the point the chain's middle (the mean of the heads of
  // the joints after the root; a one-joint chain has none) bends toward. Applied after the solve as a swivel of the
  // whole chain about the line from the root's head to the effector's head, which leaves the effector where it is:
  // the root joint turns about that line until the middle lies in the half-plane of the pole. The root's limits may
  // cut the swivel short; it is kept only as far as it leaves the target reached (or, unreached, no farther away),
  // trying the whole angle, then half, a quarter and an eighth of it. While the middle is still not on the pole's
  // side (a clavicle root turns little), the next joint does the same for the rest of the chain about its own line to
  // the effector, and so on. When the limits still keep the middle off the pole's side, the pole seeds a second
  // solve: the swivel is applied whole (clamped, losing the target for a moment) and the solver starts again from
  // there; its answer is kept when its middle faces the pole and it reaches the target as well as the first (or
  // comes no farther from it), else the first stands. A pole on the line, or a chain whose middle is on it
  // (straight), swivels nothing. Cost: at most one more solve, only with a pole.
  glm::vec3 pole{0.0f};
  bool use_pole = false;
  // How much of the solve is applied, in [0, 1]: each joint's rotation becomes the shortest-path slerp from its input
  // rotation to the solved one by `weight`, clamped into its limits; result describes that pose. 1 (default) is the
  // solve; 0 writes nothing to the pose (bit-identical, not even clamped), its result describing the input pose
  // (iterations 0).
  float weight = 1.0f;

  static constexpr std::size_t scratch_alignment = alignof(double);
  // Scratch bytes a solve of a chain of `joint_count` joints needs, either method: 168 per joint + 40.
  static constexpr std::size_t scratch_size(std::size_t joint_count) noexcept { return 168 * joint_count + 40; }
  // scratch_size for this job's chain (0 without one).
  std::size_t scratch_size() const noexcept;

  // Why run() would refuse: no chain or one without joints, spans too short, a setting out of range (see IkSettings),
  // the scratch too small or misaligned, a non-finite target, base, pole (when used), chain rotation or translation,
  // a weight outside [0, 1] or NaN, or a chain whose length overflows. O(chain).
  Status validate() const noexcept;
  // validate(), then the solve. On failure writes nothing (neither the pose nor result nor random_state). Cost:
  // O(iterations × joints), no allocation.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  std::size_t count() const noexcept { return 1; }
};

// How TwoBoneIkJob::pole is read.
enum class PoleKind : std::uint8_t {
  direction,  // a model-space direction (ozz-animation's pole vector)
  point,      // a model-space point (a rig's knee or elbow target): the direction from the root's head to it
};

// Sine of the cone about the line root → target inside which the pole hands the bend plane over to the pose's
// (TwoBoneIkJob, "Pole"): 0.25, about 14.5°.
inline constexpr float two_bone_pole_cone_sine = 0.25f;

// The closed-form two-bone solve (thesis eqs. 14–28, generalised to 3D) with what a rigger sets on a limb: a pole,
// a swivel, soft extension, stretch and a weight. For a chain of exactly two joints (root → middle → effector, bone
// lengths a = |translation of the middle bone| and b = |translation of the effector bone|, both > 0):
//  1. the reachable distance c (Soften) and the stretch factor s (Stretch) are chosen from r = |target − root head|;
//  2. the middle joint opens or closes about the limb's current bend axis until |effector − root| = c (law of
//     cosines); a straight or folded start bends about the axis toward the pole (else about the middle joint's
//     widest-ranging Euler axis across the bone, a hinge, signed toward the side its range allows);
//  3. the root turns the effector onto the line root → target (shortest arc), then twists about that line so that
//     the middle joint lies in the half-plane of the bend reference (Pole), turned by swivel_degrees;
//  4. each joint is clamped into its DOF limits (the closed form does not know them: when they cut it off the pose is
//     the clamped one, not exact, and `reached` says so);
//  5. the rotations are blended with the input pose by `weight` (Weight) and clamped again.
// Soften. With L = a + b and soften k in [0, 1], the limb's root–effector distance is c = r up to r = L − kL, and
// beyond it c = L − kL·exp((L − r)/(kL) − 1): continuous with its first derivative, increasing in r, decreasing in k,
// and below L for every finite r (until it rounds to L, some 15 zones beyond), so the knee approaches straight
// asymptotically instead of snapping. k = 0 gives
// c = min(r, L) (no softening). c is then kept at least |a − b| (the folded limb). (ozz's soften ratio is 1 − k.)
// Stretch. With max_stretch S >= 1: s = clamp(r / c, 1, S), so the limb lengthens exactly when the (softened) limb
// falls short of the target; both bones are scaled by s (the bend angle is c's, unchanged), so with s < S the
// effector reaches the target. s is output (`stretch`) and, when `stretched_translations` is given, the middle and
// effector bones' local translations times s are written there: forward kinematics of the written rotations with
// those translations puts the effector at the target whenever r <= S·c. Without stretched_translations the caller
// applies s itself (scale those two translations, or leave the bones and show the stretch otherwise, as an elastic
// lattice); `result` describes the stretched limb either way. S = 1 (the default) never stretches.
// Pole. The bend reference is the pole's part across the line root → target (the pole is a direction or, with
// PoleKind::point, the direction from the root's head to the point). Where the target passes near the pole's line
// that part shrinks to nothing and turns by 180° across it, which flips the knee of a plain pole solve; so inside the
// cone about the line whose sine is two_bone_pole_cone_sine, the reference is blended (smoothstep of sine / cone
// sine, as vectors) into the limb's own bend direction after step 3's aim (the input pose's plane), which it equals
// on the line: as the target crosses the line the middle joint swings over to the pole's new side continuously,
// spread over the cone (the tests bound its swing at 40× the target's turn; a flip is a jump). A zero pole uses the
// input pose's plane throughout. Some target direction must remain where the bend direction jumps (a direction
// across the line cannot turn continuously over every target direction): here it is one direction per end of the
// line, at sine cone/2 from it on the side the pose bends toward, where the pole's part is exactly opposite the
// pose's bend at half blend (the pose's plane is kept there). A rig whose targets do pass there can put the pole to
// the limb's side with swivel_degrees = ±90 (the "no-flip" setup), which moves these directions to where the limb
// points along the pole.
// Swivel. The reference is then turned by swivel_degrees about root → target (right-handed): the bend plane's angle
// a rigger dials in, with or without a pole.
// Weight. Each joint's local rotation becomes slerp(input, solved, weight): the input turned by that fraction of the
// shortest rotation to the solved one (the correction solved · input⁻¹ scaled by weight, as IkJob's weight), then
// clamped into its limits; the stretch is 1 + weight·(s − 1). weight = 0 writes no rotation (the pose stays
// bit-identical) and a stretch of 1.
// Degenerate cases. A target on the root keeps the limb's direction and folds it as far as it goes (c = |a − b|,
// or soften's value); a bone of (nearly) zero length is refused by validate().
// Result: `reached` when the effector — of the written rotations, with the stretch applied — lies within tolerance
// of the target; `distance` is that remaining distance. count() is 1, as IkJob's.
struct DEFORM_RUNTIME_API TwoBoneIkJob {
  const IkChain* chain = nullptr;           // exactly two joints: root → middle → effector
  RigidTransform base;                      // model-space transform of the root's parent (chain_base), finite
  std::span<glm::quat> rotations;           // in/out: local rotations, more than chain->max_bone entries
  std::span<const glm::vec3> translations;  // local translations, as many; the bones' rest lengths are read here
  glm::vec3 target{0.0f};                   // model space
  glm::vec3 pole{0.0f};                     // model space, read as pole_kind says; zero: the pose's bend plane
  PoleKind pole_kind = PoleKind::direction;
  float swivel_degrees = 0.0f;  // turn of the bend plane about root → target, in [-360, 360]
  float soften = 0.0f;          // fraction of the reach over which full extension is approached, in [0, 1]
  float weight = 1.0f;          // blend of the solve with the input pose, in [0, 1]
  float max_stretch = 1.0f;     // largest factor on the bones' lengths, finite and >= 1; 1 = rigid bones
  float tolerance = 1e-3f;      // reached when |effector - target| <= tolerance; >= 0
  // Out, optional: as many entries as `translations`, or empty. When given, only the middle and effector bones'
  // entries are written: their translations times the stretch. It may view the same storage as `translations` if
  // the caller puts the rest translations back before the next solve (they are the lengths it reads).
  std::span<glm::vec3> stretched_translations;
  IkResult* result = nullptr;  // out, optional (iterations = 1)
  float* stretch = nullptr;    // out, optional: the stretch factor applied, in [1, max_stretch]

  // Why run() would refuse: no chain or not two joints, swing-twist limits on a joint (Euler limits only here),
  // spans too short, a non-finite target, pole, base, chain
  // rotation or translation, a bone of zero length (shorter than 1e-6 of the limb), a parameter outside the range
  // its comment gives. O(1).
  Status validate() const noexcept;
  // validate(), then the solve; on failure writes nothing. O(1), no allocation.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  std::size_t count() const noexcept { return 1; }
};

}  // namespace deform
