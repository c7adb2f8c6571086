// Portable skinning kernels: one vertex at a time, plain C++. The fallback on CPUs without AVX2 and the path
// for scaled DQS palettes. The SIMD kernels compute exactly this, to float rounding.
#include <cmath>

#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

glm::vec3 load3(const float* p) noexcept { return {p[0], p[1], p[2]}; }
void store3(float* p, glm::vec3 v) noexcept { p[0] = v.x, p[1] = v.y, p[2] = v.z; }

// n / |n|, or 0 for a zero normal.
glm::vec3 normalize_or_zero(glm::vec3 n) noexcept {
  const float length_squared = glm::dot(n, n);
  return length_squared > 0.0f ? n / std::sqrt(length_squared) : n;
}

// Cofactor matrix of a 3×3 given by its columns a0 a1 a2 (columns a1×a2, a2×a0, a0×a1): det · A⁻ᵀ, the normal map.
glm::vec3 cofactor_times(glm::vec3 a0, glm::vec3 a1, glm::vec3 a2, glm::vec3 n) noexcept {
  return glm::cross(a1, a2) * n.x + glm::cross(a2, a0) * n.y + glm::cross(a0, a1) * n.z;
}

glm::vec3 rotate(glm::vec4 q, glm::vec3 v) noexcept {
  const glm::vec3 r(q.x, q.y, q.z);
  return v + 2.0f * glm::cross(r, glm::cross(r, v) + q.w * v);
}

glm::vec4 as_vec4(glm::quat q) noexcept { return {q.x, q.y, q.z, q.w}; }

}  // namespace

void skin_lbs_portable(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  const bool normals = !job.in_normals.empty();
  for (std::size_t i = begin; i < end; ++i) {
    const glm::u16vec4 b = job.bone_indices[i];
    const glm::vec4 w = job.bone_weights[i];
    glm::vec3 a0(0.0f), a1(0.0f), a2(0.0f), t(0.0f);
    for (int k = 0; k < 4; ++k) {
      const glm::mat4& m = job.matrices[b[k]];
      a0 += w[k] * glm::vec3(m[0]), a1 += w[k] * glm::vec3(m[1]), a2 += w[k] * glm::vec3(m[2]);
      t += w[k] * glm::vec3(m[3]);
    }
    const float inverse_sum = 1.0f / (w.x + w.y + w.z + w.w);
    const glm::vec3 p = load3(stream_at(job.in_positions, job.in_positions_stride, i));
    glm::vec3 n(0.0f);
    if (normals) n = load3(stream_at(job.in_normals, job.in_normals_stride, i));
    store3(stream_at(job.out_positions, job.out_positions_stride, i),
           (a0 * p.x + a1 * p.y + a2 * p.z + t) * inverse_sum);
    if (normals)
      store3(stream_at(job.out_normals, job.out_normals_stride, i), normalize_or_zero(cofactor_times(a0, a1, a2, n)));
  }
}

void skin_dqs_portable(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  const bool normals = !job.in_normals.empty();
  const bool scaled = !job.scales.empty();
  for (std::size_t i = begin; i < end; ++i) {
    const glm::u16vec4 b = job.bone_indices[i];
    const glm::vec4 w = job.bone_weights[i];
    const glm::vec4 pivot = as_vec4(job.dual_quats[b[0]].real);
    glm::vec4 real(0.0f), dual(0.0f);
    glm::mat3 scale(0.0f);
    for (int k = 0; k < 4; ++k) {
      const DualQuat& q = job.dual_quats[b[k]];
      // Antipodality: q and -q are the same transform; blend each in the hemisphere of the first influence.
      const float signed_weight = glm::dot(as_vec4(q.real), pivot) < 0.0f ? -w[k] : w[k];
      real += signed_weight * as_vec4(q.real);
      dual += signed_weight * as_vec4(q.dual);
      if (scaled) scale += w[k] * job.scales[b[k]];
    }
    const float inverse_length = 1.0f / std::sqrt(glm::dot(real, real));
    real *= inverse_length, dual *= inverse_length;
    const glm::vec3 r(real.x, real.y, real.z), d(dual.x, dual.y, dual.z);
    const glm::vec3 translation = 2.0f * (real.w * d - dual.w * r + glm::cross(r, d));

    glm::vec3 p = load3(stream_at(job.in_positions, job.in_positions_stride, i));
    glm::vec3 n(0.0f);
    if (normals) n = load3(stream_at(job.in_normals, job.in_normals_stride, i));
    if (scaled) {
      scale *= 1.0f / (w.x + w.y + w.z + w.w);
      p = scale * p;
      n = cofactor_times(scale[0], scale[1], scale[2], n);
    }
    store3(stream_at(job.out_positions, job.out_positions_stride, i), rotate(real, p) + translation);
    if (normals) store3(stream_at(job.out_normals, job.out_normals_stride, i), normalize_or_zero(rotate(real, n)));
  }
}

