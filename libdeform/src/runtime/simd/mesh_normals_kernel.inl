// The VertexNormalsJob kernel, included once per instruction set (mesh_normals_portable.cpp, _avx2.cpp, _avx512.cpp
// and, on aarch64, _neon.cpp, each compiled with its own flags). Everything here has internal linkage but the one
// entry point the includer names with DEFORM_NORMALS_ENTRY, so the copies never meet at link time.
//
// A range of points [begin, end) (normals.hpp says why this shape): the triangles with a corner in it are computed 16
// at a time in structure-of-arrays lanes, a loop over the lanes around scalar code that the compiler vectorises
// (lanes.hpp: one zmm register per lane vector under AVX-512, two ymm under AVX2, four xmm for the portable copy on
// x86-64). Each point's sum receives its triangles' contributions in triangle order, whatever the range: first those
// of the triangles reaching in from below the range (computed first, parked in their corners' scratch slots, added
// per point in corner order, which is triangle order), then those of the triangles whose lowest point is in the
// range (a run of the binding's triangles, added as computed). Last, 16 points at a time are normalised and written
// to their render vertices.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "lanes.hpp"
#include "mesh_normals_kernel.hpp"

namespace {

constexpr int lanes = 16;

// glm's dot and cross with the products fused (mul_add), as the copies compiled for FMA hardware can.
inline float dot(const glm::vec3& a, const glm::vec3& b) { return mul_add(a.x, b.x, mul_add(a.y, b.y, a.z * b.z)); }
inline glm::vec3 cross(const glm::vec3& a, const glm::vec3& b) {
  return {mul_add(a.y, b.z, -(a.z * b.y)), mul_add(a.z, b.x, -(a.x * b.z)), mul_add(a.x, b.y, -(a.y * b.x))};
}

// contribution[k][axis][lane]: the angle at corner k of triangle `triangle[lane]` times the triangle's unit normal,
// for the first `count` lanes (the others compute a copy of lane 0). Each triangle is computed from its lowest point
// (the binding's order), so its contributions have the same bits whichever range computes it. A degenerate triangle
// (zero or NaN area) contributes exactly nothing, whatever its corners hold.
inline void triangle_contributions(const deform::VertexNormalsBinding& binding, const glm::vec3* positions,
                                   const std::uint32_t (&triangle)[lanes], int count,
                                   float (&contribution)[3][3][lanes]) {
  const std::uint32_t* points = binding.triangle_points.data();
  alignas(64) float corner[3][3][lanes];  // corner, axis, lane
  for (int k = 0; k < 3; ++k)
    for (int lane = 0; lane < lanes; ++lane) {
      const std::size_t t = triangle[lane < count ? lane : 0];
      const glm::vec3& position = positions[points[3 * t + std::size_t(k)]];
      corner[k][0][lane] = position.x, corner[k][1][lane] = position.y, corner[k][2][lane] = position.z;
    }
  for (int lane = 0; lane < lanes; ++lane) {
    const glm::vec3 a(corner[0][0][lane], corner[0][1][lane], corner[0][2][lane]);
    const glm::vec3 b(corner[1][0][lane], corner[1][1][lane], corner[1][2][lane]);
    const glm::vec3 c(corner[2][0][lane], corner[2][1][lane], corner[2][2][lane]);
    const glm::vec3 ab = b - a, ac = c - a, bc = c - b;
    const glm::vec3 area_normal = cross(ab, ac);  // |area_normal| = 2 * area = |e1||e2| sin(corner angle)
    const float twice_area = std::sqrt(dot(area_normal, area_normal));
    const float angle_a = deform::detail::corner_angle(twice_area, dot(ab, ac));
    const float angle_b = deform::detail::corner_angle(twice_area, -dot(ab, bc));
    const float third = std::numbers::pi_v<float> - angle_a - angle_b;
    const float angle_c = third > 0.0f ? third : 0.0f;
    const float inverse_area = 1.0f / twice_area;
    const bool degenerate = !(twice_area > 0.0f);
    const float weight[3] = {angle_a * inverse_area, angle_b * inverse_area, angle_c * inverse_area};
    DEFORM_UNROLL
    for (int k = 0; k < 3; ++k) DEFORM_UNROLL
    for (int axis = 0; axis < 3; ++axis)
      contribution[k][axis][lane] = degenerate ? 0.0f : weight[k] * area_normal[axis];
  }
}

glm::vec4 contribution_of(const float (&contribution)[3][3][lanes], int k, int lane) {
  return {contribution[k][0][lane], contribution[k][1][lane], contribution[k][2][lane], 0.0f};
}

}  // namespace

