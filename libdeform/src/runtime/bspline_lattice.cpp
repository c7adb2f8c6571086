// BsplineLattice: a uniform cubic B-spline volume of any resolution; each vertex touches the 4×4×4 control points of
// its cell (beyond the thesis, which notes that raising the Bézier degree costs n³ per vertex and stays global).
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "simd/lattice_kernel.hpp"

namespace deform {
namespace detail {

// The uniform cubic B-spline basis on one segment, t ∈ [0, 1], and its derivative in t.
void bspline_basis(float t, float* b, float* d) noexcept {
  const float s = 1.0f - t, t2 = t * t;
  b[0] = s * s * s / 6.0f;
  b[1] = (3.0f * t2 * t - 6.0f * t2 + 4.0f) / 6.0f;
  b[2] = (-3.0f * t2 * t + 3.0f * t2 + 3.0f * t + 1.0f) / 6.0f;
  b[3] = t2 * t / 6.0f;
  if (d) {
    d[0] = -0.5f * s * s;
    d[1] = 1.5f * t2 - 2.0f * t;
    d[2] = -1.5f * t2 + t + 0.5f;
    d[3] = 0.5f * t2;
  }
}

}  // namespace detail

using detail::bspline_basis;
using detail::cell_of;

BsplineLattice::BsplineLattice(const LatticeFrame& frame, glm::ivec3 point_counts, const std::string& source)
    : frame_(frame), point_counts_(point_counts) {
  frame.require_valid(source, "frame");
  const char* axis = "uvw";
  for (int a = 0; a < 3; ++a)
    if (point_counts[a] < 4 || point_counts[a] > max_bspline_points)
      throw Error::in_file(source, std::string("point count ") + axis[a],
                           std::to_string(point_counts[a]) + " control points is outside [4, " +
                               std::to_string(max_bspline_points) + "]");
  const std::size_t count = static_cast<std::size_t>(point_counts.x) * point_counts.y * point_counts.z;
  if (count > (std::size_t{1} << 26))
    throw Error::in_file(source, "point counts", std::to_string(count) + " control points is more than 2^26");
  points_.resize(count);
  reset();
}

glm::vec3 BsplineLattice::rest_point(int i, int j, int k) const noexcept {
  const glm::vec3 cells = glm::vec3(cell_counts());
  return frame_.to_world(glm::vec3(static_cast<float>(i - 1), static_cast<float>(j - 1), static_cast<float>(k - 1)) /
                         cells);
}

void BsplineLattice::reset() noexcept {
  for (int k = 0; k < point_counts_.z; ++k)
    for (int j = 0; j < point_counts_.y; ++j)
      for (int i = 0; i < point_counts_.x; ++i) points_[index(i, j, k)] = rest_point(i, j, k);
}

glm::vec3 BsplineLattice::evaluate(glm::vec3 uvw) const noexcept {
  const glm::ivec3 cells = cell_counts();
  glm::vec3 t;
  const int ci = cell_of(uvw.x, cells.x, t.x), cj = cell_of(uvw.y, cells.y, t.y), ck = cell_of(uvw.z, cells.z, t.z);
  float bu[4], bv[4], bw[4];
  bspline_basis(t.x, bu, nullptr);
  bspline_basis(t.y, bv, nullptr);
  bspline_basis(t.z, bw, nullptr);
  glm::vec3 q(0.0f);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) q += bu[i] * bv[j] * bw[k] * points_[index(ci + i, cj + j, ck + k)];
  return q;
}

glm::mat3 BsplineLattice::jacobian(glm::vec3 uvw) const noexcept {
  const glm::ivec3 cells = cell_counts();
  glm::vec3 t;
  const int ci = cell_of(uvw.x, cells.x, t.x), cj = cell_of(uvw.y, cells.y, t.y), ck = cell_of(uvw.z, cells.z, t.z);
  float bu[4], bv[4], bw[4], du[4], dv[4], dw[4];
  bspline_basis(t.x, bu, du);
  bspline_basis(t.y, bv, dv);
  bspline_basis(t.z, bw, dw);
  glm::mat3 jac(0.0f);
  const glm::vec3 base = points_[index(ci + 1, cj + 1, ck + 1)];  // derivatives are differences: keep them precise
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const glm::vec3 p = points_[index(ci + i, cj + j, ck + k)] - base;
        jac[0] += du[i] * bv[j] * bw[k] * p;
        jac[1] += bu[i] * dv[j] * bw[k] * p;
        jac[2] += bu[i] * bv[j] * dw[k] * p;
      }
  // d/du = (cells along u) · d/dt.
  jac[0] *= static_cast<float>(cells.x);
  jac[1] *= static_cast<float>(cells.y);
  jac[2] *= static_cast<float>(cells.z);
  return jac;
}

}  // namespace deform
