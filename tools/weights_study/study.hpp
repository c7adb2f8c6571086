#pragma once
// The weights study (docs/weights.md): how far automatic weights move a character's points from where the weights
// its artist painted put them, over the character's own clips or over seeded random poses. Header-only so that the
// tool and the regression test (tests/import/weights_study_test.cpp) measure the same way.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

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

// The skinning palettes of every clip played `samples_per_clip` evenly spaced times each (t = duration · (k + 0.5) /
// samples); a sample the jobs refuse is left out.
inline std::vector<std::vector<glm::mat4>> clip_palettes(const deform::Skeleton& skeleton,
                                                         const std::vector<deform::Animation>& clips,
                                                         int samples_per_clip) {
  std::vector<std::vector<glm::mat4>> palettes;
  std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
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
      palettes.push_back(palette);
    }
  }
  return palettes;
}

// `count` seeded random poses: every bone marked in `posed` (the bones the artist weighted) turns by its bind local
// rotation times X·Y·Z rotations of angles drawn uniformly in ±`degrees`; the other bones keep their bind local
// transform and follow their parents. The draws come from std::mt19937 (a fixed algorithm) mapped to angles by hand,
// so a seed gives the same poses with every standard library.
inline std::vector<deform::Pose> random_poses(const deform::Skeleton& skeleton, const std::vector<std::uint8_t>& posed,
                                              int count, std::uint32_t seed, float degrees = 20.0f) {
  std::mt19937 random(seed);
  auto angle = [&] {
    const double u = static_cast<double>(random()) / 4294967296.0;  // [0, 1)
    return glm::radians(static_cast<float>((2.0 * u - 1.0) * static_cast<double>(degrees)));
  };
  std::vector<deform::Pose> poses;
  for (int k = 0; k < count; ++k) {
    deform::Pose pose = skeleton.bind_pose();
    for (std::size_t b = 0; b < skeleton.bone_count(); ++b) {
      if (b >= posed.size() || posed[b] == 0) continue;
      const float x = angle(), y = angle(), z = angle();
      const glm::quat turn = glm::angleAxis(x, glm::vec3(1, 0, 0)) * glm::angleAxis(y, glm::vec3(0, 1, 0)) *
                             glm::angleAxis(z, glm::vec3(0, 0, 1));
      pose.rotations[b] = glm::normalize(pose.rotations[b] * turn);
    }
    poses.push_back(std::move(pose));
  }
  return poses;
}

// The skinning palettes of random_poses (a pose the forward kinematics refuses is left out).
inline std::vector<std::vector<glm::mat4>> random_palettes(const deform::Skeleton& skeleton,
                                                           const std::vector<std::uint8_t>& posed, int count,
                                                           std::uint32_t seed, float degrees = 20.0f) {
  std::vector<std::vector<glm::mat4>> palettes;
  std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
  for (const deform::Pose& pose : random_poses(skeleton, posed, count, seed, degrees)) {
    deform::LocalToWorldJob fk;
    fk.skeleton = &skeleton;
    fk.rotations = pose.rotations;
    fk.translations = pose.translations;
    fk.world = world;
    fk.palette = palette;
    if (fk.run()) palettes.push_back(palette);
  }
  return palettes;
}

// Compares the points skinned with `automatic` and with `model.weights` (the artist's, every influence) in each of
// the given poses (skinning palettes).
inline Figures compare_palettes(const deform::Model& model, const std::vector<std::vector<glm::mat4>>& palettes,
                                const deform::SkinWeights& automatic) {
  const std::vector<glm::vec3>& points = model.mesh.positions;
  const deform::Bounds bounds = deform::compute_bounds(points);
  const double diagonal = std::max(static_cast<double>(glm::length(bounds.max - bounds.min)), 1e-30);
  std::vector<float> distances;
  distances.reserve(palettes.size() * points.size());
  Figures f;
  double total = 0;
  for (const std::vector<glm::mat4>& palette : palettes) {
    ++f.poses;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const glm::vec3 a = skin_point(palette, model.weights, i, points[i]);
      const glm::vec3 b = skin_point(palette, automatic, i, points[i]);
      const float d = glm::length(a - b);
      distances.push_back(d);
      total += d;
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

// Plays every clip, `samples_per_clip` evenly spaced times each, and compares the points skinned with `automatic`
// and with `model.weights` (the artist's).
inline Figures compare(const deform::Model& model, const std::vector<deform::Animation>& clips,
                       const deform::SkinWeights& automatic, int samples_per_clip = 8) {
  return compare_palettes(model, clip_palettes(model.skeleton, clips, samples_per_clip), automatic);
}

}  // namespace weights_study
