// Direct manipulation of FFD (Hsu, Hughes & Kaufman 1992): the minimum-norm control point displacement that moves one
// embedded point to a target. With the basis row B (B_ijk at the point), the least-norm solution of B·ΔP = Δq is the
// pseudo-inverse B⁺ = Bᵀ / (B·Bᵀ), i.e. ΔP_ijk = B_ijk / Σ B² · Δq; the point then lands exactly, as Σ B·ΔP = Δq.
#include "deform/runtime/lattice.hpp"
#include "simd/lattice_kernel.hpp"

namespace deform {

void BezierLattice::move_point(glm::vec3 uvw, glm::vec3 target) noexcept {
  const glm::ivec3 d = degree();
  float bu[max_bezier_degree + 1], bv[max_bezier_degree + 1], bw[max_bezier_degree + 1];
  detail::bernstein(d.x, uvw.x, bu, nullptr);
  detail::bernstein(d.y, uvw.y, bv, nullptr);
  detail::bernstein(d.z, uvw.z, bw, nullptr);
  float su = 0.0f, sv = 0.0f, sw = 0.0f;  // Σ B_ijk² factorises into the three axes
  for (int i = 0; i <= d.x; ++i) su += bu[i] * bu[i];
  for (int j = 0; j <= d.y; ++j) sv += bv[j] * bv[j];
  for (int k = 0; k <= d.z; ++k) sw += bw[k] * bw[k];
  const glm::vec3 step = (target - evaluate(uvw)) / (su * sv * sw);
  for (int k = 0; k <= d.z; ++k)
    for (int j = 0; j <= d.y; ++j)
      for (int i = 0; i <= d.x; ++i) points_[index(i, j, k)] += (bu[i] * bv[j] * bw[k]) * step;
}

void BsplineLattice::move_point(glm::vec3 uvw, glm::vec3 target) noexcept {
  const glm::ivec3 cells = cell_counts();
  glm::vec3 t;
  const int ci = detail::cell_of(uvw.x, cells.x, t.x), cj = detail::cell_of(uvw.y, cells.y, t.y),
            ck = detail::cell_of(uvw.z, cells.z, t.z);
  float bu[4], bv[4], bw[4];
  detail::bspline_basis(t.x, bu, nullptr);
  detail::bspline_basis(t.y, bv, nullptr);
  detail::bspline_basis(t.z, bw, nullptr);
  float su = 0.0f, sv = 0.0f, sw = 0.0f;
  for (int a = 0; a < 4; ++a) su += bu[a] * bu[a], sv += bv[a] * bv[a], sw += bw[a] * bw[a];
  const glm::vec3 step = (target - evaluate(uvw)) / (su * sv * sw);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) points_[index(ci + i, cj + j, ck + k)] += (bu[i] * bv[j] * bw[k]) * step;
}

}  // namespace deform
