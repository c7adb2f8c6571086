// Vertex selection (inside the box, index lists, skin weights: §9.4.1) and the
// construction of bindings.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "finite.hpp"
#include "lattice_cells.hpp"

namespace deform {

namespace detail {
namespace {

// A point chosen for a lattice: its index, the first control point of its cell (0 for Bézier) and its parameters
// within the cell.
struct BoundVertex {
  std::uint32_t vertex;
  std::uint32_t first_point;
  glm::vec3 param;
};

// The candidates (all points when `all`) whose (u, v, w) under `to_lattice` lies in [0, 1]³, with those parameters
// in `param`. Throws deform::Error for a candidate out of range or a non-finite position.
std::vector<BoundVertex> collect_inside(const LatticeFrame& frame, std::span<const glm::vec3> positions,
                                        std::span<const std::uint32_t> candidates, bool all,
                                        const glm::mat4& to_lattice) {
  const bool identity = to_lattice == glm::mat4(1.0f);
  const std::size_t count = all ? positions.size() : candidates.size();
  std::vector<BoundVertex> list;
  for (std::size_t c = 0; c < count; ++c) {
    const std::size_t p = all ? c : candidates[c];
    if (p >= positions.size() || p >= LatticeBinding::no_vertex)
      throw Error::invalid_argument(
          "candidate " + std::to_string(c),
          "point " + std::to_string(p) + " is out of range (" + std::to_string(positions.size()) + " points)");
    if (!finite(positions[p])) throw Error::invalid_argument("vertex " + std::to_string(p), "position is not finite");
    const glm::vec3 x = identity ? positions[p] : glm::vec3(to_lattice * glm::vec4(positions[p], 1.0f));
    const glm::vec3 uvw = frame.to_lattice(x);
    if (glm::all(glm::greaterThanEqual(uvw, glm::vec3(0.0f))) && glm::all(glm::lessThanEqual(uvw, glm::vec3(1.0f))))
      list.push_back({static_cast<std::uint32_t>(p), 0, uvw});
  }
  return list;
}

// Groups the vertices into blocks (stable by first_point) and fills a binding.
// `parameter_scale` = d(cell parameter)/d(u, v, w) per axis (1 for Bézier, the cell counts for a B-spline).
LatticeBinding make_binding(LatticeKind kind, glm::ivec3 point_counts, const LatticeFrame& frame,
                            glm::vec3 parameter_scale, const glm::mat4& to_lattice, std::vector<BoundVertex> list) {
  std::stable_sort(list.begin(), list.end(),
                   [](const BoundVertex& a, const BoundVertex& b) { return a.first_point < b.first_point; });
  LatticeBinding binding;
  binding.kind = kind;
  binding.point_counts = point_counts;
  // Normals go into the frame's space by cof(to_lattice), into (u, v, w) by cof(M⁻¹) ∝ Mᵀ, into cell parameters by
  // cof(diag(scale)); the kernel then applies cof(∂Q/∂t). Positive factors are dropped: normals are normalised.
  const glm::mat3 axes(frame.u_axis, frame.v_axis, frame.w_axis);
  binding.normal_basis = cofactor(glm::mat3(glm::vec3(parameter_scale.x, 0, 0), glm::vec3(0, parameter_scale.y, 0),
                                            glm::vec3(0, 0, parameter_scale.z))) *
                         glm::transpose(axes) * cofactor(glm::mat3(to_lattice));
  binding.vertex_count = list.size();
  constexpr std::size_t lanes = LatticeBinding::block_size;
  for (std::size_t begin = 0; begin < list.size();) {
    std::size_t end = begin;
    while (end < list.size() && end - begin < lanes && list[end].first_point == list[begin].first_point) ++end;
    binding.block_first_point.push_back(list[begin].first_point);
    for (std::size_t i = begin; i < begin + lanes; ++i) {
      const bool real = i < end;
      binding.vertices.push_back(real ? list[i].vertex : LatticeBinding::no_vertex);
      binding.u.push_back(real ? list[i].param.x : 0.0f);
      binding.v.push_back(real ? list[i].param.y : 0.0f);
      binding.w.push_back(real ? list[i].param.z : 0.0f);
      if (real) binding.max_vertex = std::max(binding.max_vertex, list[i].vertex);
    }
    begin = end;
  }
  return binding;
}

}  // namespace
}  // namespace detail

std::vector<std::uint32_t> select_by_weight(const SkinWeights& weights, std::uint16_t bone, float threshold) {
  std::vector<std::uint32_t> out;
  const std::size_t count = std::min(weights.bones.size(), weights.weights.size());
  for (std::size_t p = 0; p < count; ++p) {
    float w = 0.0f;
    for (int s = 0; s < max_influences; ++s)
      if (weights.bones[p][s] == bone) w += weights.weights[p][s];
    if (w > threshold) out.push_back(static_cast<std::uint32_t>(p));
  }
  return out;
}

std::vector<std::uint32_t> select_inside(const LatticeFrame& frame, std::span<const glm::vec3> positions,
                                         const glm::mat4& to_lattice) {
  std::vector<std::uint32_t> out;
  for (const detail::BoundVertex& b : detail::collect_inside(frame, positions, {}, true, to_lattice))
    out.push_back(b.vertex);
  return out;
}

namespace {

LatticeBinding bind_cells(const BsplineLattice& lattice, std::vector<detail::BoundVertex> list,
                          const glm::mat4& to_lattice) {
  const glm::ivec3 cells = lattice.cell_counts();
  for (detail::BoundVertex& b : list) {
    glm::vec3 t;
    const int ci = detail::cell_of(b.param.x, cells.x, t.x), cj = detail::cell_of(b.param.y, cells.y, t.y),
              ck = detail::cell_of(b.param.z, cells.z, t.z);
    b.first_point = static_cast<std::uint32_t>(lattice.index(ci, cj, ck));
    b.param = t;
  }
  return detail::make_binding(LatticeKind::bspline, lattice.point_counts(), lattice.frame(), glm::vec3(cells),
                              to_lattice, std::move(list));
}

}  // namespace

LatticeBinding bind_lattice(const BezierLattice& lattice, std::span<const glm::vec3> positions,
                            std::span<const std::uint32_t> candidates, const glm::mat4& to_lattice) {
  return detail::make_binding(LatticeKind::bezier, lattice.point_counts(), lattice.frame(), glm::vec3(1.0f), to_lattice,
                              detail::collect_inside(lattice.frame(), positions, candidates, false, to_lattice));
}

LatticeBinding bind_lattice(const BezierLattice& lattice, std::span<const glm::vec3> positions,
                            const glm::mat4& to_lattice) {
  return detail::make_binding(LatticeKind::bezier, lattice.point_counts(), lattice.frame(), glm::vec3(1.0f), to_lattice,
                              detail::collect_inside(lattice.frame(), positions, {}, true, to_lattice));
}

LatticeBinding bind_lattice(const BsplineLattice& lattice, std::span<const glm::vec3> positions,
                            std::span<const std::uint32_t> candidates, const glm::mat4& to_lattice) {
  return bind_cells(lattice, detail::collect_inside(lattice.frame(), positions, candidates, false, to_lattice),
                    to_lattice);
}

LatticeBinding bind_lattice(const BsplineLattice& lattice, std::span<const glm::vec3> positions,
                            const glm::mat4& to_lattice) {
  return bind_cells(lattice, detail::collect_inside(lattice.frame(), positions, {}, true, to_lattice), to_lattice);
}

}  // namespace deform
