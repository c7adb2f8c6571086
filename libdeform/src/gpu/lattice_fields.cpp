// GpuLatticeFields (deform/gpu/lattice.hpp): a DeformerHierarchy's fields (and carried points) added in a vertex
// buffer.
#include "deform/gpu/lattice.hpp"

#include <algorithm>

namespace deform {
namespace {

constexpr std::size_t carried_point_count = 8;  // a degree-(1, 1, 1) lattice

// The carried points of `lattice` as a degree-1 Bézier binding with every point at (u, v, w) = (0, 0, 0): there the
// Bernstein bases are exactly 1 and 0, so the field is exactly control point 0, which apply_into() sets to the far
// face's displacement — the GPU adds weight · δ as apply_carried() does, with no shader of its own.
LatticeBinding carried_binding(const DeformerHierarchy& hierarchy, std::size_t lattice) {
  LatticeBinding binding;
  binding.kind = LatticeKind::bezier;
  binding.point_counts = glm::ivec3(2);
  const std::span<const std::uint32_t> points = hierarchy.carried_points(lattice);
  binding.vertices.assign(points.begin(), points.end());
  binding.u.assign(points.size(), 0.0f);
  binding.v.assign(points.size(), 0.0f);
  binding.w.assign(points.size(), 0.0f);
  binding.vertex_count = points.size();
  binding.max_vertex = points.empty() ? 0 : *std::max_element(points.begin(), points.end());
  return binding;
}

}  // namespace

Status GpuLatticeFields::create(const DeformerHierarchy& hierarchy, std::span<const std::uint32_t> vertex_point,
                                bool normals) {
  clear();
  normals_ = normals;
  lattices_.resize(hierarchy.lattice_count());
  carried_.resize(hierarchy.lattice_count());
  std::size_t largest = 0;
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    largest = std::max(largest, hierarchy.rest_lattice(l).point_count());
    // Carried points only translate: their normals stay as skinned, so the carried lattices take none.
    Status status =
        lattices_[l].create_additive(hierarchy.binding(l), hierarchy.bound_weights(l), vertex_point, normals);
    if (status)
      status = carried_[l].create_additive(carried_binding(hierarchy, l), hierarchy.carried_weights(l), vertex_point);
    if (!status) {
      clear();
      return status;
    }
  }
  carried_points_.assign(lattices_.size() * carried_point_count, glm::vec3(0.0f));
  if (normals) mapped_points_.assign(largest, glm::vec3(0.0f));
  return {};
}

Status GpuLatticeFields::add_into(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer,
                                  const GpuVertexLayout& layout) {
  if (hierarchy.lattice_count() != lattices_.size())
    return Status::failure("the hierarchy's lattice count differs from create()'s");
  // A lattice at rest adds nothing (its displacements are below 1e-7 of its length): skipped, as the CPU does.
  for (std::size_t l = 0; l < lattices_.size(); ++l)
    if (hierarchy.active(l))
      if (const Status status = lattices_[l].validate_into(hierarchy.displacements(l), vertex_buffer, layout); !status)
        return status;
  add_fields(hierarchy, vertex_buffer, layout);
  return {};
}

void GpuLatticeFields::add_fields(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer,
                                  const GpuVertexLayout& layout) {
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    if (!hierarchy.active(l)) continue;
    if (!normals_) {
      lattices_[l].evaluate_into(hierarchy.displacements(l), vertex_buffer, layout);
      continue;
    }
    const std::span<glm::vec3> mapped(mapped_points_.data(), hierarchy.rest_lattice(l).point_count());
    hierarchy.mapped_points(l, mapped);
    lattices_[l].evaluate_into(hierarchy.displacements(l), mapped, hierarchy.normals_to_bind(l), vertex_buffer, layout);
  }
}

Status GpuLatticeFields::apply_into(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer,
                                    const GpuVertexLayout& layout) {
  if (hierarchy.lattice_count() != lattices_.size())
    return Status::failure("the hierarchy's lattice count differs from create()'s");
  // Everything is checked before anything is added.
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    const std::span<glm::vec3> points(carried_points_.data() + l * carried_point_count, carried_point_count);
    std::fill(points.begin(), points.end(), hierarchy.far_displacement(l));
    if (!hierarchy.active(l)) continue;
    if (const Status status = carried_[l].validate_into(points, vertex_buffer, layout); !status) return status;
    if (const Status status = lattices_[l].validate_into(hierarchy.displacements(l), vertex_buffer, layout); !status)
      return status;
  }
  // DeformerHierarchy::apply()'s order: every carried translation, then the fields in index order. Each dispatch
  // ends with the barrier that orders the next one's read-modify-write of the same positions after it.
  for (std::size_t l = 0; l < lattices_.size(); ++l)
    if (hierarchy.active(l))
      carried_[l].evaluate_into(
          std::span<const glm::vec3>(carried_points_.data() + l * carried_point_count, carried_point_count),
          vertex_buffer, layout);
  add_fields(hierarchy, vertex_buffer, layout);
  return {};
}

}  // namespace deform
