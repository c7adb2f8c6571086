#pragma once
// Seeded random rigs for the IK tests and benchmarks: a base bone, a chain of k joints plus its effector, a sibling.
#include <cmath>
#include <random>
#include <span>
#include <stdexcept>
#include <vector>

#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace ik_test {

struct RandomChain {
  deform::Skeleton skeleton;
  std::int32_t root = 1;      // chain root; bone 0 above it places the chain somewhere in the world
  std::int32_t effector = 0;  // bone joints + 1
  std::size_t joints = 0;     // bones 1 .. joints are the chain's joints
  float length = 0.0f;        // sum of the segment lengths
};

// Random per-axis limits: some free, some locked, most a random range; y kept in [-85, 85] so that the canonical
// Euler triple is the one the limits mean.
inline deform::DofLimits random_limits(std::mt19937& random) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  deform::DofLimits limits;
  for (int axis = 0; axis < 3; ++axis) {
    const float bound = axis == 1 ? 85.0f : 170.0f;
    const float kind = unit(random);
    if (kind < 0.2f && axis != 1) {
      limits.min[axis] = -180.0f, limits.max[axis] = 180.0f;
    } else if (kind < 0.3f) {
      limits.min[axis] = limits.max[axis] = -0.5f * bound + unit(random) * bound;
    } else {
      limits.min[axis] = -bound + unit(random) * 1.4f * bound;
      limits.max[axis] = std::min(bound, limits.min[axis] + 10.0f + unit(random) * bound);
    }
  }
  return limits;
}

// Limits of every kind up to ±180° on every axis, y included (so that the Euler triple the limits mean may be either
// of a rotation's two): free, locked, bounds exactly at ±90° or ±180°, any range within [-180, 180].
inline deform::DofLimits random_wide_limits(std::mt19937& random) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float special[] = {-180.0f, -90.0f, 90.0f, 180.0f};
  deform::DofLimits limits;
  for (int axis = 0; axis < 3; ++axis) {
    const float kind = unit(random);
    if (kind < 0.15f) continue;  // free
    if (kind < 0.25f) {
      limits.min[axis] = limits.max[axis] = -180.0f + 360.0f * unit(random);
      continue;
    }
    float a = -180.0f + 360.0f * unit(random), b = -180.0f + 360.0f * unit(random);
    if (kind < 0.4f) a = special[static_cast<int>(unit(random) * 3.999f)];
    limits.min[axis] = std::min(a, b), limits.max[axis] = std::max(a, b);
  }
  return limits;
}

inline glm::vec3 random_in_limits(std::mt19937& random, const deform::DofLimits& limits) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  glm::vec3 e;
  for (int axis = 0; axis < 3; ++axis)
    e[axis] = limits.min[axis] + unit(random) * (limits.max[axis] - limits.min[axis]);
  return e;
}

inline glm::vec3 random_direction(std::mt19937& random) {
  std::normal_distribution<float> normal;
  glm::vec3 v(normal(random), normal(random), normal(random));
  return glm::length(v) < 1e-3f ? glm::vec3(0, 1, 0) : glm::normalize(v);
}

// `joints` joints with lengths in [0.2, 1.5]; free_joints: every joint free on every axis; zero_bone: this chain bone
// (1-based joint index) gets a zero-length segment; wide_limits: random_wide_limits instead of random_limits.
inline RandomChain random_chain(std::mt19937& random, std::size_t joints, bool free_joints = false, int zero_bone = -1,
                                bool wide_limits = false) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<deform::Bone> bones(joints + 3);
  const auto last = static_cast<std::int32_t>(joints + 2);
  bones[0].name = "base";
  bones[0].bind_translation = 2.0f * random_direction(random);
  bones[0].bind_rotation = glm::vec3(unit(random), unit(random), unit(random)) * 120.0f - 60.0f;
  bones[0].children = {1, last};
  float length = 0.0f;
  for (std::size_t k = 1; k <= joints + 1; ++k) {
    deform::Bone& bone = bones[k];
    bone.name = "b" + std::to_string(k);
    bone.parent = static_cast<std::int32_t>(k - 1);
    if (k <= joints) bone.children = {static_cast<std::int32_t>(k + 1)};
    const float segment = static_cast<int>(k) - 1 == zero_bone ? 0.0f : 0.2f + 1.3f * unit(random);
    bone.bind_translation = k == 1 ? random_direction(random) : segment * random_direction(random);
    if (k > 1) length += segment;
    if (!free_joints && k <= joints) bone.limits = wide_limits ? random_wide_limits(random) : random_limits(random);
    bone.bind_rotation = random_in_limits(random, bone.limits);
  }
  bones[static_cast<std::size_t>(last)].name = "sibling";
  bones[static_cast<std::size_t>(last)].parent = 0;
  bones[static_cast<std::size_t>(last)].bind_translation = glm::vec3(0, 0, 1);
  RandomChain rig{deform::Skeleton(std::move(bones)), 1, static_cast<std::int32_t>(joints + 1), joints, length};
  return rig;
}

// The bind pose with every joint set to random in-limit Euler angles.
inline deform::Pose random_in_limit_pose(std::mt19937& random, const RandomChain& rig) {
  deform::Pose pose = rig.skeleton.bind_pose();
  for (std::size_t b = 1; b <= rig.joints; ++b)
    pose.rotations[b] = deform::quat_from_euler(random_in_limits(random, rig.skeleton.bones()[b].limits));
  return pose;
}

// effector_position for a pose that holds the chain (a refusal is a test failure, as an exception).
inline glm::vec3 effector_of(const deform::IkChain& chain, std::span<const glm::quat> rotations,
                             std::span<const glm::vec3> translations) {
  glm::vec3 position(0.0f);
  if (!deform::effector_position(chain, rotations, translations, position))
    throw std::logic_error("effector_position refused the pose");
  return position;
}

// A target the chain can reach: the effector of a random in-limit pose.
inline glm::vec3 random_reachable_target(std::mt19937& random, const RandomChain& rig) {
  const deform::Pose pose = random_in_limit_pose(random, rig);
  return effector_of(deform::make_chain(rig.skeleton, rig.root, rig.effector), pose.rotations, pose.translations);
}

inline glm::vec3 chain_root_head(const deform::Pose& pose) {
  return pose.rotations[0] * pose.translations[1] + pose.translations[0];
}

// Either Euler triple of the rotation within the limits, with 0.01 degree of slack for float rounding.
inline bool rotation_within_limits(glm::quat q, const deform::DofLimits& limits) {
  const glm::vec3 e = deform::euler_from_quat(q);
  auto wrap = [](float a) { return a > 180.0f ? a - 360.0f : (a <= -180.0f ? a + 360.0f : a); };
  const glm::vec3 other(wrap(e.x + 180.0f), wrap(180.0f - e.y), wrap(e.z + 180.0f));
  return deform::within_limits(e, limits, 1e-2f) || deform::within_limits(other, limits, 1e-2f);
}

inline bool finite_pose(const deform::Pose& pose) {
  for (const glm::quat& q : pose.rotations)
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) return false;
  return true;
}

}  // namespace ik_test
