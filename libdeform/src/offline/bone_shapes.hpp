#pragma once
// Private to deform::offline: what the volumetric weights (heat_weights.cpp, voxel_weights.cpp) share: the input
// checks and bones as bind-pose segments. O(points + triangles) and O(bones).
#include <cmath>
#include <cstdint>
#include <string>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/picking.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform::detail {

// Each triangle corner's point (three per triangle), after checking that every point is finite and every corner in
// range. Throws deform::Error of kind argument naming the vertex or triangle.
inline std::vector<std::uint32_t> checked_corners(const Mesh& mesh) {
  const std::size_t point_count = mesh.point_count();
  for (std::size_t i = 0; i < point_count; ++i) {
    const glm::vec3 p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error::invalid_argument("vertex " + std::to_string(i), "position is not finite");
  }
  if (mesh.triangles.size() % 3 != 0) throw Error::invalid_argument("triangles", "index count is not a multiple of 3");
  std::vector<std::uint32_t> corners(mesh.triangles.size());
  for (std::size_t c = 0; c < corners.size(); ++c) {
    const std::uint32_t v = mesh.triangles[c];
    if (v >= mesh.vertex_point.size() || mesh.vertex_point[v] >= point_count)
      throw Error::invalid_argument("triangle " + std::to_string(c / 3), "vertex index out of range");
    corners[c] = mesh.vertex_point[v];
  }
  return corners;
}

// A bone as segments in the bind pose: head -> each child's head; a leaf continues its parent's direction
// (bone_segments()); a lone root is a point.
struct BoneShape {
  std::vector<std::pair<glm::vec3, glm::vec3>> segments;
  bool guessed = false;  // a leaf's made-up extension, or one of several segments: see clip_guessed_segments
};

inline std::vector<BoneShape> bone_shapes(const Skeleton& skeleton, float leaf_length) {
  const std::vector<BoneSegment> single = bone_segments(skeleton, leaf_length);
  const std::span<const glm::mat4> world = skeleton.bind_world();
  std::vector<BoneShape> shapes(skeleton.bone_count());
  for (std::size_t b = 0; b < shapes.size(); ++b) {
    const Bone& bone = skeleton.bones()[b];
    shapes[b].guessed = bone.children.size() != 1;
    if (bone.children.empty()) {
      shapes[b].segments.emplace_back(single[b].head, single[b].tail);
      continue;
    }
    for (std::int32_t c : bone.children)
      shapes[b].segments.emplace_back(single[b].head, glm::vec3(world[static_cast<std::size_t>(c)][3]));
  }
  return shapes;
}

// Where a bone's segment is a guess, it ends where it leaves the mesh: a leaf's made-up extension must not reach
// into a neighbouring part (a fingertip bone poking out of the hand into the hip it rests on), and a bone that
// carries several bones is only certain to lie inside the body it moves: a spine bone that carries an IK goal
// parented far out at the hand must not claim the arm on the way.
inline void clip_guessed_segments(std::vector<BoneShape>& shapes, const TriangleBvh& mesh) {
  if (mesh.triangle_count() == 0) return;
  for (BoneShape& shape : shapes) {
    if (!shape.guessed) continue;
    for (auto& [head, tail] : shape.segments) {
      const float length = glm::length(tail - head);
      if (!(length > 0.0f)) continue;
      const RayHit hit = mesh.intersect({head, (tail - head) / length}, length);
      if (hit.hit) tail = head + (tail - head) * (hit.distance / length);
    }
  }
}

}  // namespace deform::detail
