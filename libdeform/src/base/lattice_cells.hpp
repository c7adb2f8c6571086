#pragma once
// Base (private to libdeform, not installed; docs/architecture.md, "Walls"): the lattice arithmetic that binding
// (offline) and evaluation (runtime) must agree on, so that a point is evaluated in the cell it was bound in.
#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

namespace deform::detail {

// The cell of x ∈ [0, 1] among `cells` (clamped) and t within it. (The last cell owns x = 1; parameters outside
// [0, 1] stay on the border cells' polynomials.)
inline int cell_of(float x, int cells, float& t) noexcept {
  const float s = x * static_cast<float>(cells);
  const int c = std::clamp(static_cast<int>(std::floor(s)), 0, cells - 1);
  t = s - static_cast<float>(c);
  return c;
}

// Cofactor matrix det(A)·A^-T (maps normals through A up to a positive factor when det A > 0). The rows of det(A)·A⁻¹
// are the cross products of A's columns, so they are the columns of det(A)·A^-T.
inline glm::mat3 cofactor(const glm::mat3& a) noexcept {
  return glm::mat3(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]), glm::cross(a[0], a[1]));
}

}  // namespace deform::detail
