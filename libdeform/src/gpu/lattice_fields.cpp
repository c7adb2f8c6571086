// GpuLatticeFields (deform/gpu/lattice.hpp): a DeformerHierarchy's fields added in a vertex buffer.
#include "deform/gpu/lattice.hpp"

namespace deform {

Status GpuLatticeFields::create(const DeformerHierarchy& hierarchy, std::span<const std::uint32_t> vertex_point) {
  lattices_.clear();
  lattices_.resize(hierarchy.lattice_count());
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    const Status status = lattices_[l].create_additive(hierarchy.binding(l), hierarchy.bound_weights(l), vertex_point);
    if (!status) {
      lattices_.clear();
      return status;
    }
  }
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
  for (std::size_t l = 0; l < lattices_.size(); ++l)
    if (hierarchy.active(l)) lattices_[l].evaluate_into(hierarchy.displacements(l), vertex_buffer, layout);
  return {};
}

}  // namespace deform
