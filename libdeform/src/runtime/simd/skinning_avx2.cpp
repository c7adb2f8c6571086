// Skinning kernels for AVX2 + FMA: 8 vertices per step. Compiled with -mavx2 -mfma; only reached when the CPU
// reports both (skinning.cpp). Same scheme as skinning_avx512.cpp at half the width: a blended mat4 is two registers
// (columns 0-1, columns 2-3), transposed to SoA by two 8×8 transposes; dual quaternions by one 8×8 per influence.
// Packed vec3 streams (stride 12) move with full-width loads and stores and in-lane shuffles; other strides gather.
#include <immintrin.h>

#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

struct F8 {
  __m256 v;
};
inline F8 operator+(F8 a, F8 b) { return {_mm256_add_ps(a.v, b.v)}; }
inline F8 operator-(F8 a, F8 b) { return {_mm256_sub_ps(a.v, b.v)}; }
inline F8 operator*(F8 a, F8 b) { return {_mm256_mul_ps(a.v, b.v)}; }
inline F8 fma(F8 a, F8 b, F8 c) { return {_mm256_fmadd_ps(a.v, b.v, c.v)}; }
inline F8 fms(F8 a, F8 b, F8 c) { return {_mm256_fmsub_ps(a.v, b.v, c.v)}; }
inline F8 max(F8 a, F8 b) { return {_mm256_max_ps(a.v, b.v)}; }
// A 12-bit estimate refined by one Newton step (relative error ~3e-7).
inline F8 rsqrt(F8 x) {
  const __m256 y = _mm256_rsqrt_ps(x.v);
  // y (1.5 - (0.5 x) y²), the subtraction fused (FMA is enabled in this file).
  const __m256 correction =
      _mm256_fnmadd_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), x.v), _mm256_mul_ps(y, y), _mm256_set1_ps(1.5f));
  return {_mm256_mul_ps(y, correction)};
}
// A true division: the 12-bit estimate refined once is 1 ulp off at x = 1 (a normalised vertex), and the division
// costs nothing measurable next to the vertex's memory traffic.
inline F8 rcp(F8 x) { return {_mm256_div_ps(_mm256_set1_ps(1.0f), x.v)}; }
inline F8 flip_sign(F8 w, F8 d) { return {_mm256_xor_ps(w.v, _mm256_and_ps(d.v, _mm256_set1_ps(-0.0f)))}; }

// In-lane 4×4 transpose of rows r0..r3 (per 128-bit half): out[e] half c lane j = element e of r_j half c.
inline void transpose4_in_lanes(__m256 r0, __m256 r1, __m256 r2, __m256 r3, __m256 out[4]) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  out[0] = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)),
  out[1] = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  out[2] = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)),
  out[3] = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

// 8×8 transpose: out[e] lane l = element e of r[l]. Only the elements with want[e] are produced.
inline void transpose8(const __m256 r[8], __m256 out[8], unsigned want = 0xff) {
  __m256 u[8];
  transpose4_in_lanes(r[0], r[1], r[2], r[3], u);
  transpose4_in_lanes(r[4], r[5], r[6], r[7], u + 4);
  // u[e] halves: element e of rows 0-3, element 4+e of rows 0-3; u[4+e] the same for rows 4-7.
  for (int e = 0; e < 4; ++e) {
    if (want & (1u << e)) out[e] = _mm256_permute2f128_ps(u[e], u[4 + e], 0x20);
    if (want & (1u << (4 + e))) out[4 + e] = _mm256_permute2f128_ps(u[e], u[4 + e], 0x31);
  }
}

struct Avx2 {
  using V = F8;
  static constexpr std::size_t width = 8;
  static constexpr bool can_stream = false;  // streaming stores are left to the AVX-512 kernels
  static constexpr bool has_component_tables = false;
  static void fence() {}
  explicit Avx2(const SkinningJob&) {}

  static F8 splat(float x) { return {_mm256_set1_ps(x)}; }

  static void blend_matrices(const SkinningJob& job, std::size_t i, const V*, V a[12]) {
    const float* palette = &job.matrices[0][0][0];
    __m256 columns01[8], columns23[8];
    for (int l = 0; l < 8; ++l) {
      const glm::u16vec4 b = job.bone_indices[i + l];
      const glm::vec4 w = job.bone_weights[i + l];
      __m256 lo = _mm256_setzero_ps(), hi = _mm256_setzero_ps();
      for (int k = 0; k < 4; ++k) {
        const float* m = palette + 16 * std::size_t{b[k]};
        const __m256 weight = _mm256_set1_ps(w[k]);
        lo = _mm256_fmadd_ps(weight, _mm256_loadu_ps(m), lo);
        hi = _mm256_fmadd_ps(weight, _mm256_loadu_ps(m + 8), hi);
      }
      columns01[l] = lo, columns23[l] = hi;
    }
    __m256 t[8];
    transpose8(columns01, t, 0x77);  // rows 0..2 of columns 0 and 1
    a[0].v = t[0], a[1].v = t[1], a[2].v = t[2], a[3].v = t[4], a[4].v = t[5], a[5].v = t[6];
    transpose8(columns23, t, 0x77);  // rows 0..2 of column 2 and the translation
    a[6].v = t[0], a[7].v = t[1], a[8].v = t[2], a[9].v = t[4], a[10].v = t[5], a[11].v = t[6];
  }

