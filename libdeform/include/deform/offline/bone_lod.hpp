#pragma once
// Bone levels of detail (docs/skinning.md, "Levels of detail"): for a rigged model, which bones a distant copy of the
// character still skins with, and its skin on those bones. Offline: computed once, at bind time; allocates.
//
// Bones are merged by weight, leaves and fingers first. One greedy sequence: of the bones still kept, the candidates
// are those with no kept child that are neither a root nor in `keep`; the candidate that costs least is merged into
// its parent, which takes its skin weight (its own plus what its merged descendants gave it). A merge costs the skin
// weight it moves, summed over the points; given `poses` (the motion the levels will show), that weight times how
// far each point moves when its skinning matrix becomes the parent's (the mean over the poses): a forearm that swings
// then goes after a ponytail that hangs still, where by weight alone it goes first. Ties go to the deeper bone, then
// the higher id. Level k's kept set is a prefix of that sequence's removals,
// so the levels are nested, each kept set is closed under parents (a kept bone's parent is kept) and the roots, which
// carry the root motion, are always kept. Level 0 is the whole skeleton with the model's skin unchanged.
//
// A level's skin uses the full skeleton's bone ids (its influences name kept bones only), so it skins with the full
// palette: forward kinematics is unchanged, each point blends fewer matrices. Its points are the model's own; a level
// that later brings a simplified mesh carries its own points and a map to the full mesh's, beside these weights.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

struct BoneLodSettings {
  // Per level after level 0, the number of bones it keeps (non-increasing; at least the roots and `keep`, which a
  // smaller number is raised to). Used when not empty.
  std::vector<std::size_t> bones_per_level;
  // Else, per level after level 0, its weight-error budget, non-decreasing in [0, 1]: bones are merged while the
  // skin weight that leaves its own bone, averaged over the points (the mean over points of the weight whose bone is
  // not kept), stays within it.
  std::vector<float> weight_error;
  // Bones every level keeps besides the roots (a root-motion bone below the root, the bones a rig reaches with).
  std::vector<std::int32_t> keep;
  // Influences per point at levels after 0, strongest kept, renormalised (1 to 8; SkinningJob takes any number, its
  // four-slot kernels are fastest).
  std::size_t max_influences = 4;
  // The motion to judge merges on (see above): poses of the model's skeleton (local rotations and translations, one
  // per bone), e.g. its clips sampled over their length. Empty: by weight alone.
  std::vector<Pose> poses;
};

struct BoneLodLevel {
  // Per bone of the full skeleton, the kept bone it is merged into: itself when kept, else its nearest kept ancestor.
  std::vector<std::int32_t> bone_map;
  std::size_t kept_bones = 0;
  // The skin remapped to the kept bones, renormalised: per point, strongest first, at most max_influences (level 0:
  // the model's own weights).
  SkinWeights weights;
  // The mean over points of the skin weight whose bone is merged away (0 at level 0).
  float weight_error = 0.0f;
  // Σ over points of their influences (positive weights): the skinning's work.
  std::size_t influences = 0;
};

struct BoneLod {
  std::vector<BoneLodLevel> levels;  // levels[0]: the whole skeleton
};

// The levels for `model` (its skeleton and skin weights). Throws deform::Error (kind argument) naming the element: a
// model whose weights are not one per point or name a bone out of range ("weights"), settings with neither or both
// lists ("settings"), a level's count larger than the one before or a budget outside [0, 1] or smaller than the one
// before ("level N"), a kept bone out of range ("keep"), max_influences outside [1, 8], a pose without one finite
// rotation and translation per bone ("pose N"). Cost: O(points · influences · bones) per pose at most.
DEFORM_OFFLINE_API BoneLod build_bone_lod(const Model& model, const BoneLodSettings& settings);

// Whether `level`'s kept bones are closed under parents and every bone maps to a kept ancestor of itself or itself.
DEFORM_OFFLINE_API bool bone_lod_consistent(const Skeleton& skeleton, const BoneLodLevel& level);

}  // namespace deform
