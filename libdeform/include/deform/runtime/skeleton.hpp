#pragma once
// Skeleton: a bone hierarchy with bind transforms and DOF limits, poses, forward kinematics, skin weights.
// io/sk.hpp reads and writes them as .sk and .skw files, io/pose_json.hpp poses as JSON.
//
// Conventions (stated in docs/formats.md; fixed, because they decide every number downstream):
//  - a bone's local transform is L = T(t) · Rx(rx) · Ry(ry) · Rz(rz), column vectors, angles in degrees;
//    as a quaternion, q = qx · qy · qz.
//  - world W = W_parent · L; a bone's head is W · (0,0,0,1).
//  - DOF limits bound the local Euler angles, per axis, in degrees; min == max locks an axis.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"

namespace deform {

// Per-axis limits of a bone's local Euler angles, degrees. Free = [-180, 180] on every axis.
struct DofLimits {
  glm::vec3 min{-180.0f};
  glm::vec3 max{180.0f};
  bool operator==(const DofLimits&) const = default;
};

struct Bone {
  std::string name;                    // may be empty or shared; ids are the reference
  std::int32_t parent = -1;            // id of the parent, -1 for the root
  std::vector<std::int32_t> children;  // ids, in file order
  glm::vec3 bind_translation{0.0f};    // relative to the parent
  glm::vec3 bind_rotation{0.0f};       // Euler X·Y·Z, degrees, relative to the parent
  DofLimits limits;
  bool operator==(const Bone&) const = default;
};

// A pose: each bone's local rotation and translation (relative to its parent). Index = bone id.
struct Pose {
  std::vector<glm::quat> rotations;
  std::vector<glm::vec3> translations;
};

class DEFORM_RUNTIME_API Skeleton {
 public:
  Skeleton() = default;
  // Takes the bones as given and validates them: 1 to 65535 bones, exactly one root and it is bone 0 (parent -1),
  // parents in range, no cycles, child lists that agree with the parent ids (each non-root bone listed exactly once,
  // by its parent), limits with min <= max, every number finite, and bind transforms that stay finite along every
  // chain (translations near 3e38 overflow). Throws deform::Error naming `source` and the bone.
  // Cost: O(bones + children); computes order() and the bind matrices once.
  explicit Skeleton(std::vector<Bone> bones, const std::string& source = "<memory>");

  std::span<const Bone> bones() const noexcept { return bones_; }
  const Bone& bone(std::int32_t id) const { return bones_.at(static_cast<std::size_t>(id)); }
  std::size_t bone_count() const noexcept { return bones_.size(); }
  // Bone ids with every parent before its children (bone 0 first). FK runs in this order.
  std::span<const std::int32_t> order() const noexcept { return order_; }

  // Id of the first bone with this name, or of bone ID for "#ID"; -1 if none.
  std::int32_t find(std::string_view name) const noexcept;
  // The name a pose or the CLI uses for a bone: its name, or "#ID" when the name is empty, shared or starts with '#'.
  std::string key(std::int32_t id) const;
  // True if `ancestor` is `bone` or one of its ancestors.
  bool is_ancestor(std::int32_t ancestor, std::int32_t bone) const noexcept;

  // The bind pose (file translations and rotations).
  Pose bind_pose() const;
  // Bind-pose world matrices (T_B of thesis eq. 13) and their inverses, computed once at construction.
  std::span<const glm::mat4> bind_world() const noexcept { return bind_world_; }
  std::span<const glm::mat4> inverse_bind_world() const noexcept { return inverse_bind_world_; }

  // Sets the bone's local rotation from Euler angles (degrees, X·Y·Z); clamps them into the bone's limits first
  // unless `clamp` is false. Returns the angles actually used.
  glm::vec3 set_euler(Pose& pose, std::int32_t bone, glm::vec3 degrees, bool clamp = true) const;
  // Clamps the bone's current local rotation into its DOF limits (convert to Euler, clamp, convert back). Of the two
  // Euler triples of a rotation it clamps the one nearer to the limits, so an in-limit rotation is left unchanged;
  // each angle is taken modulo 360 to the value nearest its range, so it goes to its nearer limit around the circle.
  void clamp_to_limits(Pose& pose, std::int32_t bone) const;

