#pragma once
// Helpers shared by the skeleton test suites: building bones and skeletons by hand.
#include <string>
#include <vector>

#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace skeleton_test {

inline deform::Bone make_bone(std::string name, std::int32_t parent, std::vector<std::int32_t> children,
                              glm::vec3 translation = glm::vec3(0.0f), glm::vec3 rotation = glm::vec3(0.0f)) {
  deform::Bone b;
  b.name = std::move(name);
  b.parent = parent;
  b.children = std::move(children);
  b.bind_translation = translation;
  b.bind_rotation = rotation;
  return b;
}

// A small arm: root(0) -> shoulder(1) -> elbow(2) -> wrist(3), and root -> head(4), with limits on the elbow.
inline std::vector<deform::Bone> arm_bones() {
  std::vector<deform::Bone> bones = {
      make_bone("root", -1, {1, 4}, {0.0f, 1.0f, 0.0f}),
      make_bone("shoulder", 0, {2}, {0.5f, 0.5f, 0.0f}, {0.0f, 0.0f, -90.0f}),
      make_bone("elbow", 1, {3}, {0.0f, 1.0f, 0.0f}, {10.0f, 0.0f, 20.0f}),
      make_bone("wrist", 2, {}, {0.0f, 0.8f, 0.0f}),
      make_bone("head", 0, {}, {0.0f, 0.7f, 0.1f}, {-5.0f, 0.0f, 0.0f}),
  };
  bones[2].limits.min = {-10.0f, 0.0f, 0.0f};
  bones[2].limits.max = {10.0f, 0.0f, 150.0f};
  return bones;
}

inline glm::vec3 head(const glm::mat4& world) { return glm::vec3(world[3]); }

}  // namespace skeleton_test
