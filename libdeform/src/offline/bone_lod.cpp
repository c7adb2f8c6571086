// Bone levels of detail: bones merged by weight, leaves first (deform/offline/bone_lod.hpp).
#include "deform/offline/bone_lod.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {
namespace {

// Calls f(bone, weight) for each positive influence of point p, extras included.
template <class F>
void for_each_influence(const SkinWeights& weights, std::size_t p, F&& f) {
  for (int k = 0; k < 4; ++k)
    if (weights.weights[p][k] > 0.0f) f(std::size_t(weights.bones[p][k]), weights.weights[p][k]);
  if (!weights.has_extra()) return;
  const auto it = std::lower_bound(weights.extra_points.begin(), weights.extra_points.end(), std::uint32_t(p));
  if (it == weights.extra_points.end() || *it != p) return;
  const auto j = std::size_t(it - weights.extra_points.begin());
  for (std::uint32_t e = weights.extra_offsets[j]; e < weights.extra_offsets[j + 1]; ++e)
    if (weights.extra_weights[e] > 0.0f) f(std::size_t(weights.extra_bones[e]), weights.extra_weights[e]);
}

void check_weights(const Model& model) {
  const SkinWeights& w = model.weights;
  const std::size_t bones = model.skeleton.bone_count();
  if (w.size() != model.mesh.point_count() || w.weights.size() != w.size())
    throw Error::invalid_argument("weights", "not one entry per point");
  if (w.has_extra() &&
      (w.extra_offsets.size() != w.extra_points.size() + 1 || w.extra_bones.size() != w.extra_weights.size() ||
       w.extra_offsets.back() != w.extra_bones.size()))
    throw Error::invalid_argument("weights", "extra influences are inconsistent");
  for (std::size_t p = 0; p < w.size(); ++p) {
    for (int k = 0; k < 4; ++k) {
      if (!std::isfinite(w.weights[p][k]) || w.weights[p][k] < 0.0f)
        throw Error::invalid_argument("weights", "point " + std::to_string(p) + " has a negative or non-finite weight");
      if (w.weights[p][k] > 0.0f && w.bones[p][k] >= bones)
        throw Error::invalid_argument("weights", "point " + std::to_string(p) + " names a bone out of range");
    }
  }
  for (std::size_t e = 0; e < w.extra_bones.size(); ++e) {
    if (!std::isfinite(w.extra_weights[e]) || w.extra_weights[e] < 0.0f || w.extra_bones[e] >= bones)
      throw Error::invalid_argument("weights", "extra influence " + std::to_string(e) + " is out of range");
  }
}

// Each pose's skinning matrices (world × inverse bind), pose after pose: bones matrices each.
std::vector<glm::mat4> pose_palettes(const Skeleton& skeleton, const std::vector<Pose>& poses) {
  const std::size_t bones = skeleton.bone_count();
  std::vector<glm::mat4> palettes(poses.size() * bones);
  std::vector<glm::mat4> world(bones);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    LocalToWorldJob fk;
    fk.skeleton = &skeleton;
    fk.rotations = poses[k].rotations;
    fk.translations = poses[k].translations;
    fk.world = world;
    fk.palette = std::span<glm::mat4>(palettes).subspan(k * bones, bones);
    if (poses[k].rotations.size() != bones || poses[k].translations.size() != bones || !fk.run())
      throw Error::invalid_argument("pose " + std::to_string(k),
                                    "not one finite rotation and translation per bone of the skeleton");
  }
  return palettes;
}

std::size_t count_influences(const SkinWeights& weights) {
  std::size_t n = 0;
  for (std::size_t p = 0; p < weights.size(); ++p) for_each_influence(weights, p, [&](std::size_t, float) { ++n; });
  return n;
}

}  // namespace

