#pragma once
// Private to deform::offline: what the volumetric weights (heat_weights.cpp, voxel_weights.cpp) share: the checks of
// their common options, the start (the input checked, the deforming bones listed), the end (a warning per bone left
// without a point) and bones as bind-pose segments. O(points + triangles) and O(bones).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/heat_weights.hpp"
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

// The options both methods take, checked the same way; each method calls these among its own checks, in its order.
inline void check_max_influences(int value, int most) {
  if (value < 1 || value > most)
    throw Error::invalid_argument("max_influences", "must be 1 to " + std::to_string(most));
}
inline void check_leaf_length(float value) {
  if (!std::isfinite(value) || value < 0.0f) throw Error::invalid_argument("leaf_length", "must be finite and >= 0");
}

// What both methods start from once their own options are checked: the deforming-bone mask checked (empty, or one
// entry per bone with at least one bone deforming), every point finite and every corner in range
// (checked_corners). Throws deform::Error of kind argument naming the option, vertex or triangle.
struct VolumetricInput {
  std::size_t bone_count = 0;
  std::size_t point_count = 0;
  std::vector<std::uint32_t> corners;    // each triangle corner's point, three per triangle
  std::vector<std::uint8_t> deforms;     // per bone: 1 where the bone may take points
  std::vector<std::uint32_t> deforming;  // the ids of those bones, ascending
};

inline VolumetricInput volumetric_input(const Mesh& mesh, const Skeleton& skeleton,
                                        const std::vector<std::uint8_t>& deforming) {
  VolumetricInput in;
  in.bone_count = skeleton.bone_count();
  in.point_count = mesh.point_count();
  if (!deforming.empty()) {
    if (deforming.size() != in.bone_count)
      throw Error::invalid_argument("deforming", "must be empty or hold one entry per bone");
    if (std::none_of(deforming.begin(), deforming.end(), [](std::uint8_t d) { return d != 0; }))
      throw Error::invalid_argument("deforming", "no bone deforms");
  }
  in.corners = checked_corners(mesh);
  in.deforms.assign(in.bone_count, 1);
  for (std::size_t b = 0; b < in.bone_count; ++b) {
    if (!deforming.empty() && deforming[b] == 0) in.deforms[b] = 0;
    if (in.deforms[b]) in.deforming.push_back(static_cast<std::uint32_t>(b));
  }
  return in;
}

// What both methods end with: a warning per deforming bone that no point took (bones_without_vertices), after the
// method's own warnings. A mesh without points ends here with no weights.
inline void warn_of_unused_bones(WeightsResult& result, const Skeleton& skeleton,
                                 const std::vector<std::uint8_t>& deforming) {
  for (std::string& w : bones_without_vertices(result.weights, skeleton, deforming))
    result.warnings.push_back(std::move(w));
}

// The nearest point of segment [a, b] to p (a when the segment has no length).
inline glm::vec3 nearest_on_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  const glm::vec3 axis = b - a;
  const float length2 = glm::dot(axis, axis);
  if (length2 <= 0.0f) return a;
  const float t = std::clamp(glm::dot(p - a, axis) / length2, 0.0f, 1.0f);
  return a + t * axis;
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
