// A rig for any rigged model: elastic lattices on one limb, found by bone names or, failing that, by depth.
#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/offline/rig.hpp"
#include "deform/io/rig_json.hpp"
namespace deform {
namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return text;
}

bool names_left(const std::string& name) {
  return name.find("left") != std::string::npos || name.ends_with("_l") || name.ends_with(".l") ||
         name.find("_l_") != std::string::npos || name.starts_with("l_");
}

// The first bone whose lower-cased name contains `word`, a left one first; -1 if none.
std::int32_t find_named(const Skeleton& skeleton, const char* word) {
  std::int32_t any = -1;
  for (std::size_t b = 0; b < skeleton.bone_count(); ++b) {
    const std::string name = lower(skeleton.bone(std::int32_t(b)).name);
    if (name.find(word) == std::string::npos) continue;
    if (names_left(name)) return std::int32_t(b);
    if (any < 0) any = std::int32_t(b);
  }
  return any;
}

}  // namespace

Rig default_rig(const Model& model, std::int32_t effector) {
  const Skeleton& skeleton = model.skeleton;
  const auto bones = static_cast<std::int32_t>(skeleton.bone_count());
  if (effector >= bones) throw Error::in_file(model.name, "bone " + std::to_string(effector), "no such bone");

  // Skin weight carried by each bone and, summed up the hierarchy, by its subtree: a lattice needs points to bind.
  std::vector<double> own(std::size_t(bones), 0.0), subtree;
  for (std::size_t p = 0; p < model.weights.size(); ++p)
    for (int i = 0; i < max_influences; ++i)
      if (model.weights.bones[p][i] < bones) own[model.weights.bones[p][i]] += model.weights.weights[p][i];
  subtree = own;
  const auto order = skeleton.order();
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (const std::int32_t parent = skeleton.bone(*it).parent; parent >= 0)
      subtree[std::size_t(parent)] += subtree[std::size_t(*it)];
  const auto depth = [&](std::int32_t b) {
    int d = 0;
    while ((b = skeleton.bone(b).parent) >= 0) ++d;
    return d;
  };

  if (effector < 0) effector = find_named(skeleton, "hand");
  if (effector < 0) effector = find_named(skeleton, "wrist");
  if (effector < 0)
    for (std::int32_t b = 0; b < bones; ++b)
      if (own[std::size_t(b)] > 0.0 && (effector < 0 || depth(b) > depth(effector))) effector = b;
  if (effector < 0) throw Error::in_file(model.name, "", "no bone carries skin weight, so no lattice can be bound");

  // Up the limb from the effector: the first three bones with weight of their own get a lattice each.
  Rig rig;
  rig.reach_effector = effector;
  std::int32_t top = -1;
  for (std::int32_t b = effector; b >= 0 && rig.lattices.size() < 3; b = skeleton.bone(b).parent) {
    if (own[std::size_t(b)] <= 0.0 || subtree[std::size_t(b)] <= 0.0) continue;
    LatticeSpec spec;
    spec.name = skeleton.key(b);
    spec.bone = b;
    spec.elastic.oscillator = {150.0f, 0.2f, 1.0f};
    rig.lattices.insert(rig.lattices.begin(), std::move(spec));
    top = b;
  }
  // The reach chain starts one bone above the topmost lattice (a clavicle), or at it when it is the root.
  if (top >= 0) rig.reach_root = skeleton.bone(top).parent >= 0 ? skeleton.bone(top).parent : top;
  if (rig.reach_root == rig.reach_effector) rig.reach_root = -1;
  return rig;
}

}  // namespace deform
