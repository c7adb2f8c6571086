// SkinWeights helpers: building a point's slots and extras from any number of influences, and folding back to four.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "deform/runtime/skeleton.hpp"

namespace deform {

std::size_t append_influences(SkinWeights& weights, std::span<const std::uint16_t> bones, std::span<const float> values,
                              std::uint16_t fallback_bone) {
  // Merge repeated bones (summed, in double), drop non-positive weights, strongest first, lower bone on a tie.
  std::vector<std::pair<std::uint16_t, double>> list;
  const std::size_t n = std::min(bones.size(), values.size());
  list.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!(values[k] > 0.0f)) continue;
    auto same = std::find_if(list.begin(), list.end(), [&](const auto& e) { return e.first == bones[k]; });
    if (same != list.end()) same->second += values[k];
    else list.emplace_back(bones[k], values[k]);
  }
  std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  double total = 0.0;
  for (const auto& e : list) total += e.second;
  const std::size_t point = weights.bones.size();
  glm::u16vec4 slot_bones(0);
  glm::vec4 slot_weights(0.0f);
  if (list.empty() || !(total > 0.0) || !std::isfinite(total)) {
    slot_bones[0] = fallback_bone;
    slot_weights[0] = 1.0f;
    list.clear();
  } else {
    for (std::size_t k = 0; k < list.size() && k < 4; ++k) {
      slot_bones[int(k)] = list[k].first;
      slot_weights[int(k)] = static_cast<float>(list[k].second / total);
    }
  }
  weights.bones.push_back(slot_bones);
  weights.weights.push_back(slot_weights);
  if (list.size() > 4) {
    if (weights.extra_offsets.empty()) weights.extra_offsets.push_back(0);
    weights.extra_points.push_back(static_cast<std::uint32_t>(point));
    for (std::size_t k = 4; k < list.size(); ++k) {
      weights.extra_bones.push_back(list[k].first);
      weights.extra_weights.push_back(static_cast<float>(list[k].second / total));
    }
    weights.extra_offsets.push_back(static_cast<std::uint32_t>(weights.extra_bones.size()));
  }
  return list.empty() ? 1 : list.size();
}

std::size_t drop_extra_influences(SkinWeights& weights, float* largest_dropped) {
  float largest = 0.0f;
  const std::size_t points = weights.extra_points.size();
  for (std::size_t j = 0; j < points; ++j) {
    const std::size_t p = weights.extra_points[j];
    glm::vec4& w = weights.weights[p];
    double kept = 0.0, dropped_total = 0.0, dropped_max = 0.0;
    for (int k = 0; k < 4; ++k) kept += w[k];
    for (std::uint32_t e = weights.extra_offsets[j]; e < weights.extra_offsets[j + 1]; ++e) {
      dropped_total += weights.extra_weights[e];
      dropped_max = std::max(dropped_max, double(weights.extra_weights[e]));
    }
    if (kept + dropped_total > 0.0) largest = std::max(largest, float(dropped_max / (kept + dropped_total)));
    if (kept > 0.0) w = glm::vec4(glm::dvec4(w) / kept);
  }
  weights.extra_points.clear();
  weights.extra_offsets.clear();
  weights.extra_bones.clear();
  weights.extra_weights.clear();
  if (largest_dropped != nullptr) *largest_dropped = largest;
  return points;
}

std::size_t influence_count(const SkinWeights& weights, std::size_t p) noexcept {
  std::size_t n = 0;
  for (int k = 0; k < 4; ++k) n += weights.weights[p][k] > 0.0f ? 1 : 0;
  const auto it = std::lower_bound(weights.extra_points.begin(), weights.extra_points.end(), p);
  if (it != weights.extra_points.end() && *it == p) {
    const auto j = static_cast<std::size_t>(it - weights.extra_points.begin());
    for (std::uint32_t e = weights.extra_offsets[j]; e < weights.extra_offsets[j + 1]; ++e)
      n += weights.extra_weights[e] > 0.0f ? 1 : 0;
  }
  return n;
}

}  // namespace deform
