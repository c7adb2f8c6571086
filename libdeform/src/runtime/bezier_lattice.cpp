// BezierLattice: a trivariate Bézier volume of degree (l, m, n) (thesis eq. 35 generalised; Sederberg & Parry 1986).
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "simd/lattice_kernel.hpp"

namespace deform {
namespace detail {

// B_0..n,n(t) by de Casteljau's triangle; `lower` (when not null) receives the degree n − 1 basis.
void bernstein(int n, float t, float* b, float* lower) noexcept {
  const float s = 1.0f - t;
  b[0] = 1.0f;
  for (int r = 1; r <= n; ++r) {
    if (r == n && lower)
      for (int i = 0; i < n; ++i) lower[i] = b[i];
    float saved = 0.0f;
    for (int i = 0; i < r; ++i) {
      const float tmp = b[i];
      b[i] = saved + s * tmp;
      saved = t * tmp;
    }
    b[r] = saved;
  }
}

}  // namespace detail
namespace {

using detail::bernstein;

// B'_i,n = n·(B_i−1,n−1 − B_i,n−1).
void bernstein_derivative(int n, const float* lower, float* d) noexcept {
  const float fn = static_cast<float>(n);
  for (int i = 0; i <= n; ++i) d[i] = fn * ((i > 0 ? lower[i - 1] : 0.0f) - (i < n ? lower[i] : 0.0f));
}

constexpr int max_n = max_bezier_degree + 1;

}  // namespace

BezierLattice::BezierLattice(const LatticeFrame& frame, glm::ivec3 degree, const std::string& source)
    : frame_(frame), point_counts_(degree + 1) {
  frame.require_valid(source, "frame");
  const char* axis = "lmn";
  for (int a = 0; a < 3; ++a)
    if (degree[a] < 1 || degree[a] > max_bezier_degree)
      throw Error::in_file(
          source, std::string("degree ") + axis[a],
          "degree " + std::to_string(degree[a]) + " is outside [1, " + std::to_string(max_bezier_degree) + "]");
  points_.resize(static_cast<std::size_t>(point_counts_.x) * point_counts_.y * point_counts_.z);
  reset();
}

glm::vec3 BezierLattice::rest_point(int i, int j, int k) const noexcept {
  const glm::vec3 d = glm::vec3(degree());
  return frame_.to_world(glm::vec3(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k)) / d);
}

void BezierLattice::reset() noexcept {
  for (int k = 0; k < point_counts_.z; ++k)
    for (int j = 0; j < point_counts_.y; ++j)
      for (int i = 0; i < point_counts_.x; ++i) points_[index(i, j, k)] = rest_point(i, j, k);
}

glm::vec3 BezierLattice::evaluate(glm::vec3 uvw) const noexcept {
  const glm::ivec3 d = degree();
  float bu[max_n], bv[max_n], bw[max_n];
  bernstein(d.x, uvw.x, bu, nullptr);
  bernstein(d.y, uvw.y, bv, nullptr);
  bernstein(d.z, uvw.z, bw, nullptr);
  glm::vec3 q(0.0f);
  for (int k = 0; k <= d.z; ++k) {
    glm::vec3 s(0.0f);
    for (int j = 0; j <= d.y; ++j) {
      glm::vec3 r(0.0f);
      for (int i = 0; i <= d.x; ++i) r += bu[i] * points_[index(i, j, k)];
      s += bv[j] * r;
    }
    q += bw[k] * s;
  }
  return q;
}

glm::mat3 BezierLattice::jacobian(glm::vec3 uvw) const noexcept {
  const glm::ivec3 d = degree();
  float bu[max_n], bv[max_n], bw[max_n], lu[max_n], lv[max_n], lw[max_n], du[max_n], dv[max_n], dw[max_n];
  bernstein(d.x, uvw.x, bu, lu);
  bernstein(d.y, uvw.y, bv, lv);
  bernstein(d.z, uvw.z, bw, lw);
  bernstein_derivative(d.x, lu, du);
  bernstein_derivative(d.y, lv, dv);
  bernstein_derivative(d.z, lw, dw);
  glm::mat3 j(0.0f);
  for (int k = 0; k <= d.z; ++k)
    for (int jj = 0; jj <= d.y; ++jj)
      for (int i = 0; i <= d.x; ++i) {
        const glm::vec3 p = points_[index(i, jj, k)];
        j[0] += du[i] * bv[jj] * bw[k] * p;
        j[1] += bu[i] * dv[jj] * bw[k] * p;
        j[2] += bu[i] * bv[jj] * dw[k] * p;
      }
  return j;
}

}  // namespace deform
