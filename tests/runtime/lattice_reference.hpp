#pragma once
// The plain reference of the lattice maths, straight from the equations, in double: Bernstein polynomials with pow and
// binomial coefficients (thesis eqs. 32-35), uniform cubic B-splines by the Cox-de Boor recursion. Slow on purpose.
#include <algorithm>
#include <cmath>
#include <span>

#include <glm/glm.hpp>

namespace lattice_reference {

inline double binomial(int n, int k) {
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// B_i,n(t) = C(n, i) t^i (1 - t)^(n - i) and its derivative.
inline double bernstein(int n, int i, double t) { return binomial(n, i) * std::pow(t, i) * std::pow(1.0 - t, n - i); }
inline double bernstein_derivative(int n, int i, double t) {
  double d = 0.0;
  if (i > 0) d += i * std::pow(t, i - 1) * std::pow(1.0 - t, n - i);
  if (i < n) d -= (n - i) * std::pow(t, i) * std::pow(1.0 - t, n - i - 1);
  return binomial(n, i) * d;
}

// Q(u, v, w) = Σ P_ijk B_i,l(u) B_j,m(v) B_k,n(w), control points i-fastest.
inline glm::dvec3 bezier(std::span<const glm::vec3> p, glm::ivec3 degree, glm::dvec3 uvw) {
  glm::dvec3 q(0.0);
  for (int k = 0; k <= degree.z; ++k)
    for (int j = 0; j <= degree.y; ++j)
      for (int i = 0; i <= degree.x; ++i)
        q += glm::dvec3(p[static_cast<std::size_t>(i + (degree.x + 1) * (j + (degree.y + 1) * k))]) *
             bernstein(degree.x, i, uvw.x) * bernstein(degree.y, j, uvw.y) * bernstein(degree.z, k, uvw.z);
  return q;
}

inline glm::dmat3 bezier_jacobian(std::span<const glm::vec3> p, glm::ivec3 degree, glm::dvec3 uvw) {
  glm::dmat3 jac(0.0);
  for (int k = 0; k <= degree.z; ++k)
    for (int j = 0; j <= degree.y; ++j)
      for (int i = 0; i <= degree.x; ++i) {
        const glm::dvec3 x(p[static_cast<std::size_t>(i + (degree.x + 1) * (j + (degree.y + 1) * k))]);
        const double bu = bernstein(degree.x, i, uvw.x), bv = bernstein(degree.y, j, uvw.y),
                     bw = bernstein(degree.z, k, uvw.z);
        jac[0] += x * bernstein_derivative(degree.x, i, uvw.x) * bv * bw;
        jac[1] += x * bu * bernstein_derivative(degree.y, j, uvw.y) * bw;
        jac[2] += x * bu * bv * bernstein_derivative(degree.z, k, uvw.z);
      }
  return jac;
}

// The uniform cubic B-spline N(x) on the integer knots 0..4 (Cox-de Boor), support [0, 4).
inline double cox_de_boor(int degree, int first_knot, double x) {
  if (degree == 0) return (x >= first_knot && x < first_knot + 1) ? 1.0 : 0.0;
  return (x - first_knot) / degree * cox_de_boor(degree - 1, first_knot, x) +
         (first_knot + degree + 1 - x) / degree * cox_de_boor(degree - 1, first_knot + 1, x);
}

// Q(u, v, w) = Σ P_ijk N(s_u − i + 3) N(s_v − j + 3) N(s_w − k + 3), s = u · cells; the last cell is closed at s =
// cells.
inline glm::dvec3 bspline(std::span<const glm::vec3> p, glm::ivec3 counts, glm::dvec3 uvw) {
  const glm::dvec3 cells = glm::dvec3(counts - 3);
  glm::dvec3 s = uvw * cells;
  for (int a = 0; a < 3; ++a)
    if (s[a] >= cells[a]) s[a] = cells[a] * (1.0 - 1e-15);  // evaluate the last cell's polynomial at its end
  glm::dvec3 q(0.0);
  for (int k = 0; k < counts.z; ++k)
    for (int j = 0; j < counts.y; ++j)
      for (int i = 0; i < counts.x; ++i) {
        const double b =
            cox_de_boor(3, 0, s.x - i + 3) * cox_de_boor(3, 0, s.y - j + 3) * cox_de_boor(3, 0, s.z - k + 3);
        if (b != 0.0) q += b * glm::dvec3(p[static_cast<std::size_t>(i + counts.x * (j + counts.y * k))]);
      }
  return q;
}

// ∂Q/∂(u, v, w) of the B-spline reference by central differences in double (the map is C² inside the box).
inline glm::dmat3 bspline_jacobian(std::span<const glm::vec3> p, glm::ivec3 counts, glm::dvec3 uvw) {
  glm::dmat3 jac;
  const double h = 1e-6;
  for (int a = 0; a < 3; ++a) {
    glm::dvec3 lo = uvw, hi = uvw;
    lo[a] = std::max(0.0, uvw[a] - h);
    hi[a] = std::min(1.0, uvw[a] + h);
    jac[a] = (bspline(p, counts, hi) - bspline(p, counts, lo)) / (hi[a] - lo[a]);
  }
  return jac;
}

// cof(J)·n normalised: the normal a map with Jacobian J gives a surface of normal n.
inline glm::dvec3 transform_normal(const glm::dmat3& j, glm::dvec3 n) {
  // det(J)·J^-T: its columns are the cross products of J's columns (the rows of det(J)·J⁻¹).
  const glm::dmat3 cof(glm::cross(j[1], j[2]), glm::cross(j[2], j[0]), glm::cross(j[0], j[1]));
  return glm::normalize(cof * n);
}

}  // namespace lattice_reference
