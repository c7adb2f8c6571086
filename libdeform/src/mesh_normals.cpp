// Angle-weighted vertex normals (Thürmer & Wüthrich, "Computing vertex normals from polygonal facets", 1998) and
// bounds: per-frame safe (no allocation, no exceptions).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "deform/mesh.hpp"

namespace deform {

bool compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions, std::span<glm::vec3> scratch,
                            std::span<glm::vec3> out_vertex_normals) {
  const std::size_t point_count = mesh.point_count();
  const std::size_t vertex_count = mesh.vertex_count();
  if (positions.size() != point_count || scratch.size() != point_count || out_vertex_normals.size() != vertex_count ||
      mesh.triangles.size() % 3 != 0)
    return false;

  for (glm::vec3& n : scratch) n = glm::vec3(0.0f);
  const std::uint32_t* triangle = mesh.triangles.data();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t, triangle += 3) {
    if (triangle[0] >= vertex_count || triangle[1] >= vertex_count || triangle[2] >= vertex_count) return false;
    const std::uint32_t a = mesh.vertex_point[triangle[0]];
    const std::uint32_t b = mesh.vertex_point[triangle[1]];
    const std::uint32_t c = mesh.vertex_point[triangle[2]];
    if (a >= point_count || b >= point_count || c >= point_count) return false;
    const glm::vec3 ab = positions[b] - positions[a];
    const glm::vec3 ac = positions[c] - positions[a];
    const glm::vec3 bc = positions[c] - positions[b];
    const glm::vec3 area_normal = glm::cross(ab, ac);  // |area_normal| = 2 * area = |e1||e2| sin(corner angle)
    const float twice_area = glm::length(area_normal);
    if (!(twice_area > 0.0f)) continue;  // degenerate: no direction to contribute
    const glm::vec3 unit_normal = area_normal / twice_area;
    const float angle_a = std::atan2(twice_area, glm::dot(ab, ac));
    const float angle_b = std::atan2(twice_area, -glm::dot(ab, bc));
    const float angle_c = std::numbers::pi_v<float> - angle_a - angle_b;
    scratch[a] += angle_a * unit_normal;
    scratch[b] += angle_b * unit_normal;
    scratch[c] += std::max(angle_c, 0.0f) * unit_normal;
  }
  // The sums are dimensionless (radians times unit normals): below this length the contributions cancelled (a
  // point between opposite faces) and the direction would be rounding noise.
  constexpr float cancelled = 1e-5f;
  for (glm::vec3& n : scratch) {
    const float length = glm::length(n);
    n = length > cancelled ? n / length : glm::vec3(0.0f);
  }
  for (std::size_t r = 0; r < vertex_count; ++r) {
    const std::uint32_t point = mesh.vertex_point[r];
    if (point >= point_count) return false;
    out_vertex_normals[r] = scratch[point];
  }
  return true;
}

Bounds compute_bounds(std::span<const glm::vec3> points) {
  if (points.empty()) return {};
  Bounds bounds{points[0], points[0]};
  for (const glm::vec3& p : points) {
    bounds.min = glm::min(bounds.min, p);
    bounds.max = glm::max(bounds.max, p);
  }
  return bounds;
}

}  // namespace deform