namespace deform::detail {

void DEFORM_NORMALS_ENTRY(const NormalsKernelArgs& args) noexcept {
  const VertexNormalsBinding& binding = *args.binding;
  const std::uint32_t* offsets = binding.corner_offsets.data();
  const std::uint32_t* triangle_points = binding.triangle_points.data();
  const std::size_t begin = args.begin, end = args.end;
  const std::size_t first_owned = binding.triangle_offsets[begin], last_owned = binding.triangle_offsets[end];
  glm::vec4* sums = args.scratch;                          // per point
  glm::vec4* parked = args.scratch + binding.point_count;  // per corner
  std::uint32_t triangle[lanes];
  alignas(64) float contribution[3][3][lanes];

  // 1. The triangles whose lowest point is below the range and another in it, once each (at the first of their
  // points in the range), their in-range corners' contributions parked in the corners' slots. Rare after the first
  // points of a range on a mesh numbered with any locality; none when the range starts at 0.
  if (begin > 0) {
    int count = 0;
    const auto park = [&] {
      triangle_contributions(binding, args.positions, triangle, count, contribution);
      for (int lane = 0; lane < count; ++lane)
        for (int k = 0; k < 3; ++k) {
          const std::size_t index = 3 * std::size_t(triangle[lane]) + std::size_t(k);
          const std::size_t point = triangle_points[index];
          if (point >= begin && point < end)
            parked[binding.triangle_corners[index]] = contribution_of(contribution, k, lane);
        }
      count = 0;
    };
    for (std::size_t p = begin; p < end; ++p)
      for (std::size_t c = offsets[p]; c < offsets[p + 1]; ++c) {
        const std::uint32_t t = binding.corner_triangle[c];
        if (t >= first_owned) break;  // the corners are in triangle order: the rest are the range's own
        const std::uint32_t* points = triangle_points + 3 * std::size_t(t);
        const std::size_t other = points[1] == p ? points[2] : points[1];
        if (other >= begin && other < p) continue;  // parked at `other`
        triangle[count++] = t;
        if (count == lanes) park();
      }
    if (count > 0) park();
  }

  // 2. Each point's sum starts with its parked contributions, in corner (= triangle) order.
  for (std::size_t p = begin; p < end; ++p) {
    glm::vec4 sum(0.0f);
    if (begin > 0)
      for (std::size_t c = offsets[p]; c < offsets[p + 1] && binding.corner_triangle[c] < first_owned; ++c)
        sum += parked[c];
    sums[p] = sum;
  }

  // 3. The triangles whose lowest point is in the range, in order: each adds to its corners' points in the range.
  for (std::size_t first = first_owned; first < last_owned; first += lanes) {
    const int count = int(std::min<std::size_t>(lanes, last_owned - first));
    for (int lane = 0; lane < lanes; ++lane)
      triangle[lane] = std::uint32_t(first + std::size_t(lane < count ? lane : 0));
    triangle_contributions(binding, args.positions, triangle, count, contribution);
    for (int lane = 0; lane < count; ++lane) {
      const std::uint32_t* points = triangle_points + 3 * (first + std::size_t(lane));
      sums[points[0]] += contribution_of(contribution, 0, lane);  // the lowest point: in the range
      for (int k = 1; k < 3; ++k)
        if (points[k] < end) sums[points[k]] += contribution_of(contribution, k, lane);
    }
  }

  // 4. 16 points at a time, normalised (a cancelled or NaN sum gives (0, 0, 0)) and written to their render vertices.
  for (std::size_t first = begin; first < end; first += lanes) {
    const int count = int(std::min<std::size_t>(lanes, end - first));
    alignas(64) float sum[3][lanes] = {}, normal[3][lanes];
    for (int lane = 0; lane < count; ++lane) {
      const glm::vec4& s = sums[first + std::size_t(lane)];
      sum[0][lane] = s.x, sum[1][lane] = s.y, sum[2][lane] = s.z;
    }
    for (int lane = 0; lane < lanes; ++lane) {
      const float x = sum[0][lane], y = sum[1][lane], z = sum[2][lane];
      const float length = std::sqrt(mul_add(x, x, mul_add(y, y, z * z)));
      const bool kept = length > cancelled_normal_sum;
      normal[0][lane] = kept ? x / length : 0.0f;
      normal[1][lane] = kept ? y / length : 0.0f;
      normal[2][lane] = kept ? z / length : 0.0f;
    }
    for (int lane = 0; lane < count; ++lane) {
      const std::size_t p = first + std::size_t(lane);
      const glm::vec3 n(normal[0][lane], normal[1][lane], normal[2][lane]);
      for (std::uint32_t v = binding.vertex_offsets[p]; v < binding.vertex_offsets[p + 1]; ++v)
        args.normals[binding.point_vertices[v]] = n;
    }
  }
}

}  // namespace deform::detail
