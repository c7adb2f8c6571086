#pragma once
// Private to deform::offline: bones as bind-pose segments for the volumetric weights (heat_weights.cpp,
// voxel_weights.cpp). O(bones) each.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/picking.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform::detail {

// A bone as segments in the bind pose: head -> each child's head; a leaf continues its parent's direction
// (bone_segments()); a lone root is a point.
struct BoneShape {
  std::vector<std::pair<glm::vec3, glm::vec3>> segments;
};

inline std::vector<BoneShape> bone_shapes(const Skeleton& skeleton, float leaf_length) {
  const std::vector<BoneSegment> single = bone_segments(skeleton, leaf_length);
  const std::span<const glm::mat4> world = skeleton.bind_world();
  std::vector<BoneShape> shapes(skeleton.bone_count());
  for (std::size_t b = 0; b < shapes.size(); ++b) {
    const Bone& bone = skeleton.bones()[b];
    if (bone.children.empty()) {
      shapes[b].segments.emplace_back(single[b].head, single[b].tail);
      continue;
    }
    for (std::int32_t c : bone.children)
      shapes[b].segments.emplace_back(single[b].head, glm::vec3(world[static_cast<std::size_t>(c)][3]));
  }
  return shapes;
}

// A leaf ends where it leaves the mesh: its made-up extension must not reach into a neighbouring part (a fingertip
// bone poking out of the hand into the hip it rests on).
inline void clip_leaves(std::vector<BoneShape>& shapes, const Skeleton& skeleton, const TriangleBvh& mesh) {
  if (mesh.triangle_count() == 0) return;
  for (std::size_t b = 0; b < shapes.size(); ++b) {
    if (!skeleton.bones()[b].children.empty()) continue;
    auto& [head, tail] = shapes[b].segments.front();
    const float length = glm::length(tail - head);
    if (!(length > 0.0f)) continue;
    const RayHit hit = mesh.intersect({head, (tail - head) / length}, length);
    if (hit.hit) tail = head + (tail - head) * (hit.distance / length);
  }
}

}  // namespace deform::detail