BoneLod build_bone_lod(const Model& model, const BoneLodSettings& settings) {
  const Skeleton& skeleton = model.skeleton;
  const std::size_t bones = skeleton.bone_count();
  const std::size_t points = model.mesh.point_count();
  check_weights(model);
  const bool by_count = !settings.bones_per_level.empty();
  if (by_count == !settings.weight_error.empty())
    throw Error::invalid_argument("settings", "give either bones_per_level or weight_error, not both or neither");
  if (settings.max_influences < 1 || settings.max_influences > 8)
    throw Error::invalid_argument("settings", "max_influences must be in [1, 8]");
  const std::size_t level_count = 1 + (by_count ? settings.bones_per_level.size() : settings.weight_error.size());
  for (std::size_t l = 1; l < level_count; ++l) {
    const std::string element = "level " + std::to_string(l);
    if (by_count && l > 1 && settings.bones_per_level[l - 1] > settings.bones_per_level[l - 2])
      throw Error::invalid_argument(element, "keeps more bones than the level before");
    if (!by_count) {
      const float budget = settings.weight_error[l - 1];
      if (!(budget >= 0.0f && budget <= 1.0f)) throw Error::invalid_argument(element, "budget is outside [0, 1]");
      if (l > 1 && budget < settings.weight_error[l - 2])
        throw Error::invalid_argument(element, "budget is smaller than the level before's");
    }
  }
  std::vector<bool> pinned(bones, false);
  for (std::size_t b = 0; b < bones; ++b) pinned[b] = skeleton.bones()[b].parent < 0;
  for (const std::int32_t b : settings.keep) {
    if (b < 0 || std::size_t(b) >= bones)
      throw Error::invalid_argument("keep", "bone " + std::to_string(b) + " out of range");
    pinned[std::size_t(b)] = true;
  }
  // The kept set must be closed under parents: a pinned bone pins its ancestors.
  for (std::size_t b = 0; b < bones; ++b)
    if (pinned[b])
      for (std::int32_t a = skeleton.bones()[b].parent; a >= 0; a = skeleton.bones()[std::size_t(a)].parent)
        pinned[std::size_t(a)] = true;

  // Each bone's own skin weight summed over the points (double: thousands of small terms).
  std::vector<double> own(bones, 0.0);
  for (std::size_t p = 0; p < points; ++p)
    for_each_influence(model.weights, p, [&](std::size_t b, float w) { own[b] += w; });
  std::vector<std::size_t> depth(bones, 0);
  for (const std::int32_t id : skeleton.order()) {
    const std::int32_t parent = skeleton.bones()[std::size_t(id)].parent;
    if (parent >= 0) depth[std::size_t(id)] = depth[std::size_t(parent)] + 1;
  }

  // What merging each bone into its parent costs: its points' weight on it (own and merged descendants'), each
  // times how far the point moves between the two bones' skinning matrices over the poses (1 without poses).
  const std::vector<glm::mat4> palettes = pose_palettes(skeleton, settings.poses);
  std::vector<std::vector<std::pair<std::uint32_t, float>>> carried(bones);  // per bone: (point, weight) it skins
  for (std::size_t p = 0; p < points; ++p)
    for_each_influence(model.weights, p, [&](std::size_t b, float w) { carried[b].emplace_back(std::uint32_t(p), w); });
  const auto merge_cost = [&](std::size_t b) {
    const std::int32_t parent = skeleton.bones()[b].parent;
    double cost = 0.0;
    for (const auto& [p, w] : carried[b]) {
      if (settings.poses.empty() || parent < 0) {
        cost += w;
        continue;
      }
      const glm::vec4 x(model.mesh.positions[p], 1.0f);
      double moved = 0.0;
      for (std::size_t k = 0; k < settings.poses.size(); ++k) {
        const glm::mat4* palette = palettes.data() + k * bones;
        moved += glm::length(glm::vec3(palette[b] * x - palette[std::size_t(parent)] * x));
      }
      cost += w * moved / double(settings.poses.size());
    }
    return cost;
  };
  std::vector<double> cost(bones);
  for (std::size_t b = 0; b < bones; ++b) cost[b] = merge_cost(b);

  // The greedy sequence of merges, each bone's carried points moving to its parent.
  std::vector<bool> kept(bones, true);
  std::vector<std::size_t> kept_children(bones, 0);
  for (std::size_t b = 0; b < bones; ++b)
    if (const std::int32_t parent = skeleton.bones()[b].parent; parent >= 0) ++kept_children[std::size_t(parent)];
  std::vector<std::size_t> removals;  // in order
  std::vector<double> error_after;    // the mean weight error once removals[0..i] are merged
  double moved = 0.0;
  for (;;) {
    std::size_t best = bones;
    for (std::size_t b = 0; b < bones; ++b) {
      if (!kept[b] || pinned[b] || kept_children[b] != 0) continue;
      if (best == bones || cost[b] < cost[best] ||
          (cost[b] == cost[best] && (depth[b] > depth[best] || (depth[b] == depth[best] && b > best))))
        best = b;
    }
    if (best == bones) break;
    const auto parent = std::size_t(skeleton.bones()[best].parent);
    kept[best] = false;
    --kept_children[parent];
    carried[parent].insert(carried[parent].end(), carried[best].begin(), carried[best].end());
    cost[parent] = merge_cost(parent);
    moved += own[best];
    removals.push_back(best);
    error_after.push_back(points == 0 ? 0.0 : moved / double(points));
  }

  BoneLod lod;
  lod.levels.resize(level_count);
  BoneLodLevel& full = lod.levels[0];
  full.bone_map.resize(bones);
  for (std::size_t b = 0; b < bones; ++b) full.bone_map[b] = std::int32_t(b);
  full.kept_bones = bones;
  full.weights = model.weights;
  full.influences = count_influences(full.weights);
  for (std::size_t l = 1; l < level_count; ++l) {
    std::size_t merges = 0;
    if (by_count) {
      const std::size_t target = settings.bones_per_level[l - 1];
      merges = bones > target ? std::min(bones - target, removals.size()) : 0;
    } else {
      const double budget = settings.weight_error[l - 1];
      while (merges < removals.size() && error_after[merges] <= budget + 1e-12) ++merges;
    }
    BoneLodLevel& level = lod.levels[l];
    std::vector<bool> level_kept(bones, true);
    for (std::size_t r = 0; r < merges; ++r) level_kept[removals[r]] = false;
    level.bone_map.resize(bones);
    for (const std::int32_t id : skeleton.order()) {  // parents first: a merged bone maps where its parent maps
      const auto b = std::size_t(id);
      level.bone_map[b] = level_kept[b] ? id : level.bone_map[std::size_t(skeleton.bones()[b].parent)];
    }
    level.kept_bones = bones - merges;
    level.weight_error = merges == 0 ? 0.0f : float(error_after[merges - 1]);
    std::vector<std::uint16_t> point_bones;
    std::vector<float> point_weights;
    for (std::size_t p = 0; p < points; ++p) {
      point_bones.clear();
      point_weights.clear();
      for_each_influence(model.weights, p, [&](std::size_t b, float w) {
        const auto to = std::uint16_t(level.bone_map[b]);
        const auto same = std::find(point_bones.begin(), point_bones.end(), to);
        if (same != point_bones.end()) point_weights[std::size_t(same - point_bones.begin())] += w;
        else point_bones.push_back(to), point_weights.push_back(w);
      });
      // The strongest max_influences (ties: the lower bone, as append_influences orders them), renormalised there.
      while (point_bones.size() > settings.max_influences) {
        std::size_t weakest = 0;
        for (std::size_t k = 1; k < point_bones.size(); ++k)
          if (point_weights[k] < point_weights[weakest] ||
              (point_weights[k] == point_weights[weakest] && point_bones[k] > point_bones[weakest]))
            weakest = k;
        point_bones.erase(point_bones.begin() + std::ptrdiff_t(weakest));
        point_weights.erase(point_weights.begin() + std::ptrdiff_t(weakest));
      }
      const std::size_t first = model.weights.bones[p][0];
      append_influences(level.weights, point_bones, point_weights,
                        std::uint16_t(first < bones ? level.bone_map[first] : 0));
    }
    level.influences = count_influences(level.weights);
  }
  return lod;
}

bool bone_lod_consistent(const Skeleton& skeleton, const BoneLodLevel& level) {
  const std::size_t bones = skeleton.bone_count();
  if (level.bone_map.size() != bones) return false;
  std::size_t kept = 0;
  for (std::size_t b = 0; b < bones; ++b) {
    const std::int32_t to = level.bone_map[b];
    if (to < 0 || std::size_t(to) >= bones || level.bone_map[std::size_t(to)] != to) return false;
    if (!skeleton.is_ancestor(to, std::int32_t(b)) && to != std::int32_t(b)) return false;
    if (to == std::int32_t(b)) {
      ++kept;
      const std::int32_t parent = skeleton.bones()[b].parent;
      if (parent >= 0 && level.bone_map[std::size_t(parent)] != parent) return false;
    }
  }
  return kept == level.kept_bones;
}

}  // namespace deform
