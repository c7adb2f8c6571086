// LatticeEvaluateJob: validation and the choice of the kernel copy the job's Isa names.
#include <algorithm>

#include "deform/runtime/lattice.hpp"
#include "deform/runtime/parallel.hpp"
#include "lattice_kernel.hpp"

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
  return detail::evaluate_lattice_portable;
}

}  // namespace

bool LatticeEvaluateJob::validate() const noexcept {
  if (!binding || control_points.size() != binding->control_point_count()) return false;
  const std::size_t lanes = binding->block_count() * LatticeBinding::block_size;
  if (binding->vertices.size() != lanes || binding->u.size() != lanes || binding->v.size() != lanes ||
      binding->w.size() != lanes)
    return false;
  const std::size_t needed = binding->vertex_count == 0 ? 0 : std::size_t{binding->max_vertex} + 1;
  if (positions.size() < needed) return false;
  if (normals_in.empty() != normals_out.empty()) return false;
  if (!normals_out.empty() && (normals_in.size() < needed || normals_out.size() < needed)) return false;
  if (!isa_available(isa)) return false;
  return begin_block <= std::min(end_block, binding->block_count());
}

bool LatticeEvaluateJob::run() const noexcept {
  if (!validate()) return false;
  const bool normals = !normals_out.empty();
  const detail::KernelArgs args{binding,
                                control_points.data(),
                                positions.data(),
                                normals ? normals_in.data() : nullptr,
                                normals ? normals_out.data() : nullptr,
                                begin_block,
                                std::min(end_block, binding->block_count())};
  if (args.begin_block < args.end_block) kernel_for(isa)(args);
  return true;
}

bool run_parallel(const LatticeEvaluateJob& job, ThreadPool& pool) {
  if (!job.validate()) return false;
  const std::size_t begin = job.begin_block, end = std::min(job.end_block, job.binding->block_count());
  // 64 blocks = 1,024 vertices: below that a thread wake-up costs more than it saves.
  pool.parallel_for(end - begin, 64, [&](std::size_t b, std::size_t e) {
    LatticeEvaluateJob part = job;
    part.begin_block = begin + b;
    part.end_block = begin + e;
    part.run();
  });
  return true;
}

bool transform_points(std::span<const glm::vec3> in, const glm::mat4& matrix, std::span<glm::vec3> out) {
  if (in.size() != out.size()) return false;
  for (std::size_t i = 0; i < in.size(); ++i) out[i] = glm::vec3(matrix * glm::vec4(in[i], 1.0f));
  return true;
}

}  // namespace deform
