// Angle-weighted vertex normals (Thürmer & Wüthrich, "Computing vertex normals from polygonal facets", 1998) and
// bounds: per-frame safe (no allocation, no exceptions). VertexNormals runs the block kernel of
// mesh_normals_kernel.inl: the portable, AVX2 or AVX-512 copy, as its Isa says (isa.hpp).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "mesh_normals_kernel.hpp"

namespace deform {
namespace {

using KernelEntry = void (*)(const detail::NormalsKernelArgs&) noexcept;

// The copy for `isa`, which isa_available() has accepted.
KernelEntry kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::vertex_normals_avx512;
  if (isa == Isa::avx2) return detail::vertex_normals_avx2;
#endif
  return detail::vertex_normals_portable;
}

constexpr std::size_t block = detail::triangles_per_block;

}  // namespace

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
    const float angle_a = detail::corner_angle(twice_area, glm::dot(ab, ac));
    const float angle_b = detail::corner_angle(twice_area, -glm::dot(ab, bc));
    const float angle_c = std::numbers::pi_v<float> - angle_a - angle_b;
    scratch[a] += angle_a * unit_normal;
    scratch[b] += angle_b * unit_normal;
    scratch[c] += std::max(angle_c, 0.0f) * unit_normal;
  }
  for (glm::vec3& n : scratch) {
    const float length = glm::length(n);
    n = length > detail::cancelled_normal_sum ? n / length : glm::vec3(0.0f);
  }
  for (std::size_t r = 0; r < vertex_count; ++r) {
    const std::uint32_t point = mesh.vertex_point[r];
    if (point >= point_count) return false;
    out_vertex_normals[r] = scratch[point];
  }
  return true;
}

VertexNormals::VertexNormals(const Mesh& mesh) : vertex_point_(mesh.vertex_point), point_sums_(mesh.point_count()) {
  const std::size_t point_count = mesh.point_count();
  if (mesh.triangles.size() % 3 != 0)
    throw std::invalid_argument("VertexNormals: triangle index count not a multiple of 3");
  for (const std::uint32_t point : vertex_point_)
    if (point >= point_count) throw std::invalid_argument("VertexNormals: vertex_point index out of range");
  std::vector<std::uint32_t> kept;  // 3 points per triangle without a repeated point
  kept.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::uint32_t p[3];
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t vertex = mesh.triangles[3 * t + k];
      if (vertex >= vertex_point_.size()) throw std::invalid_argument("VertexNormals: triangle index out of range");
      p[k] = vertex_point_[vertex];
    }
    if (p[0] != p[1] && p[1] != p[2] && p[0] != p[2]) kept.insert(kept.end(), {p[0], p[1], p[2]});
  }
  triangle_count_ = kept.size() / 3;
  block_points_.assign(3 * block * ((triangle_count_ + block - 1) / block), 0);
  for (std::size_t t = 0; t < triangle_count_; ++t)
    for (std::size_t k = 0; k < 3; ++k)
      block_points_[3 * block * (t / block) + block * k + t % block] = kept[3 * t + k];
}

bool VertexNormals::compute(std::span<const glm::vec3> positions, std::span<glm::vec3> out_vertex_normals,
                            Isa isa) {
  if (positions.size() != point_count() || out_vertex_normals.size() != vertex_count() || !isa_available(isa))
    return false;
  const detail::NormalsKernelArgs args{block_points_.data(), triangle_count_, positions.data(), point_sums_.data(),
                                       point_sums_.size()};
  kernel_for(isa)(args);
  for (std::size_t r = 0; r < vertex_point_.size(); ++r)
    out_vertex_normals[r] = glm::vec3(point_sums_[vertex_point_[r]]);
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
