// SkinningJob: validation, instruction-set dispatch, the thread split, and the DQS palette.
#include "deform/runtime/skinning.hpp"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "deform/runtime/parallel.hpp"
#include "skinning_kernels.hpp"

namespace deform {
namespace {

constexpr std::size_t max_palette_size = 65536;

bool stride_ok(std::size_t stride) noexcept {
  return stride % 4 == 0 && stride >= 12 && stride <= max_skinning_stride;
}

// The span holds `count` vertices of 3 floats at `stride` bytes.
bool stream_ok(std::size_t size_bytes, std::size_t stride, std::size_t count) noexcept {
  if (!stride_ok(stride)) return false;
  if (count == 0) return true;
  if (count - 1 > (std::numeric_limits<std::size_t>::max() - 12) / stride) return false;
  return size_bytes >= (count - 1) * stride + 12;
}

std::size_t palette_size(const SkinningJob& job) noexcept {
  return job.method == SkinningMethod::lbs ? job.matrices.size() : job.dual_quats.size();
}

// Everything validate() checks that costs O(1).
bool layout_ok(const SkinningJob& job) noexcept {
  const std::size_t bones = palette_size(job);
  if (bones == 0 || bones > max_palette_size) return false;
  if (job.method != SkinningMethod::lbs && job.method != SkinningMethod::dqs) return false;
  if (job.method == SkinningMethod::dqs && !job.scales.empty() && job.scales.size() != bones) return false;
  if (!isa_available(job.isa)) return false;
  const std::size_t count = job.bone_indices.size();
  if (job.bone_weights.size() != count) return false;
  if (!stream_ok(job.in_positions.size_bytes(), job.in_positions_stride, count) ||
      !stream_ok(job.out_positions.size_bytes(), job.out_positions_stride, count))
    return false;
  if (job.in_normals.empty() != job.out_normals.empty()) return false;
  if (!job.in_normals.empty() && (!stream_ok(job.in_normals.size_bytes(), job.in_normals_stride, count) ||
                                  !stream_ok(job.out_normals.size_bytes(), job.out_normals_stride, count)))
    return false;
  if (count > 0 && (job.in_positions.data() == nullptr || job.out_positions.data() == nullptr)) return false;
  return true;
}

detail::SkinKernel select_kernel(const SkinningJob& job) noexcept {
  const bool lbs = job.method == SkinningMethod::lbs;
  const Isa isa = job.isa == Isa::automatic ? isa_best() : job.isa;
  // Scaled DQS palettes (a rare, non-rigid rig) take the portable kernel on every instruction set.
  if (!lbs && !job.scales.empty()) return detail::skin_dqs_portable;
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return lbs ? detail::skin_lbs_avx512 : detail::skin_dqs_avx512;
  if (isa == Isa::avx2) return lbs ? detail::skin_lbs_avx2 : detail::skin_dqs_avx2;
#endif
  (void)isa;
  return lbs ? detail::skin_lbs_portable : detail::skin_dqs_portable;
}

}  // namespace

bool SkinningJob::validate() const noexcept {
  if (!layout_ok(*this)) return false;
  const std::size_t bones = palette_size(*this);
  for (std::size_t i = 0; i < bone_indices.size(); ++i) {
    const glm::u16vec4 b = bone_indices[i];
    const glm::vec4 w = bone_weights[i];
    float sum = 0.0f;
    for (int k = 0; k < 4; ++k) {
      if (b[k] >= bones || !std::isfinite(w[k]) || w[k] < 0.0f) return false;
      sum += w[k];
    }
    if (!(sum > 0.0f) || !std::isfinite(sum)) return false;
  }
  return true;
}

bool SkinningJob::run() const noexcept { return run(0, bone_indices.size()); }

bool SkinningJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (!layout_ok(*this) || begin > end || end > bone_indices.size()) return false;
  if (begin < end) select_kernel(*this)(*this, begin, end);
  return true;
}

bool SkinningJob::run(ThreadPool& pool, std::size_t min_chunk) const {
  if (!layout_ok(*this)) return false;
  const std::size_t count = bone_indices.size();
  if (count == 0) return true;
  struct Split {
    const SkinningJob* job;
    detail::SkinKernel kernel;
  } split{this, select_kernel(*this)};
  const Split* context = &split;  // one pointer: the std::function below stores it without allocating
  // A vertex's result does not depend on where its range begins (partial blocks run the block code), so the result
  // is bit-identical to run(); chunks of whole 16-vertex blocks keep each thread on its own cache lines.
  constexpr std::size_t block = 16;
  const std::size_t blocks = (count + block - 1) / block;
  pool.parallel_for(blocks, std::max<std::size_t>(1, min_chunk / block),
                    [context, count](std::size_t begin, std::size_t end) {
                      context->kernel(*context->job, begin * block, std::min(end * block, count));
                    });
  return true;
}

namespace {

double determinant(const glm::dmat3& m) noexcept { return glm::determinant(m); }

}  // namespace

bool compute_dual_quat_palette(std::span<const glm::mat4> matrices, std::span<DualQuat> out,
                               std::span<glm::mat3> out_scales, bool& has_scale) noexcept {
  if (out.size() != matrices.size() || out_scales.size() != matrices.size()) return false;
  // Validate everything first so that a failure writes nothing.
  for (const glm::mat4& m : matrices) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(m[c][r])) return false;
    const double det = determinant(glm::dmat3(glm::mat3(m)));
    if (!(std::abs(det) > 1e-12)) return false;
  }
  bool any_scale = false;
  for (std::size_t i = 0; i < matrices.size(); ++i) {
    const glm::dmat3 a{glm::mat3(matrices[i])};
    // Polar decomposition by Higham's iteration Q ← ½ (Q + Q⁻ᵀ), which converges quadratically to the orthogonal
    // factor of a matrix with positive determinant; a mirroring matrix is negated first (det(-A) = -det(A) in 3D).
    const double sign = determinant(a) < 0.0 ? -1.0 : 1.0;
    glm::dmat3 q = a * sign;
    for (int iteration = 0; iteration < 64; ++iteration) {
      const glm::dmat3 next = 0.5 * (q + glm::transpose(glm::inverse(q)));
      double change = 0.0;
      for (int c = 0; c < 3; ++c) change = std::max(change, glm::length(next[c] - q[c]));
      q = next;
      if (change < 1e-12) break;
    }
    const glm::dmat3 s = glm::transpose(q) * a;  // A = Q · S (S carries the mirroring sign)
    const glm::quat real = glm::normalize(glm::quat_cast(glm::mat3(q)));
    const glm::vec3 t(matrices[i][3]);
    out[i].real = real;
    out[i].dual = 0.5f * (glm::quat(0.0f, t.x, t.y, t.z) * real);
    out_scales[i] = glm::mat3(s);
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (std::abs(s[c][r] - (c == r ? 1.0 : 0.0)) > 1e-5) any_scale = true;
  }
  has_scale = any_scale;
  return true;
}

}  // namespace deform
