// Skinning kernels for AVX-512 (F, DQ, VL, BW): 16 vertices per step. Compiled with -mavx512f -mavx512dq -mavx512vl
// -mavx512bw -mfma; only reached when the CPU reports those features (skinning.cpp).
//
// Palettes of at most 64 bones (a game character, or one draw-call's bone subset) are first transposed into
// per-component tables, so fetching a component for 16 vertices is one two-register permute (vpermt2ps) indexed by
// their bone ids when the palette has at most 32 bones, and two permutes and a blend on the id's bit 5 up to 64: no
// gathers, no transposes. (The built-in character has 33 bones; through the general path its skinning took twice as
// long.) Larger palettes take the general path: LBS blends
// each vertex's four matrices in one register (a mat4 is 16 floats) and transposes the 16 blended matrices to SoA
// (16×16, 4 shuffle stages); DQS loads each influence's dual quaternions two vertices per register and transposes
// them (two 8×8 at once). Either way the antipodality test, the blend and the transform run on 16 lanes.
#include <immintrin.h>

#include "deform/runtime/portable.hpp"
#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

struct F16 {
  __m512 v;
};
inline F16 operator+(F16 a, F16 b) { return {_mm512_add_ps(a.v, b.v)}; }
inline F16 operator-(F16 a, F16 b) { return {_mm512_sub_ps(a.v, b.v)}; }
inline F16 operator*(F16 a, F16 b) { return {_mm512_mul_ps(a.v, b.v)}; }
inline F16 fma(F16 a, F16 b, F16 c) { return {_mm512_fmadd_ps(a.v, b.v, c.v)}; }
inline F16 fms(F16 a, F16 b, F16 c) { return {_mm512_fmsub_ps(a.v, b.v, c.v)}; }
inline F16 max(F16 a, F16 b) { return {_mm512_max_ps(a.v, b.v)}; }
// 14-bit estimates refined by one Newton step (relative error ~1e-7).
inline F16 rsqrt(F16 x) {
  const __m512 y = _mm512_rsqrt14_ps(x.v);
  const __m512 half_x_yy = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(0.5f), x.v), _mm512_mul_ps(y, y));
  return {_mm512_mul_ps(y, _mm512_sub_ps(_mm512_set1_ps(1.5f), half_x_yy))};
}
inline F16 rcp(F16 x) {
  const __m512 y = _mm512_rcp14_ps(x.v);
  return {_mm512_mul_ps(y, _mm512_fnmadd_ps(x.v, y, _mm512_set1_ps(2.0f)))};
}
inline F16 flip_sign(F16 w, F16 d) { return {_mm512_xor_ps(w.v, _mm512_and_ps(d.v, _mm512_set1_ps(-0.0f)))}; }

inline __m512 unpacklo_pd(__m512 a, __m512 b) {
  return _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
}
inline __m512 unpackhi_pd(__m512 a, __m512 b) {
  return _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
}

// In-lane 4×4 transpose of rows r0..r3 (per 128-bit chunk): out[e] chunk c lane j = element e of r_j chunk c.
inline void transpose4_in_lanes(__m512 r0, __m512 r1, __m512 r2, __m512 r3, __m512 out[4]) {
  const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  out[0] = unpacklo_pd(t0, t2), out[1] = unpackhi_pd(t0, t2);
  out[2] = unpacklo_pd(t1, t3), out[3] = unpackhi_pd(t1, t3);
}

