// LatticeEvaluateJob: validation and the choice of the kernel copy the job's Isa names.
#include <cmath>
#include <cstdint>

#include "deform/runtime/lattice.hpp"
#include "finite.hpp"
#include "simd/lattice_kernel.hpp"

namespace deform {
namespace {

using Kernel = void (*)(const detail::KernelArgs&);

// The copy for `isa`, which isa_available() has accepted.
Kernel kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::evaluate_lattice_avx512;
  if (isa == Isa::avx2) return detail::evaluate_lattice_avx2;
#endif
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return detail::evaluate_lattice_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return detail::evaluate_lattice_simd128;
#endif
  return detail::evaluate_lattice_portable;
}

bool counts_in(glm::ivec3 counts, int low, int high) noexcept {
  return counts.x >= low && counts.y >= low && counts.z >= low && counts.x <= high && counts.y <= high &&
         counts.z <= high;
}

// Everything validate() checks that costs O(1).
Status layout_ok(const LatticeEvaluateJob& job) noexcept {
  const LatticeBinding* binding = job.binding;
  if (!binding) return Status::failure("no binding");
  // The kernels size their per-block arrays by the Bézier degree and read a B-spline cell's 4×4×4 points.
  const glm::ivec3 counts = binding->point_counts;
  const bool bezier = binding->kind == LatticeKind::bezier && counts_in(counts, 2, max_bezier_degree + 1);
  const bool bspline = binding->kind == LatticeKind::bspline && counts_in(counts, 4, max_bspline_points);
  if (!bezier && !bspline) return Status::failure("binding point counts invalid");
  const std::size_t lanes = binding->block_count() * LatticeBinding::block_size;
  if (binding->vertices.size() != lanes || binding->u.size() != lanes || binding->v.size() != lanes ||
      binding->w.size() != lanes)
    return Status::failure("binding arrays differ in size");
  if (job.control_points.size() != binding->control_point_count())
    return Status::failure("control point count differs from the binding");
  const std::size_t needed = binding->vertex_count == 0 ? 0 : std::size_t{binding->max_vertex} + 1;
  if (job.normals_in.empty() != job.normals_out.empty())
    return Status::failure("normals_in and normals_out: both or neither");
  const bool normals_only = job.positions.empty() && !job.normals_out.empty();
  if (job.positions.size() < needed && !normals_only) return Status::failure("positions too short");
  if (!job.normals_out.empty() && (job.normals_in.size() < needed || job.normals_out.size() < needed))
    return Status::failure("normals too short");
  if (!job.weights.empty() && job.weights.size() != lanes) return Status::failure("weights: one per binding lane");
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  return {};
}

}  // namespace

Status LatticeEvaluateJob::validate() const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  for (std::size_t lane = 0; lane < binding->vertices.size(); ++lane) {
    const std::uint32_t vertex = binding->vertices[lane];
    if (vertex != LatticeBinding::no_vertex && vertex > binding->max_vertex)
      return Status::failure("binding vertex out of range");
    if (!std::isfinite(binding->u[lane]) || !std::isfinite(binding->v[lane]) || !std::isfinite(binding->w[lane]))
      return Status::failure("binding parameter is not finite");
  }
  if (binding->kind == LatticeKind::bspline) {
    const glm::ivec3 counts = binding->point_counts;
    const std::size_t nu = std::size_t(counts.x), nv = std::size_t(counts.y);
    for (const std::uint32_t first : binding->block_first_point) {
      // The cell's corner (i, j, k) must leave room for its 4×4×4 points.
      const std::size_t i = first % nu, j = first / nu % nv, k = first / (nu * nv);
      if (i + 4 > nu || j + 4 > nv || k + 4 > std::size_t(counts.z))
        return Status::failure("binding cell out of range");
    }
  }
  return {};
}

Status LatticeEvaluateJob::run() const noexcept { return run(0, count()); }

Status LatticeEvaluateJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  if (begin > end || end > binding->block_count()) return Status::failure("range outside the job");
  const bool normals = !normals_out.empty();
  const detail::KernelArgs args{binding,
                                control_points.data(),
                                positions.empty() ? nullptr : positions.data(),
                                normals ? normals_in.data() : nullptr,
                                normals ? normals_out.data() : nullptr,
                                weights.empty() ? nullptr : weights.data(),
                                begin,
                                end,
                                normals_jacobian_offset,
                                binding->normal_basis * normals_in_to_binding};
  if (begin < end) kernel_for(isa)(args);
  return {};
}

Status transform_points(std::span<const glm::vec3> in, const glm::mat4& matrix, std::span<glm::vec3> out) noexcept {
  if (in.size() != out.size()) return Status::failure("in and out differ in size");
  for (std::size_t i = 0; i < in.size(); ++i) out[i] = glm::vec3(matrix * glm::vec4(in[i], 1.0f));
  return {};
}

}  // namespace deform
