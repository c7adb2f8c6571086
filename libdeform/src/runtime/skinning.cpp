// SkinningJob: validation, instruction-set dispatch, and the DQS palette.
#include "deform/runtime/skinning.hpp"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "simd/skinning_kernels.hpp"

namespace deform {
namespace {

constexpr std::size_t max_palette_size = 65536;

// Ok when the span holds `count` vertices of 3 floats at `stride` bytes (a multiple of 4 in [12, max]).
Status stream_ok(std::size_t size_bytes, std::size_t stride, std::size_t count, const char* bad_stride,
                 const char* too_short) noexcept {
  if (stride % 4 != 0 || stride < 12 || stride > max_skinning_stride) return Status::failure(bad_stride);
  if (count == 0) return {};
  if (count - 1 > (std::numeric_limits<std::size_t>::max() - 12) / stride || size_bytes < (count - 1) * stride + 12)
    return Status::failure(too_short);
  return {};
}

std::size_t palette_size(const SkinningJob& job) noexcept {
  return job.method == SkinningMethod::lbs ? job.matrices.size() : job.dual_quats.size();
}

// Everything validate() checks that costs O(1).
Status layout_ok(const SkinningJob& job) noexcept {
  if (job.method != SkinningMethod::lbs && job.method != SkinningMethod::dqs)
    return Status::failure("unknown skinning method");
  const std::size_t bones = palette_size(job);
  if (bones == 0) return Status::failure("palette is empty");
  if (bones > max_palette_size) return Status::failure("palette has more than 65536 bones");
  if (job.method == SkinningMethod::dqs && !job.scales.empty() && job.scales.size() != bones)
    return Status::failure("scales and dual quaternions differ in count");
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  const std::size_t count = job.bone_indices.size();
  if (job.bone_weights.size() != count) return Status::failure("bone weights and bone indices differ in count");
  if (job.extra_vertices.empty()) {
    if (!job.extra_bones.empty() || !job.extra_weights.empty() || job.extra_offsets.size() > 1 ||
        (job.extra_offsets.size() == 1 && job.extra_offsets[0] != 0))
      return Status::failure("extra influences are inconsistent");
  } else if (job.extra_offsets.size() != job.extra_vertices.size() + 1 ||
             job.extra_bones.size() != job.extra_weights.size() || job.extra_offsets.back() != job.extra_bones.size() ||
             job.extra_offsets.front() != 0 || job.extra_vertices.back() >= count) {
    return Status::failure("extra influences are inconsistent");
  }
  if (Status s = stream_ok(job.in_positions.size_bytes(), job.in_positions_stride, count, "in_positions stride invalid",
                           "in_positions too short");
      !s)
    return s;
  if (Status s = stream_ok(job.out_positions.size_bytes(), job.out_positions_stride, count,
                           "out_positions stride invalid", "out_positions too short");
      !s)
    return s;
  if (job.in_normals.empty() != job.out_normals.empty())
    return Status::failure("in_normals and out_normals: both or neither");
  if (job.in_normals.empty()) return {};
  if (Status s = stream_ok(job.in_normals.size_bytes(), job.in_normals_stride, count, "in_normals stride invalid",
                           "in_normals too short");
      !s)
    return s;
  return stream_ok(job.out_normals.size_bytes(), job.out_normals_stride, count, "out_normals stride invalid",
                   "out_normals too short");
}

template <class T, int n>
bool all_finite(const T& v) noexcept {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
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
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return lbs ? detail::skin_lbs_neon : detail::skin_dqs_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return lbs ? detail::skin_lbs_simd128 : detail::skin_dqs_simd128;
#endif
  (void)isa;
  return lbs ? detail::skin_lbs_portable : detail::skin_dqs_portable;
}

}  // namespace

Status SkinningJob::validate() const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  if (method == SkinningMethod::lbs) {
    for (const glm::mat4& m : matrices)
      for (int c = 0; c < 4; ++c)
        if (!all_finite<glm::vec4, 4>(m[c])) return Status::failure("palette matrix is not finite");
  } else {
    for (const DualQuat& q : dual_quats)
      if (!all_finite<glm::quat, 4>(q.real) || !all_finite<glm::quat, 4>(q.dual))
        return Status::failure("dual quaternion is not finite");
    for (const glm::mat3& m : scales)
      for (int c = 0; c < 3; ++c)
        if (!all_finite<glm::vec3, 3>(m[c])) return Status::failure("scale matrix is not finite");
  }
  const std::size_t bones = palette_size(*this);
  std::size_t extra = 0;  // the next entry of extra_vertices
  for (std::size_t i = 0; i < bone_indices.size(); ++i) {
    const glm::u16vec4 b = bone_indices[i];
    const glm::vec4 w = bone_weights[i];
    float sum = 0.0f;
    for (int k = 0; k < 4; ++k) {
      if (b[k] >= bones) return Status::failure("bone index out of range");
      if (!std::isfinite(w[k])) return Status::failure("weight is not finite");
      if (w[k] < 0.0f) return Status::failure("weight is negative");
      // A denormal weight alone sums to a denormal whose reciprocal overflows (1e-45 gave NaN positions).
      if (w[k] > 0.0f && w[k] < std::numeric_limits<float>::min()) return Status::failure("weight is denormal");
      sum += w[k];
    }
    if (extra < extra_vertices.size() && extra_vertices[extra] == i) {
      if (extra > 0 && !(extra_vertices[extra] > extra_vertices[extra - 1]))
        return Status::failure("extra influences are inconsistent");
      const std::uint32_t first = extra_offsets[extra], last = extra_offsets[extra + 1];
      if (last < first || last > extra_bones.size()) return Status::failure("extra influences are inconsistent");
      for (std::uint32_t e = first; e < last; ++e) {
        const float we = extra_weights[e];
        if (extra_bones[e] >= bones) return Status::failure("bone index out of range");
        if (!std::isfinite(we)) return Status::failure("weight is not finite");
        if (we < 0.0f) return Status::failure("weight is negative");
        if (we > 0.0f && we < std::numeric_limits<float>::min()) return Status::failure("weight is denormal");
        sum += we;
      }
      ++extra;
    }
    if (!(sum >= min_skin_weight_sum && sum <= max_skin_weight_sum)) return Status::failure("weight sum out of range");
  }
  // Every listed vertex was met in order: none left over (unsorted or repeated entries are).
  if (extra != extra_vertices.size()) return Status::failure("extra influences are inconsistent");
  return {};
}