// Rows 0..2 of the columns of sixteen mat4s m[l] (column-major, 16 floats each) as SoA: a[3c + e] lane l = column c,
// row e of m[l] (c = 3: the translation). A 16×16 transpose of which 12 rows are kept.
inline void transpose_affine(const __m512 m[16], __m512 a[12]) {
  __m512 u[16];
  for (int g = 0; g < 4; ++g) transpose4_in_lanes(m[4 * g], m[4 * g + 1], m[4 * g + 2], m[4 * g + 3], u + 4 * g);
  // u[4g + e] chunk c = element 4c + e of rows 4g .. 4g+3.
  for (int e = 0; e < 3; ++e) {
    const __m512 s0 = _mm512_shuffle_f32x4(u[e], u[4 + e], _MM_SHUFFLE(2, 0, 2, 0));
    const __m512 s1 = _mm512_shuffle_f32x4(u[e], u[4 + e], _MM_SHUFFLE(3, 1, 3, 1));
    const __m512 s2 = _mm512_shuffle_f32x4(u[8 + e], u[12 + e], _MM_SHUFFLE(2, 0, 2, 0));
    const __m512 s3 = _mm512_shuffle_f32x4(u[8 + e], u[12 + e], _MM_SHUFFLE(3, 1, 3, 1));
    a[0 + e] = _mm512_shuffle_f32x4(s0, s2, _MM_SHUFFLE(2, 0, 2, 0));  // column 0
    a[6 + e] = _mm512_shuffle_f32x4(s0, s2, _MM_SHUFFLE(3, 1, 3, 1));  // column 2
    a[3 + e] = _mm512_shuffle_f32x4(s1, s3, _MM_SHUFFLE(2, 0, 2, 0));  // column 1
    a[9 + e] = _mm512_shuffle_f32x4(s1, s3, _MM_SHUFFLE(3, 1, 3, 1));  // column 3: translation
  }
}

__m512i lane_offsets(std::size_t stride) {
  return _mm512_mullo_epi32(_mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                            _mm512_set1_epi32(static_cast<int>(stride)));
}

struct Avx512 {
  using V = F16;
  static constexpr std::size_t width = 16;
  static constexpr std::size_t max_table_bones = 64;
  static constexpr std::size_t narrow_table_bones = 32;  // one two-register permute per component
  static constexpr bool can_stream = true;
  static constexpr bool has_component_tables = true;
  static void fence() { _mm_sfence(); }  // streamed lines reach memory before what the caller writes next

  // Component tables: table[c][b] = component c of bone b (LBS: columns 0..2 rows 0..2, then the translation; DQS:
  // real xyzw, dual xyzw). Used when the palette has at most 64 bones; `wide` when it has more than 32. Columns past
  // the palette up to 32 (or 64) are zero, the rest are never loaded; the array is not cleared as a whole because the
  // kernel builds it on every call.
  bool use_tables = false;
  bool wide = false;
  alignas(64) float table[12][max_table_bones];

  explicit Avx512(const SkinningJob& job) {
    const bool lbs = job.method == SkinningMethod::lbs;
    const std::size_t bones = lbs ? job.matrices.size() : job.dual_quats.size();
    if (bones > max_table_bones) return;
    use_tables = true;
    wide = bones > narrow_table_bones;
    const std::size_t columns = wide ? max_table_bones : narrow_table_bones;
    if (lbs) {
      // Sixteen bones at a time, transposed in registers (a scalar copy and zero fill: 0.06 µs more per call for a
      // 33-bone character); bones past the palette are zero lanes.
      fill_affine_table(job.matrices, columns);
      return;
    }
    for (std::size_t b = 0; b < bones; ++b) {
      const DualQuat& q = job.dual_quats[b];
      const float values[8] = {q.real.x, q.real.y, q.real.z, q.real.w, q.dual.x, q.dual.y, q.dual.z, q.dual.w};
      for (int c = 0; c < 8; ++c) table[c][b] = values[c];
    }
    for (int c = 0; c < 8; ++c)
      for (std::size_t b = bones; b < columns; ++b) table[c][b] = 0.0f;
  }

  // Out of line: run once per call, it stays out of the function that holds the block loop.
  DEFORM_NOINLINE void fill_affine_table(std::span<const glm::mat4> matrices, std::size_t columns) {
    for (std::size_t first = 0; first < columns; first += 16) {
      __m512 m[16], a[12];
      for (std::size_t l = 0; l < 16; ++l)
        m[l] = first + l < matrices.size() ? _mm512_loadu_ps(&matrices[first + l][0][0]) : _mm512_setzero_ps();
      transpose_affine(m, a);
      for (int c = 0; c < 12; ++c) _mm512_store_ps(&table[c][first], a[c]);
    }
  }