 private:
  std::vector<Bone> bones_;
  std::vector<std::int32_t> order_;
  std::vector<glm::mat4> bind_world_;
  std::vector<glm::mat4> inverse_bind_world_;
  std::vector<std::int32_t> by_name_;      // bone ids sorted by (name, id), for find()
  std::vector<std::uint8_t> unique_name_;  // per bone: 1 when key() is its name, 0 when it is "#ID"
};

// --- Euler angles (X·Y·Z, degrees) ---

// q = qx(x) · qy(y) · qz(z), i.e. the rotation of Rx · Ry · Rz.
DEFORM_RUNTIME_API glm::quat quat_from_euler(glm::vec3 degrees) noexcept;
// The inverse of quat_from_euler with angles in [-180, 180] and y in [-90, 90]; robust at y = ±90° (gimbal lock:
// the whole X/Z rotation is put on x, z = 0), never NaN for a unit or near-unit quaternion.
DEFORM_RUNTIME_API glm::vec3 euler_from_quat(glm::quat q) noexcept;
// Clamps each angle into [min, max] of its axis. A NaN angle becomes the angle of [min, max] nearest 0 (never NaN).
DEFORM_RUNTIME_API glm::vec3 clamp_euler(glm::vec3 degrees, const DofLimits& limits) noexcept;
// The Euler angles (degrees, X·Y·Z) of `rotation` that `limits` mean, always within them: of the rotation's two
// triples (x, y, z) and (x + 180, 180 - y, z + 180), each angle taken modulo 360 to the value nearest its axis'
// range, the one nearer the limits (summed over the axes; the first on a tie). Within the limits (as a solver or
// clamp_to_limits leaves a rotation, to float rounding) that triple is the rotation. Outside them, the nearest
// limit of x, then y refitted to it and clamped, then z refitted to both and clamped: at y = ±90° (gimbal lock,
// where only x ± z is defined) x goes to the value within its limits nearest the triple's that leaves the remainder
// for z within z's limits, where one exists. So quat_from_euler of the result is the
// rotation itself when it is within the limits (to 1e-5 rad; float rounding far from gimbal lock), and whatever is
// printed from it reads back unchanged through set_euler's clamp. Limits within [-180, 180]; a non-unit rotation is
// normalised, a zero or non-finite one reads as the identity. Double precision, a few atan2 calls.
DEFORM_RUNTIME_API glm::vec3 euler_within_limits(glm::quat rotation, const DofLimits& limits) noexcept;
// True when every angle is within its axis' limits (with `slack` degrees of tolerance).
DEFORM_RUNTIME_API bool within_limits(glm::vec3 degrees, const DofLimits& limits, float slack = 1e-3f) noexcept;

// --- forward kinematics ---

// Local matrix L = T · R of one bone of a pose.
DEFORM_RUNTIME_API glm::mat4 local_matrix(glm::quat rotation, glm::vec3 translation) noexcept;

// Forward kinematics (the per-frame job): every bone's model-space ("world") matrix W = W_parent · L, and optionally
// its skinning matrix T_C = W · T_B⁻¹ (thesis eq. 13), the palette SkinningJob reads. The elements are the bones in
// skeleton->order() (parents first): run(begin, end) computes order()[begin, end), reading the world matrices of
// parents outside the range from `world` as an earlier run left them. Rotations are unit quaternions (as a Pose
// holds them); no allocation, no exceptions; O(bones).
struct DEFORM_RUNTIME_API LocalToWorldJob {
  const Skeleton* skeleton = nullptr;
  std::span<const glm::quat> rotations;     // local, bone_count() entries, index = bone id
  std::span<const glm::vec3> translations;  // local, bone_count() entries
  std::span<glm::mat4> world;               // out: bone_count() entries
  std::span<glm::mat4> palette;             // out, optional: empty, or bone_count() entries

  // The skeleton is set, every span has bone_count() entries (the palette may be empty) and every rotation and
  // translation is finite. O(bones).
  Status validate() const noexcept;
  // The size checks of validate() (O(1)) and the finiteness of the pose entries it reads (O(bones), a fraction of the
  // matrix products); on failure writes nothing.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  // bone_count(), 0 without a skeleton.
  std::size_t count() const noexcept;
};

// Skin weights, index = point (OBJ `v`) index. Every point has four slots, strongest first; unused slots have weight
// 0 and bone 0. A point with more than four influences keeps its four strongest in the slots and the rest in the
// `extra_*` arrays (compressed sparse rows over the few points that need them): extra_points lists those points in
// ascending order, and the influences of extra_points[j] past the fourth are extra_bones / extra_weights
// [extra_offsets[j], extra_offsets[j + 1]). The four slots and the extras together sum to 1 (importers normalise);
// without extras the slots alone do. SkinningJob takes the extras as they are (its general path, skinning.hpp).
// Formats that hold four influences (.skw) keep only the slots: see drop_extra_influences.
inline constexpr int max_influences = 4;
// The most influences per point that the .skw reader and the heat weights keep when asked for more than four.
inline constexpr int max_requested_influences = 16;
struct SkinWeights {
  std::vector<glm::u16vec4> bones;
  std::vector<glm::vec4> weights;
  std::vector<std::uint32_t> extra_points;   // ascending; empty when every point has at most four influences
  std::vector<std::uint32_t> extra_offsets;  // extra_points.size() + 1 entries, starting at 0; empty with no extras
  std::vector<std::uint16_t> extra_bones;
  std::vector<float> extra_weights;
  std::size_t size() const noexcept { return bones.size(); }
  bool has_extra() const noexcept { return !extra_points.empty(); }
  bool operator==(const SkinWeights&) const = default;
};

// Appends one point's influences (any number, any order, weights >= 0, not necessarily normalised; a bone listed
// twice has its weights summed): sorted strongest first (ties: lower bone first), zero weights dropped, normalised
// to sum 1; the first four go to the slots, the rest to the extras. A point with no positive weight gets bone
// `fallback_bone` with weight 1. Returns the number of influences kept.
DEFORM_RUNTIME_API std::size_t append_influences(SkinWeights& weights, std::span<const std::uint16_t> bones,
                                                 std::span<const float> values, std::uint16_t fallback_bone = 0);
// Keeps the four strongest influences of every point, renormalised to sum 1, and clears the extras (for formats and
// consumers that hold four). Returns the number of points that lost influences and, in `largest_dropped`, the
// largest weight dropped (as a fraction of its point's total).
DEFORM_RUNTIME_API std::size_t drop_extra_influences(SkinWeights& weights, float* largest_dropped = nullptr);
// The number of influences of point `p` with a positive weight, extras included.
DEFORM_RUNTIME_API std::size_t influence_count(const SkinWeights& weights, std::size_t p) noexcept;

}  // namespace deform
