// Portable skinning kernels: one vertex at a time, plain C++. The fallback on CPUs without AVX2 and the path
// for scaled DQS palettes. The SIMD kernels compute exactly this, to float rounding.
#include <algorithm>
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

// The general kernel works on `lanes` listed vertices side by side: one vertex alone is a serial chain of blend,
// cofactor, square root and division (about 30 ns), which independent lanes overlap. Every lane runs the same
// operations on its own data (no fused multiply-add in this file, no reduction across lanes), so a vertex's result
// does not depend on the group it falls in; a short group repeats its last vertex in the spare lanes and does not
// store them.
namespace {
constexpr std::size_t lanes = 8;
}  // namespace

void skin_extra_vertices(const SkinningJob& job, std::size_t j_begin, std::size_t j_end) noexcept {
  const bool normals = !job.in_normals.empty();
  const bool lbs = job.method == SkinningMethod::lbs;
  const bool scaled = !lbs && !job.scales.empty();
  for (std::size_t g = j_begin; g < j_end; g += lanes) {
    const std::size_t used = std::min(lanes, j_end - g);
    std::size_t vertex[lanes], first[lanes], count[lanes];
    std::size_t most = 0;
    for (std::size_t l = 0; l < lanes; ++l) {
      const std::size_t j = g + std::min(l, used - 1);
      vertex[l] = job.extra_vertices[j];
      first[l] = job.extra_offsets[j];
      count[l] = 4 + (job.extra_offsets[j + 1] - first[l]);
      most = std::max(most, count[l]);
    }
    // Influence k of lane l: the four slots, then the extras; (bone 0, weight 0) past the lane's last.
    auto influence = [&](std::size_t l, std::size_t k, std::size_t& bone, float& w) {
      if (k < 4) {
        bone = job.bone_indices[vertex[l]][int(k)], w = job.bone_weights[vertex[l]][int(k)];
      } else if (k < count[l]) {
        bone = job.extra_bones[first[l] + k - 4], w = job.extra_weights[first[l] + k - 4];
      } else {
        bone = 0, w = 0.0f;
      }
    };
    float sum[lanes] = {};
    glm::vec4 c0[lanes], c1[lanes], c2[lanes], c3[lanes];  // LBS: blended columns; DQS: real, dual
    glm::mat3 scale[lanes];
    for (std::size_t l = 0; l < lanes; ++l) {
      c0[l] = c1[l] = c2[l] = c3[l] = glm::vec4(0.0f);
      if (scaled) scale[l] = glm::mat3(0.0f);
    }
    if (lbs) {
      for (std::size_t k = 0; k < most; ++k)
        for (std::size_t l = 0; l < lanes; ++l) {
          std::size_t bone;
          float w;
          influence(l, k, bone, w);
          const glm::mat4& m = job.matrices[bone];
          c0[l] += w * m[0], c1[l] += w * m[1], c2[l] += w * m[2], c3[l] += w * m[3];
          sum[l] += w;
        }
    } else {
      glm::vec4 pivot[lanes];
      for (std::size_t l = 0; l < lanes; ++l) pivot[l] = as_vec4(job.dual_quats[job.bone_indices[vertex[l]][0]].real);
      for (std::size_t k = 0; k < most; ++k)
        for (std::size_t l = 0; l < lanes; ++l) {
          std::size_t bone;
          float w;
          influence(l, k, bone, w);
          const DualQuat& q = job.dual_quats[bone];
          // Antipodality: blend each in the hemisphere of the first (strongest) influence.
          const float signed_weight = glm::dot(as_vec4(q.real), pivot[l]) < 0.0f ? -w : w;
          c0[l] += signed_weight * as_vec4(q.real);
          c1[l] += signed_weight * as_vec4(q.dual);
          if (scaled) scale[l] += w * job.scales[bone];
          sum[l] += w;
        }
    }
    for (std::size_t l = 0; l < used; ++l) {
      const std::size_t i = vertex[l];
      glm::vec3 p = load3(stream_at(job.in_positions, job.in_positions_stride, i));
      glm::vec3 n(0.0f);
      if (normals) n = load3(stream_at(job.in_normals, job.in_normals_stride, i));
      if (lbs) {
        const glm::vec3 a0(c0[l]), a1(c1[l]), a2(c2[l]), t(c3[l]);
        store3(stream_at(job.out_positions, job.out_positions_stride, i),
               (a0 * p.x + a1 * p.y + a2 * p.z + t) * (1.0f / sum[l]));
        if (normals)
          store3(stream_at(job.out_normals, job.out_normals_stride, i),
                 normalize_or_zero(cofactor_times(a0, a1, a2, n)));
        continue;
      }
      const float inverse_length = 1.0f / std::sqrt(glm::dot(c0[l], c0[l]));
      const glm::vec4 real = c0[l] * inverse_length, dual = c1[l] * inverse_length;
      const glm::vec3 r(real.x, real.y, real.z), d(dual.x, dual.y, dual.z);
      const glm::vec3 translation = 2.0f * (real.w * d - dual.w * r + glm::cross(r, d));
      if (scaled) {
        const glm::mat3 s = scale[l] * (1.0f / sum[l]);
        p = s * p;
        n = cofactor_times(s[0], s[1], s[2], n);
      }
      store3(stream_at(job.out_positions, job.out_positions_stride, i), rotate(real, p) + translation);
      if (normals) store3(stream_at(job.out_normals, job.out_normals_stride, i), normalize_or_zero(rotate(real, n)));
    }
  }
}

}  // namespace deform::detail
