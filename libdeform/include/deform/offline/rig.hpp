#pragma once
// Rig files: the deformer set-up of a character — its lattices, their bones, degree, vertex selection, elastic
// parameters and hierarchy, and the default reach chain — saved to and loaded from JSON (the thesis' RV04F03).
// The format is in docs/formats.md ("Rig files").
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/offline/pose_driver.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/spring_chain.hpp"

namespace deform {

// The model a rig was made for (the file's optional "model" key): the built-in character, the OBJ, .sk and .skw
// paths, or one file an importer reads (glTF, FBX, ...), as the file writes them (relative paths are relative to the
// rig file's folder). All empty: not named. At most one of builtin, obj (with skeleton and weights) and file is set.
struct RigModel {
  bool builtin = false;
  std::string obj;
  std::string skeleton;
  std::string weights;
  std::string file;  // an imported model (deform::import), e.g. "CesiumMan.glb"
  bool operator==(const RigModel&) const = default;
};

// Pose-space correctives (docs/skinning.md): shapes sculpted at poses of a few driver bones, each turned on near its
// pose by one pose driver over the group. Each shape becomes a morph target of the character's model, named as here.
struct CorrectiveShape {
  std::string name;                   // the morph target's name
  std::vector<glm::vec3> pose;        // per driver bone: its local rotation at the sculpted pose, Euler X·Y·Z degrees
  std::vector<std::uint32_t> points;  // strictly ascending
  std::vector<glm::vec3> deltas;      // bind space, one per point
  bool operator==(const CorrectiveShape&) const = default;
};
struct CorrectiveSpec {
  std::string name;                 // unique among the rig's groups
  std::vector<std::int32_t> bones;  // the driver bones, distinct
  RbfKernel kernel = RbfKernel::gaussian;
  float radius = 0.0f;  // 0 picks it (PoseDriverSettings::radius)
  float twist_weight = 1.0f;
  bool rest = true;  // the bind pose is a sample too, where every shape of the group is off
  std::vector<CorrectiveShape> shapes;
  bool operator==(const CorrectiveSpec&) const = default;
};
// The group's driver: sample poses the bind pose (when `rest`) and each shape's pose, shape s at weight 1 at its own
// pose and 0 at the others. Throws deform::Error naming the group as bind_pose_driver does.
DEFORM_OFFLINE_API PoseDriverBinding bind_corrective(const CorrectiveSpec& spec, const Skeleton& skeleton);

struct Rig {
  RigModel model;
  std::vector<LatticeSpec> lattices;
  // The chain reach() uses by default: effector bone and chain root (-1: none / chosen from the lattices).
  std::int32_t reach_effector = -1;
  std::int32_t reach_root = -1;
  // The chains reach() uses for other effectors (each root a proper ancestor of its effector; one entry per effector,
  // none the reach_effector): a foot reaches from its hip joint, not from the hips, so the body stays where it stands.
  struct ReachChain {
    std::int32_t effector = -1;
    std::int32_t root = -1;
    bool operator==(const ReachChain&) const = default;
  };
  std::vector<ReachChain> reach_chains;
  // Largest stretch reach() asks of a lattice, as a multiple of its length (>= 0).
  float max_stretch = 3.0f;
  // Spring chains (tails, hair, ears: runtime/spring_chain.hpp), the colliders they share, and their sub-step.
  std::vector<SpringChainSpec> spring_chains;
  std::vector<SpringCollider> colliders;
  float spring_substep = SpringChains::default_substep;
  std::vector<CorrectiveSpec> correctives;  // pose-space corrective groups
  bool operator==(const Rig&) const = default;
};
// What default_rig() finds in a skeleton, and why (`deform info MODEL --rig` prints it; docs/ik.md, "Default rigs").
enum class LimbKind : std::uint8_t { arm, leg, front_leg, hind_leg, neck, tail, limb };
DEFORM_OFFLINE_API const char* limb_kind_name(LimbKind kind) noexcept;
struct Limb {
  LimbKind kind = LimbKind::limb;
  int side = 0;                        // +1 the character's left, -1 its right, 0 the middle
  std::vector<std::int32_t> chain;     // the reach chain, root first (clavicle or shoulder, hip joint), effector last
  std::vector<std::int32_t> lattices;  // the bones that get an elastic lattice (upper, lower, hand or foot)
  std::string why;                     // how it was found, in words
};
struct RigSurvey {
  std::vector<Limb> limbs;  // arms (left, right), legs (left, right), then a quadruped's neck; a tail last
  // Bones left out of every limb, each with the reason: no vertex is skinned to it or below it (IK goals, poles,
  // helper roots), a helper's name (twist, IK, pole, target, control) with no skinned bone below it.
  std::vector<std::pair<std::int32_t, std::string>> skipped;
  std::int32_t pelvis = -1;        // the bone the legs (hind legs) branch from, -1 when none was found
  std::int32_t chest = -1;         // the bone the arms (front legs) branch from
  glm::vec3 up{0.0f, 1.0f, 0.0f};  // model-space up, against the legs' direction in the bind pose
  bool four_legged = false;
  std::string naming;  // the name map that matched ("Mixamo", "Blender" (rigify, metarig), "Unreal mannequin", "VRM",
                       // "generic"), or "none": found from the structure alone
};
// Finds the limbs of a rigged model from its skeleton's structure and skin weights, names as hints that win when
// present. Structure: helpers (bones no vertex is skinned to, directly or below them, and twist/IK/pole bones by
// name) are set aside; limbs are mirrored pairs of branches (the same bone count and extent, tips apart) of at least
// half the largest pair's extent; the pair nearer the skeleton's root is the legs; along each limb the two longest
// consecutive bones are the upper and lower limb, the next the hand or foot; a bone before an arm's upper arm is its
// clavicle. A creature whose front limbs end near the floor (within 30% of the pelvis' height) is four-legged and
// gets a neck (from the chest's remaining branch) and a tail (from the pelvis' remaining branch). Sides: names, else
// +X is the character's left. Names (Mixamo `mixamorig:LeftHand`, rigify `DEF-hand.L`, Unreal `hand_l`, VRM
// `leftHand` or `J_Bip_L_Hand`, and generic hand/wrist/foot/ankle words) choose the hand or foot on a limb and find
// limbs the structure missed. Allocates; O(bones² + points).
DEFORM_OFFLINE_API RigSurvey survey_rig(const Model& model);

// A rig for any rigged model, so an imported character stretches and reaches: survey_rig()'s limbs each get elastic
// lattices on their upper, lower and end bone (those carrying skin weight), reach chains from the clavicle or
// shoulder and from the hip joint (Rig::reach_chains), the reach effector the left hand (else the first limb's end);
// a tail a spring chain. With `effector` >= 0 that bone is the reach effector: when it ends no limb, its limb is the
// bone and its two nearest ancestors that carry skin weight, reaching from the bone above them. When no limb is found
// the deepest bone with skin weight is the effector. (The built-in character has a rig of its own: builtin_rig() in
// extras.) Throws deform::Error when no bone carries skin weight or `effector` is out of range.
DEFORM_OFFLINE_API Rig default_rig(const Model& model, std::int32_t effector = -1);
}  // namespace deform
