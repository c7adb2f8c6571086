// Which limbs a character's rig stretches, and the one nearest a target (character.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "deform/character/character.hpp"

namespace deform {
namespace {

// Calls visit(bone) for every reach effector (see character.hpp), in no particular order, possibly twice.
template <class Visit>
void for_each_reach_effector(const Character& character, Visit&& visit) {
  const Skeleton& skeleton = character.skeleton();
  const DeformerHierarchy& lattices = character.deformers();
  for (std::size_t l = 0; l < lattices.lattice_count(); ++l) {
    const std::int32_t bone = lattices.spec(l).bone;
    bool below = false, above = false;
    for (std::size_t other = 0; other < lattices.lattice_count(); ++other) {
      const LatticeSpec& spec = lattices.spec(other);
      if (spec.bone == bone) continue;
      if (skeleton.is_ancestor(bone, spec.bone)) below = true;
      if (spec.carry_descendants && skeleton.is_ancestor(spec.bone, bone)) above = true;
    }
    if (above && !below) visit(bone);
  }
  const std::int32_t effector = character.rig().reach_effector;
  if (effector > 0 && std::size_t(effector) < skeleton.bone_count()) visit(effector);
  for (const Rig::ReachChain& chain : character.rig().reach_chains)
    if (chain.effector > 0 && std::size_t(chain.effector) < skeleton.bone_count()) visit(chain.effector);
}

}  // namespace

std::vector<std::int32_t> reach_effectors(const Character& character) {
  std::vector<std::int32_t> bones;
  for_each_reach_effector(character, [&](std::int32_t bone) { bones.push_back(bone); });
  std::sort(bones.begin(), bones.end());
  bones.erase(std::unique(bones.begin(), bones.end()), bones.end());
  return bones;
}

std::int32_t nearest_reach_effector(const Character& character, glm::vec3 target) {
  if (!std::isfinite(target.x) || !std::isfinite(target.y) || !std::isfinite(target.z)) return -1;
  std::int32_t nearest = -1;
  float best = std::numeric_limits<float>::infinity();
  for_each_reach_effector(character, [&](std::int32_t bone) {
    const glm::vec3 gap = character.bone_position(bone) - target;
    const float distance = glm::dot(gap, gap);
    if (distance < best || (distance == best && bone < nearest) || nearest < 0) {
      best = distance;
      nearest = bone;
    }
  });
  return nearest;
}

}  // namespace deform