Status SkinningJob::run() const noexcept { return run(0, bone_indices.size()); }

Status SkinningJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  if (begin > end || end > bone_indices.size()) return Status::failure("range outside the job");
  // A vertex's result does not depend on where its range begins: partial blocks run the block code.
  if (begin >= end) return {};
  const detail::SkinKernel kernel = select_kernel(*this);
  if (extra_vertices.empty()) {
    kernel(*this, begin, end);
    return {};
  }
  const auto j = static_cast<std::size_t>(std::lower_bound(extra_vertices.begin(), extra_vertices.end(), begin) -
                                          extra_vertices.begin());
  const auto j_end = static_cast<std::size_t>(
      std::lower_bound(extra_vertices.begin() + std::ptrdiff_t(j), extra_vertices.end(), end) - extra_vertices.begin());
  const bool in_place =
      out_positions.data() == in_positions.data() || (!in_normals.empty() && out_normals.data() == in_normals.data());
  if (!in_place) {
    // Outputs apart from inputs: the four-influence kernel over the whole range (whole blocks, the fast way), then
    // the general kernel over the listed vertices, which reads their untouched inputs and overwrites their results.
    // Splitting the range instead costs a partial block per run (3x the whole on a mesh with a tenth of its
    // vertices listed: docs/performance.md).
    kernel(*this, begin, end);
  } else {
    // In place, a vertex must be read before it is written and written once: the four-influence kernel takes the
    // runs between listed vertices only.
    std::size_t at = begin;
    for (std::size_t k = j; k < j_end; ++k) {
      if (extra_vertices[k] > at) kernel(*this, at, extra_vertices[k]);
      at = std::size_t(extra_vertices[k]) + 1;
    }
    if (at < end) kernel(*this, at, end);
  }
  detail::skin_extra_vertices(*this, j, j_end);
  return {};
}

namespace {

double determinant(const glm::dmat3& m) noexcept { return glm::determinant(m); }

}  // namespace

Status compute_dual_quat_palette(std::span<const glm::mat4> matrices, std::span<DualQuat> out,
                                 std::span<glm::mat3> out_scales, bool& has_scale) noexcept {
  if (out.size() != matrices.size() || out_scales.size() != matrices.size())
    return Status::failure("palette sizes differ");
  // Validate everything first so that a failure writes nothing.
  for (const glm::mat4& m : matrices) {
    for (int c = 0; c < 4; ++c)
      if (!all_finite<glm::vec4, 4>(m[c])) return Status::failure("palette matrix is not finite");
    const double det = determinant(glm::dmat3(glm::mat3(m)));
    if (!(std::abs(det) > 1e-12)) return Status::failure("palette matrix is singular");
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
  return {};
}

}  // namespace deform
