#pragma once
// Test helper for the importer, character, level-of-detail and simplification tests: a model's points skinned (LBS,
// every influence, the extras too) by a pose, with its own weights or others given per point.
#include <doctest/doctest.h>

#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"

namespace import_test {

inline std::vector<glm::vec3> skin(const deform::Model& model, const deform::SkinWeights& w, const deform::Pose& pose) {
  const std::size_t bones = model.skeleton.bone_count();
  std::vector<glm::mat4> world(bones), palette(bones);
  deform::LocalToWorldJob fk;
  fk.skeleton = &model.skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  fk.palette = palette;
  REQUIRE(fk.run());
  std::vector<glm::vec3> out(model.mesh.point_count());
  deform::SkinningJob job;
  job.matrices = palette;
  job.bone_indices = w.bones;
  job.bone_weights = w.weights;
  job.extra_vertices = w.extra_points;
  job.extra_offsets = w.extra_offsets;
  job.extra_bones = w.extra_bones;
  job.extra_weights = w.extra_weights;
  job.in_positions = deform::as_floats(std::span<const glm::vec3>(model.mesh.positions));
  job.out_positions = deform::as_floats(std::span<glm::vec3>(out));
  REQUIRE(job.validate());
  REQUIRE(job.run());
  return out;
}

inline std::vector<glm::vec3> skin(const deform::Model& model, const deform::Pose& pose) {
  return skin(model, model.weights, pose);
}

}  // namespace import_test