  static V splat(float x) { return {_mm512_set1_ps(x)}; }

  // Bone ids of influence k of vertices i .. i+15 as 32-bit lanes, in their low 16 bits (for even k the high bits
  // hold influence k + 1: the table lookups read only the low 6 bits). As 32-bit words, vertex l's four 16-bit ids
  // are words 2l (influences 0, 1) and 2l + 1 (influences 2, 3).
  static __m512i raw_bone_ids(const SkinningJob& job, std::size_t i, int k) {
    const __m512i* p = reinterpret_cast<const __m512i*>(&job.bone_indices[i]);
    const __m512i words = _mm512_add_epi32(_mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30),
                                           _mm512_set1_epi32(k >> 1));
    const __m512i pair = _mm512_permutex2var_epi32(_mm512_loadu_si512(p), words, _mm512_loadu_si512(p + 1));
    return (k & 1) != 0 ? _mm512_srli_epi32(pair, 16) : pair;
  }

  // Ids ready for lookup: the permute index (its low 5 bits) and, for a wide table, the lanes whose bone is 32..63.
  struct Ids {
    __m512i index;
    __mmask16 upper;
  };
  template <bool wide_table>
  static Ids ids_for(__m512i raw) {
    return {raw, wide_table ? _mm512_test_epi32_mask(raw, _mm512_set1_epi32(32)) : __mmask16(0)};
  }
  Ids bone_ids(const SkinningJob& job, std::size_t i, int k) const {
    const __m512i raw = raw_bone_ids(job, i, k);
    return wide ? ids_for<true>(raw) : ids_for<false>(raw);
  }

  V component(int c, Ids ids) const { return {wide ? lookup<true>(c, ids) : lookup<false>(c, ids)}; }

  template <bool wide_table>
  __m512 lookup(int component, Ids ids) const {
    const float* row = table[component];
    const __m512 low = _mm512_permutex2var_ps(_mm512_load_ps(row), ids.index, _mm512_load_ps(row + 16));
    if constexpr (!wide_table) {
      return low;
    } else {
      const __m512 high = _mm512_permutex2var_ps(_mm512_load_ps(row + 32), ids.index, _mm512_load_ps(row + 48));
      return _mm512_mask_blend_ps(ids.upper, low, high);
    }
  }

  // Σₖ wₖ Mₖ from the tables, one SoA component at a time.
  template <bool wide_table>
  void blend_from_tables(const SkinningJob& job, std::size_t i, const V w[4], V a[12]) const {
    const __m512i low = raw_bone_ids(job, i, 0), high = raw_bone_ids(job, i, 2);
    const Ids ids[4] = {ids_for<wide_table>(low), ids_for<wide_table>(_mm512_srli_epi32(low, 16)),
                        ids_for<wide_table>(high), ids_for<wide_table>(_mm512_srli_epi32(high, 16))};
    for (int c = 0; c < 12; ++c) {
      __m512 sum = _mm512_mul_ps(w[0].v, lookup<wide_table>(c, ids[0]));
      for (int k = 1; k < 4; ++k) sum = _mm512_fmadd_ps(w[k].v, lookup<wide_table>(c, ids[k]), sum);
      a[c].v = sum;
    }
  }

  // Forced inline: called once per block, where a call cost 25% of the in-cache kernel.
  DEFORM_ALWAYS_INLINE void blend_matrices(const SkinningJob& job, std::size_t i, const V w[4], V a[12]) const {
    if (use_tables) {
      // A wide table's block whose sixteen vertices all have bones below 32 (bit 5 clear in all four 16-bit ids)
      // takes the narrow lookups: with bones ordered root first, most blocks of a 33- to 64-bone character do.
      const __m512i any = _mm512_or_si512(raw_bone_ids(job, i, 0), raw_bone_ids(job, i, 2));
      if (wide && _mm512_test_epi32_mask(any, _mm512_set1_epi32(0x00200020)) != 0) {
        blend_from_tables<true>(job, i, w, a);
      } else {
        blend_from_tables<false>(job, i, w, a);
      }
      return;
    }
    const float* palette = &job.matrices[0][0][0];
    __m512 m[16];
    for (int l = 0; l < 16; ++l) {
      const glm::u16vec4 b = job.bone_indices[i + l];
      const float* weight = &job.bone_weights[i + l].x;
      __m512 s = _mm512_mul_ps(_mm512_set1_ps(weight[0]), _mm512_loadu_ps(palette + 16 * std::size_t{b[0]}));
      s = _mm512_fmadd_ps(_mm512_set1_ps(weight[1]), _mm512_loadu_ps(palette + 16 * std::size_t{b[1]}), s);
      s = _mm512_fmadd_ps(_mm512_set1_ps(weight[2]), _mm512_loadu_ps(palette + 16 * std::size_t{b[2]}), s);
      m[l] = _mm512_fmadd_ps(_mm512_set1_ps(weight[3]), _mm512_loadu_ps(palette + 16 * std::size_t{b[3]}), s);
    }
    __m512 blended[12];
    transpose_affine(m, blended);
    for (int c = 0; c < 12; ++c) a[c].v = blended[c];
  }

  static void load_weights(const SkinningJob& job, std::size_t i, V w[4]) {
    const float* p = &job.bone_weights[i].x;
    const __m512 r0 = _mm512_loadu_ps(p), r1 = _mm512_loadu_ps(p + 16);       // vertices 0-7: weight k at 4v + k
    const __m512 r2 = _mm512_loadu_ps(p + 32), r3 = _mm512_loadu_ps(p + 48);  // vertices 8-15
    const __m512i even_pair = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
    const __m512i odd_pair = _mm512_add_epi32(even_pair, _mm512_set1_epi32(2));
    // Weights 0 | 1 (and 2 | 3) of eight vertices per register, then the halves of the two vertex groups joined.
    const __m512 w01_low = _mm512_permutex2var_ps(r0, even_pair, r1);
    const __m512 w01_high = _mm512_permutex2var_ps(r2, even_pair, r3);
    const __m512 w23_low = _mm512_permutex2var_ps(r0, odd_pair, r1);
    const __m512 w23_high = _mm512_permutex2var_ps(r2, odd_pair, r3);
    w[0].v = _mm512_shuffle_f32x4(w01_low, w01_high, _MM_SHUFFLE(1, 0, 1, 0));
    w[1].v = _mm512_shuffle_f32x4(w01_low, w01_high, _MM_SHUFFLE(3, 2, 3, 2));
    w[2].v = _mm512_shuffle_f32x4(w23_low, w23_high, _MM_SHUFFLE(1, 0, 1, 0));
    w[3].v = _mm512_shuffle_f32x4(w23_low, w23_high, _MM_SHUFFLE(3, 2, 3, 2));
  }

  void load_dual_quat(const SkinningJob& job, std::size_t i, int k, V q[8]) const {
    if (use_tables) {
      const Ids ids = bone_ids(job, i, k);
      for (int c = 0; c < 8; ++c) q[c] = component(c, ids);
      return;
    }
    const float* palette = &job.dual_quats[0].real.x;
    // Row l: vertex l in the low half, vertex 8 + l in the high half.
    __m512 r[8];
    for (int l = 0; l < 8; ++l) {
      const __m256 lo = _mm256_loadu_ps(palette + 8 * std::size_t{job.bone_indices[i + l][k]});
      const __m256 hi = _mm256_loadu_ps(palette + 8 * std::size_t{job.bone_indices[i + 8 + l][k]});
      r[l] = _mm512_insertf32x8(_mm512_castps256_ps512(lo), hi, 1);
    }
    __m512 u[8];
    transpose4_in_lanes(r[0], r[1], r[2], r[3], u);
    transpose4_in_lanes(r[4], r[5], r[6], r[7], u + 4);
    // u[e] chunks: element e of vertices 0-3, element 4+e of 0-3, element e of 8-11, element 4+e of 8-11;
    // u[4+e] the same for vertices 4-7 and 12-15.
    const __m512i low_elements = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
    const __m512i high_elements = _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
    for (int e = 0; e < 4; ++e) {
      q[e].v = _mm512_permutex2var_ps(u[e], low_elements, u[4 + e]);
      q[4 + e].v = _mm512_permutex2var_ps(u[e], high_elements, u[4 + e]);
    }
  }

  static void load3(const float* base, std::size_t stride, std::size_t i, F16 out[3]) {
    const float* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(base) + i * stride);
    if (stride == 12) {
      // Packed vec3: three loads and a two-step permute per component.
      const __m512 r0 = _mm512_loadu_ps(p), r1 = _mm512_loadu_ps(p + 16), r2 = _mm512_loadu_ps(p + 32);
      for (int c = 0; c < 3; ++c) {
        alignas(64) int first[16], second[16];
        for (int l = 0; l < 16; ++l) {
          const int flat = 3 * l + c;
          first[l] = flat < 32 ? flat : 0;
          second[l] = flat < 32 ? l : 16 + (flat - 32);
        }
        const __m512 t = _mm512_permutex2var_ps(r0, _mm512_load_si512(first), r1);
        out[c].v = _mm512_permutex2var_ps(t, _mm512_load_si512(second), r2);
      }
      return;
    }
    const __m512i offsets = lane_offsets(stride);
    for (int c = 0; c < 3; ++c) out[c].v = _mm512_i32gather_ps(offsets, p + c, 1);
  }

  static void store3(float* base, std::size_t stride, std::size_t i, const F16 in[3], bool stream) {
    float* p = reinterpret_cast<float*>(reinterpret_cast<unsigned char*>(base) + i * stride);
    if (stride == 12) {
      __m512 t[3];
      for (int r = 0; r < 3; ++r) {
        // Register r holds flat floats 16r .. 16r+15: component f % 3 of vertex f / 3.
        alignas(64) int first[16], second[16];
        for (int l = 0; l < 16; ++l) {
          const int flat = 16 * r + l, vertex = flat / 3, component = flat % 3;
          first[l] = component == 0 ? vertex : component == 1 ? 16 + vertex : 0;
          second[l] = component == 2 ? 16 + vertex : l;
        }
        const __m512 xy = _mm512_permutex2var_ps(in[0].v, _mm512_load_si512(first), in[1].v);
        t[r] = _mm512_permutex2var_ps(xy, _mm512_load_si512(second), in[2].v);
      }
      if (stream) {  // p is 64-byte aligned (first_streaming_vertex): no read-for-ownership of the lines
        _mm512_stream_ps(p, t[0]);
        _mm512_stream_ps(p + 16, t[1]);
        _mm512_stream_ps(p + 32, t[2]);
      } else {
        _mm512_storeu_ps(p, t[0]);
        _mm512_storeu_ps(p + 16, t[1]);
        _mm512_storeu_ps(p + 32, t[2]);
      }
      return;
    }
    __m512 r[4];
    transpose4_in_lanes(in[0].v, in[1].v, in[2].v, in[2].v, r);
    // r[e] chunk c = x y z z of vertex 4c + e.
    auto at = [&](int vertex) {
      return reinterpret_cast<float*>(reinterpret_cast<unsigned char*>(p) + static_cast<std::size_t>(vertex) * stride);
    };
    for (int e = 0; e < 4; ++e) {
      _mm_mask_storeu_ps(at(e), 0x7, _mm512_castps512_ps128(r[e]));
      _mm_mask_storeu_ps(at(4 + e), 0x7, _mm512_extractf32x4_ps(r[e], 1));
      _mm_mask_storeu_ps(at(8 + e), 0x7, _mm512_extractf32x4_ps(r[e], 2));
      _mm_mask_storeu_ps(at(12 + e), 0x7, _mm512_extractf32x4_ps(r[e], 3));
    }
  }
};

}  // namespace
}  // namespace deform::detail

#include "skinning_simd.hpp"

namespace deform::detail {

void skin_lbs_avx512(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_lbs_blocks<Avx512>(job, begin, end);
}
void skin_dqs_avx512(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_dqs_blocks<Avx512>(job, begin, end);
}

}  // namespace deform::detail