void skin_extra_vertex(const SkinningJob& job, std::size_t j) noexcept {
  const std::size_t i = job.extra_vertices[j];
  const std::size_t first = job.extra_offsets[j], last = job.extra_offsets[j + 1];
  const glm::u16vec4 b4 = job.bone_indices[i];
  const glm::vec4 w4 = job.bone_weights[i];
  const bool normals = !job.in_normals.empty();
  glm::vec3 p = load3(stream_at(job.in_positions, job.in_positions_stride, i));
  glm::vec3 nrm(0.0f);
  if (normals) nrm = load3(stream_at(job.in_normals, job.in_normals_stride, i));
  // Influence k: the four slots, then the extras. `visit(bone, weight)` for each with a positive weight; the sum is
  // over all of them, as the four-influence kernels divide by theirs.
  float sum = 0.0f;
  auto each = [&](auto&& visit) {
    for (int k = 0; k < 4; ++k)
      if (w4[k] > 0.0f) visit(std::size_t(b4[k]), w4[k]);
    for (std::size_t e = first; e < last; ++e)
      if (job.extra_weights[e] > 0.0f) visit(std::size_t(job.extra_bones[e]), job.extra_weights[e]);
  };
  if (job.method == SkinningMethod::lbs) {
    // Whole vec4 columns, so the compiler blends each with one vector multiply-add.
    glm::vec4 c0(0.0f), c1(0.0f), c2(0.0f), c3(0.0f);
    each([&](std::size_t bone, float w) {
      const glm::mat4& m = job.matrices[bone];
      c0 += w * m[0], c1 += w * m[1], c2 += w * m[2], c3 += w * m[3];
      sum += w;
    });
    const glm::vec3 a0(c0), a1(c1), a2(c2), t(c3);
    store3(stream_at(job.out_positions, job.out_positions_stride, i), (a0 * p.x + a1 * p.y + a2 * p.z + t) * (1.0f / sum));
    if (normals)
      store3(stream_at(job.out_normals, job.out_normals_stride, i), normalize_or_zero(cofactor_times(a0, a1, a2, nrm)));
    return;
  }
  const bool scaled = !job.scales.empty();
  const glm::vec4 pivot = as_vec4(job.dual_quats[b4[0]].real);
  glm::vec4 real(0.0f), dual(0.0f);
  glm::mat3 scale(0.0f);
  each([&](std::size_t bone, float w) {
    const DualQuat& q = job.dual_quats[bone];
    const float signed_weight = glm::dot(as_vec4(q.real), pivot) < 0.0f ? -w : w;
    real += signed_weight * as_vec4(q.real);
    dual += signed_weight * as_vec4(q.dual);
    if (scaled) scale += w * job.scales[bone];
    sum += w;
  });
  const float inverse_length = 1.0f / std::sqrt(glm::dot(real, real));
  real *= inverse_length, dual *= inverse_length;
  const glm::vec3 r(real.x, real.y, real.z), d(dual.x, dual.y, dual.z);
  const glm::vec3 translation = 2.0f * (real.w * d - dual.w * r + glm::cross(r, d));
  if (scaled) {
    scale *= 1.0f / sum;
    p = scale * p;
    nrm = cofactor_times(scale[0], scale[1], scale[2], nrm);
  }
  store3(stream_at(job.out_positions, job.out_positions_stride, i), rotate(real, p) + translation);
  if (normals) store3(stream_at(job.out_normals, job.out_normals_stride, i), normalize_or_zero(rotate(real, nrm)));
}

}  // namespace deform::detail
