#pragma once
// The weights study (docs/weights.md): how far automatic weights move a character's points from where the weights
// its artist painted put them, over the character's own clips. Header-only so that the tool and the regression test
// (tests/import/weights_study_test.cpp) measure the same way.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/animation.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"

namespace weights_study {

struct Figures {
  double mean_percent = 0;               // mean point distance, % of the bind-pose bounding-box diagonal
  double p99_percent = 0;                // 99th percentile of the point distances (all points × all samples)
  double max_percent = 0;                // the largest
  double strongest_differs_percent = 0;  // points whose strongest bone differs from the artist's
  std::size_t poses = 0;                 // clip samples measured
};

// The bone with the largest weight of point i (the lower id on a tie).
inline std::uint16_t strongest_bone(const deform::SkinWeights& w, std::size_t i) {
  int best = 0;
  for (int k = 1; k < deform::max_influences; ++k)
    if (w.weights[i][k] > w.weights[i][best] ||
        (w.weights[i][k] == w.weights[i][best] && w.weights[i][k] > 0.0f && w.bones[i][k] < w.bones[i][best]))
      best = k;
  return w.bones[i][best];
}

// Linear blend skinning of one point with every influence, the four slots and any past them (weights
// renormalised, as SkinningJob does). An artist's rig may give a point more than four (the FBX models do).
inline glm::vec3 skin_point(const std::vector<glm::mat4>& palette, const deform::SkinWeights& w, std::size_t i,
                            glm::vec3 p) {
  glm::vec4 sum(0.0f);
  float total = 0.0f;
  auto add = [&](std::uint16_t bone, float x) {
    if (x <= 0.0f) return;
    sum += x * (palette[bone] * glm::vec4(p, 1.0f));
    total += x;
  };
  for (int k = 0; k < deform::max_influences; ++k) add(w.bones[i][k], w.weights[i][k]);
  const auto row = std::lower_bound(w.extra_points.begin(), w.extra_points.end(), static_cast<std::uint32_t>(i));
  if (row != w.extra_points.end() && *row == i) {
    const std::size_t j = static_cast<std::size_t>(row - w.extra_points.begin());
    for (std::uint32_t e = w.extra_offsets[j]; e < w.extra_offsets[j + 1]; ++e)
      add(w.extra_bones[e], w.extra_weights[e]);
  }
  return total > 0.0f ? glm::vec3(sum) / total : p;
}

// Plays every clip, `samples_per_clip` evenly spaced times each (t = duration · (k + 0.5) / samples), and compares
// the points skinned with `automatic` and with `model.weights` (the artist's).
inline Figures compare(const deform::Model& model, const std::vector<deform::Animation>& clips,
                       const deform::SkinWeights& automatic, int samples_per_clip = 8) {
  const deform::Skeleton& skeleton = model.skeleton;
  const std::vector<glm::vec3>& points = model.mesh.positions;
  const deform::Bounds bounds = deform::compute_bounds(points);
  const double diagonal = std::max(static_cast<double>(glm::length(bounds.max - bounds.min)), 1e-30);
  std::vector<float> distances;
  std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
  Figures f;
  double total = 0;
  for (const deform::Animation& clip : clips) {
    for (int s = 0; s < samples_per_clip; ++s) {
      deform::Pose pose = skeleton.bind_pose();
      deform::SamplingJob sampling;
      sampling.animation = &clip;
      sampling.time = clip.duration * (static_cast<float>(s) + 0.5f) / static_cast<float>(samples_per_clip);
      sampling.rotations = pose.rotations;
      sampling.translations = pose.translations;
      if (!sampling.run()) continue;
      deform::LocalToWorldJob fk;
      fk.skeleton = &skeleton;
      fk.rotations = pose.rotations;
      fk.translations = pose.translations;
      fk.world = world;
      fk.palette = palette;
      if (!fk.run()) continue;
      ++f.poses;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const glm::vec3 a = skin_point(palette, model.weights, i, points[i]);
        const glm::vec3 b = skin_point(palette, automatic, i, points[i]);
        const float d = glm::length(a - b);
        distances.push_back(d);
        total += d;
      }
    }
  }
  if (!distances.empty()) {
    f.mean_percent = 100.0 * total / static_cast<double>(distances.size()) / diagonal;
    const std::size_t at = std::min(distances.size() - 1, static_cast<std::size_t>(0.99 * double(distances.size())));
    std::nth_element(distances.begin(), distances.begin() + static_cast<std::ptrdiff_t>(at), distances.end());
    f.p99_percent = 100.0 * distances[at] / diagonal;
    f.max_percent = 100.0 * *std::max_element(distances.begin(), distances.end()) / diagonal;
  }
  std::size_t differs = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    differs += strongest_bone(model.weights, i) != strongest_bone(automatic, i) ? 1 : 0;
  f.strongest_differs_percent = points.empty() ? 0.0 : 100.0 * double(differs) / double(points.size());
  return f;
}

}  // namespace weights_study
