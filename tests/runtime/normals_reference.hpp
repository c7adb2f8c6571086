#pragma once
// The library's vertex-normal code before VertexNormals (float, std::atan2 per triangle corner), kept as the plain
// reference the fast paths are compared with (normals_test.cpp) and timed against (bench/normals_bench.cpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>

#include <glm/glm.hpp>

#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace normals_reference {

// Angle-weighted normals summed per point in `scratch` (point_count() entries), gathered to `out` (vertex_count()).
inline void atan2_vertex_normals(const deform::Mesh& mesh, std::span<const glm::vec3> positions,
                                 std::span<glm::vec3> scratch, std::span<glm::vec3> out) {
  std::fill(scratch.begin(), scratch.end(), glm::vec3(0.0f));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t a = mesh.vertex_point[mesh.triangles[3 * t]];
    const std::uint32_t b = mesh.vertex_point[mesh.triangles[3 * t + 1]];
    const std::uint32_t c = mesh.vertex_point[mesh.triangles[3 * t + 2]];
    const glm::vec3 ab = positions[b] - positions[a];
    const glm::vec3 ac = positions[c] - positions[a];
    const glm::vec3 bc = positions[c] - positions[b];
    const glm::vec3 area_normal = glm::cross(ab, ac);
    const float twice_area = glm::length(area_normal);
    if (!(twice_area > 0.0f)) continue;
    const glm::vec3 unit_normal = area_normal / twice_area;
    const float angle_a = std::atan2(twice_area, glm::dot(ab, ac));
    const float angle_b = std::atan2(twice_area, -glm::dot(ab, bc));
    const float angle_c = std::numbers::pi_v<float> - angle_a - angle_b;
    scratch[a] += angle_a * unit_normal;
    scratch[b] += angle_b * unit_normal;
    scratch[c] += std::max(angle_c, 0.0f) * unit_normal;
  }
  for (glm::vec3& n : scratch) {
    const float length = glm::length(n);
    n = length > 1e-5f ? n / length : glm::vec3(0.0f);
  }
  for (std::size_t r = 0; r < out.size(); ++r) out[r] = scratch[mesh.vertex_point[r]];
}

}  // namespace normals_reference
