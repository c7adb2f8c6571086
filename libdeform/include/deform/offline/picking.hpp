#pragma once
// Picking: which triangle of a mesh a ray (from a camera pixel, or any origin and direction) hits first.
// No graphics API: the camera is a view and a projection matrix (OpenGL clip conventions, as glm builds them).
// This is how "click an object of the scene" (thesis RV03F03) reaches the IK solvers.
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"
namespace deform {

// A half-line origin + t · direction, t >= 0. `direction` need not be unit length but must not be zero; hit
// distances are measured in world units along it whatever its length.
struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};
};

// The ray through a pixel: `pixel` in window coordinates (x right, y down from the top-left corner, as mouse events
// give; add 0.5 for a pixel's centre), `viewport` = (x, y, width, height) in the same coordinates. The ray starts on
// the near plane, direction unit length. view/projection as for rendering (clip z in [-1, 1]); a zero-sized viewport
// or a singular projection·view gives a non-finite ray, which intersect() never hits.
DEFORM_OFFLINE_API Ray ray_from_pixel(const glm::mat4& view, const glm::mat4& projection, glm::vec2 pixel,
                                      glm::vec4 viewport) noexcept;

// The nearest hit of a ray.
struct RayHit {
  bool hit = false;
  std::uint32_t triangle = 0;   // index of the triangle (indices[3·triangle ..]) as given to build()
  glm::vec3 barycentric{0.0f};  // weights of the triangle's three corners at the hit point (sum 1)
  float distance = 0.0f;        // world units from the ray origin
};

// The nearest intersection of `ray` with the triangles `indices` (3 per triangle, into `positions`) by testing every
// triangle: O(triangles). Triangles are two-sided; degenerate ones are never hit; a hit farther than `max_distance`
// is not reported. Indices must be in range (not checked: this is the reference the BVH is tested against).
DEFORM_OFFLINE_API RayHit intersect_triangles(const Ray& ray, std::span<const glm::vec3> positions,
                                              std::span<const std::uint32_t> indices,
                                              float max_distance = std::numeric_limits<float>::infinity()) noexcept;

// A bounding volume hierarchy over triangles (binned surface-area heuristic, at most 4 triangles per leaf). Built
// once per topology; refit() follows a deforming mesh each frame without reallocating; intersect() answers a ray in
// O(log triangles) typically (about a microsecond for 100k triangles, docs/performance.md).
class DEFORM_OFFLINE_API TriangleBvh {
 public:
  TriangleBvh() = default;

  // Builds over the triangles `indices` (3 per triangle) of `positions`. Throws deform::Error when indices.size() is
  // not a multiple of 3, an index is out of range, a position is not finite or there are 2^31 triangles or more.
  // Allocates O(triangles); cost O(triangles · log triangles).
  void build(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices);

  // Moves the triangles to new `positions` (same point count as at build, e.g. the skinned mesh of this frame) and
  // refits the boxes bottom-up; the tree shape stays, so a large deformation slows queries but never breaks them.
  // Returns false (and changes nothing) on a wrong point count. A non-finite position makes its triangles unpickable.
  // No allocation, O(triangles).
  bool refit(std::span<const glm::vec3> positions) noexcept;

  // The nearest hit, as intersect_triangles() gives it for the positions of the last build() or refit(). Triangles
  // with a corner at point `skip_point` (an index into build()'s positions) are not hit: a ray cast from a vertex
  // past its own triangles.
  static constexpr std::uint32_t no_point = 0xFFFFFFFFu;
  RayHit intersect(const Ray& ray, float max_distance = std::numeric_limits<float>::infinity(),
                   std::uint32_t skip_point = no_point) const noexcept;

  std::size_t triangle_count() const noexcept { return triangle_ids_.size(); }

 private:
  struct Node {
    glm::vec3 min{0.0f};
    std::uint32_t first = 0;  // leaf: first slot; interior: index of the left child (the right one follows it)
    glm::vec3 max{0.0f};
    std::uint32_t count = 0;  // leaf: triangle count (>= 1); interior: 0
  };
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> triangle_ids_;   // slot -> triangle index as given to build()
  std::vector<std::uint32_t> corner_points_;  // slot -> its three point indices
  std::vector<glm::vec3> corners_;            // slot -> its three corner positions (current)
  std::size_t point_count_ = 0;
};

// The mesh's triangles as indices into its points (`positions`), the form build() and intersect_triangles() take:
// Mesh::triangles index render vertices, mapped here through vertex_point. Allocates 3 · triangle_count() entries.
DEFORM_OFFLINE_API std::vector<std::uint32_t> point_triangles(const Mesh& mesh);

}  // namespace deform
