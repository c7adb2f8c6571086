// Skinning kernels for aarch64 Advanced SIMD (NEON): 4 vertices per step, the block loops of skinning_simd.hpp over
// 128-bit vectors. Built only for aarch64, where every CPU has NEON and FMA (no flags, no run-time check). A blended
// mat4 is four registers per vertex, transposed to SoA by one 4×4 transpose per column; packed vec3 streams (stride
// 12) move with the structure loads and stores (LD3/ST3), which de-interleave x, y, z in one instruction.
#include <arm_neon.h>

#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

struct F4 {
  float32x4_t v;
};
inline F4 operator+(F4 a, F4 b) { return {vaddq_f32(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {vsubq_f32(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {vmulq_f32(a.v, b.v)}; }
inline F4 fma(F4 a, F4 b, F4 c) { return {vfmaq_f32(c.v, a.v, b.v)}; }
// a·b − c with one rounding: −(c − a·b), the negation exact.
inline F4 fms(F4 a, F4 b, F4 c) { return {vnegq_f32(vfmsq_f32(c.v, a.v, b.v))}; }
inline F4 max(F4 a, F4 b) { return {vmaxq_f32(a.v, b.v)}; }
// aarch64 has a true square root and division: correctly rounded, so no estimate to refine (the 8-bit FRSQRTE would
// need two Newton steps to reach the AVX copies' ~3e-7).
inline F4 rsqrt(F4 x) { return {vdivq_f32(vdupq_n_f32(1.0f), vsqrtq_f32(x.v))}; }
inline F4 rcp(F4 x) { return {vdivq_f32(vdupq_n_f32(1.0f), x.v)}; }
inline F4 flip_sign(F4 w, F4 d) {
  const uint32x4_t sign = vandq_u32(vreinterpretq_u32_f32(d.v), vdupq_n_u32(0x80000000u));
  return {vreinterpretq_f32_u32(veorq_u32(vreinterpretq_u32_f32(w.v), sign))};
}

// 4×4 transpose: out[e] lane l = element e of r[l].
inline void transpose4(const float32x4_t r[4], float32x4_t out[4]) {
  const float32x4_t t0 = vtrn1q_f32(r[0], r[1]), t1 = vtrn2q_f32(r[0], r[1]);  // a0 b0 a2 b2 | a1 b1 a3 b3
  const float32x4_t t2 = vtrn1q_f32(r[2], r[3]), t3 = vtrn2q_f32(r[2], r[3]);  // c0 d0 c2 d2 | c1 d1 c3 d3
  const auto lo = [](float32x4_t a, float32x4_t b) {
    return vreinterpretq_f32_f64(vtrn1q_f64(vreinterpretq_f64_f32(a), vreinterpretq_f64_f32(b)));
  };
  const auto hi = [](float32x4_t a, float32x4_t b) {
    return vreinterpretq_f32_f64(vtrn2q_f64(vreinterpretq_f64_f32(a), vreinterpretq_f64_f32(b)));
  };
  out[0] = lo(t0, t2), out[1] = lo(t1, t3), out[2] = hi(t0, t2), out[3] = hi(t1, t3);
}

struct Neon {
  using V = F4;
  static constexpr std::size_t width = 4;
  static constexpr bool can_stream = false;  // aarch64 has no non-temporal store that bypasses the caches as x86 does
  static constexpr bool has_component_tables = false;
  static void fence() {}
  explicit Neon(const SkinningJob&) {}

  static F4 splat(float x) { return {vdupq_n_f32(x)}; }

  static void blend_matrices(const SkinningJob& job, std::size_t i, const V*, V a[12]) {
    const float* palette = &job.matrices[0][0][0];
    float32x4_t columns[4][4];  // [column][vertex]
    for (int l = 0; l < 4; ++l) {
      const glm::u16vec4 b = job.bone_indices[i + std::size_t(l)];
      const glm::vec4 w = job.bone_weights[i + std::size_t(l)];
      float32x4_t sum[4] = {vdupq_n_f32(0.0f), vdupq_n_f32(0.0f), vdupq_n_f32(0.0f), vdupq_n_f32(0.0f)};
      for (int k = 0; k < 4; ++k) {
        const float* m = palette + 16 * std::size_t{b[k]};
        for (int c = 0; c < 4; ++c) sum[c] = vfmaq_n_f32(sum[c], vld1q_f32(m + 4 * c), w[k]);
      }
      for (int c = 0; c < 4; ++c) columns[c][l] = sum[c];
    }
    for (int c = 0; c < 4; ++c) {
      float32x4_t t[4];
      transpose4(columns[c], t);
      for (int r = 0; r < 3; ++r) a[3 * c + r].v = t[r];
    }
  }

  static void load_weights(const SkinningJob& job, std::size_t i, F4 w[4]) {
    const float32x4x4_t r = vld4q_f32(&job.bone_weights[i].x);
    for (int e = 0; e < 4; ++e) w[e].v = r.val[e];
  }

  static void load_dual_quat(const SkinningJob& job, std::size_t i, int k, F4 q[8]) {
    const float* palette = &job.dual_quats[0].real.x;
    float32x4_t real[4], dual[4], t[4];
    for (int l = 0; l < 4; ++l) {
      const float* d = palette + 8 * std::size_t{job.bone_indices[i + std::size_t(l)][k]};
      real[l] = vld1q_f32(d), dual[l] = vld1q_f32(d + 4);
    }
    transpose4(real, t);
    for (int c = 0; c < 4; ++c) q[c].v = t[c];
    transpose4(dual, t);
    for (int c = 0; c < 4; ++c) q[4 + c].v = t[c];
  }

  static void load3(const float* base, std::size_t stride, std::size_t i, F4 out[3]) {
    const unsigned char* p = reinterpret_cast<const unsigned char*>(base) + i * stride;
    if (stride == 12) {
      const float32x4x3_t xyz = vld3q_f32(reinterpret_cast<const float*>(p));
      for (int c = 0; c < 3; ++c) out[c].v = xyz.val[c];
      return;
    }
    float lanes[3][4];
    for (std::size_t l = 0; l < 4; ++l) {
      const float* v = reinterpret_cast<const float*>(p + l * stride);
      for (int c = 0; c < 3; ++c) lanes[c][l] = v[c];
    }
    for (int c = 0; c < 3; ++c) out[c].v = vld1q_f32(lanes[c]);
  }

  static void store3(float* base, std::size_t stride, std::size_t i, const F4 in[3], bool /*stream*/) {
    unsigned char* p = reinterpret_cast<unsigned char*>(base) + i * stride;
    if (stride == 12) {
      vst3q_f32(reinterpret_cast<float*>(p), float32x4x3_t{{in[0].v, in[1].v, in[2].v}});
      return;
    }
    float lanes[3][4];
    for (int c = 0; c < 3; ++c) vst1q_f32(lanes[c], in[c].v);
    for (std::size_t l = 0; l < 4; ++l) {
      float* v = reinterpret_cast<float*>(p + l * stride);
      for (int c = 0; c < 3; ++c) v[c] = lanes[c][l];
    }
  }
};

}  // namespace
}  // namespace deform::detail

#include "skinning_simd.hpp"

namespace deform::detail {

void skin_lbs_neon(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_lbs_blocks<Neon>(job, begin, end);
}
void skin_dqs_neon(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_dqs_blocks<Neon>(job, begin, end);
}

}  // namespace deform::detail