  static void load_weights(const SkinningJob& job, std::size_t i, F8 w[4]) {
    const float* p = &job.bone_weights[i].x;
    __m256 r[4];
    transpose4_in_lanes(_mm256_loadu_ps(p), _mm256_loadu_ps(p + 8), _mm256_loadu_ps(p + 16), _mm256_loadu_ps(p + 24),
                        r);
    // r[e] lane 4c + j holds weight e of vertex 2j + c.
    const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    for (int e = 0; e < 4; ++e) w[e].v = _mm256_permutevar8x32_ps(r[e], order);
  }

  static void load_dual_quat(const SkinningJob& job, std::size_t i, int k, F8 q[8]) {
    const float* palette = &job.dual_quats[0].real.x;
    __m256 r[8], t[8];
    for (int l = 0; l < 8; ++l) r[l] = _mm256_loadu_ps(palette + 8 * std::size_t{job.bone_indices[i + l][k]});
    transpose8(r, t);
    for (int c = 0; c < 8; ++c) q[c].v = t[c];
  }

  static void load3(const float* base, std::size_t stride, std::size_t i, F8 out[3]) {
    const float* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(base) + i * stride);
    if (stride == 12) {
      // Packed vec3: six 4-float loads put vertices 0-3 in the low halves and 4-7 in the high halves, so that
      // in-lane shuffles (no gathers, no lane crossing) separate x, y, z.
      const __m256 m03 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
      const __m256 m14 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
      const __m256 m25 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
      // Per half: m03 = x0 y0 z0 x1, m14 = y1 z1 x2 y2, m25 = z2 x3 y3 z3.
      const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));  // x2 y2 x3 y3
      const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));  // y0 z0 y1 z1
      out[0].v = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
      out[1].v = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
      out[2].v = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
      return;
    }
    const __m256i offsets =
        _mm256_mullo_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(static_cast<int>(stride)));
    for (int c = 0; c < 3; ++c) out[c].v = _mm256_i32gather_ps(p + c, offsets, 1);
  }

  static void store3(float* base, std::size_t stride, std::size_t i, const F8 in[3], bool /*stream*/) {
    unsigned char* p = reinterpret_cast<unsigned char*>(base) + i * stride;
    if (stride == 12) {
      // load3's shuffles run backwards: per half, x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3, then halves regrouped.
      const __m256 x = in[0].v, y = in[1].v, z = in[2].v;
      const __m256 xy = _mm256_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0));  // x0 x2 y0 y2
      const __m256 yz = _mm256_shuffle_ps(y, z, _MM_SHUFFLE(3, 1, 3, 1));  // y1 y3 z1 z3
      const __m256 zx = _mm256_shuffle_ps(z, x, _MM_SHUFFLE(3, 1, 2, 0));  // z0 z2 x1 x3
      const __m256 m03 = _mm256_shuffle_ps(xy, zx, _MM_SHUFFLE(2, 0, 2, 0));
      const __m256 m14 = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
      const __m256 m25 = _mm256_shuffle_ps(zx, yz, _MM_SHUFFLE(3, 1, 3, 1));
      float* out = reinterpret_cast<float*>(p);
      _mm256_storeu_ps(out, _mm256_permute2f128_ps(m03, m14, 0x20));
      _mm256_storeu_ps(out + 8, _mm256_permute2f128_ps(m25, m03, 0x30));
      _mm256_storeu_ps(out + 16, _mm256_permute2f128_ps(m14, m25, 0x31));
      return;
    }
    __m256 r[4];
    transpose4_in_lanes(in[0].v, in[1].v, in[2].v, in[2].v, r);
    // r[e] half c = x y z z of vertex 4c + e.
    for (int e = 0; e < 4; ++e)
      for (int c = 0; c < 2; ++c) {
        const __m128 xyz = c == 0 ? _mm256_castps256_ps128(r[e]) : _mm256_extractf128_ps(r[e], 1);
        float* out = reinterpret_cast<float*>(p + static_cast<std::size_t>(4 * c + e) * stride);
        _mm_storel_pi(reinterpret_cast<__m64*>(out), xyz);
        _mm_store_ss(out + 2, _mm_movehl_ps(xyz, xyz));
      }
  }
};

}  // namespace
}  // namespace deform::detail

#include "skinning_simd.hpp"

namespace deform::detail {

void skin_lbs_avx2(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_lbs_blocks<Avx2>(job, begin, end);
}
void skin_dqs_avx2(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_dqs_blocks<Avx2>(job, begin, end);
}

}  // namespace deform::detail
