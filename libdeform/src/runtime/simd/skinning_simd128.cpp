// Skinning kernels for WebAssembly SIMD128: 4 vertices per step, the block loops of skinning_simd.hpp over v128
// values. Built only into a WebAssembly build with DEFORM_WASM_SIMD128 (compiled with -msimd128; an engine without
// SIMD128 refuses the whole module, so there is no run-time check). SIMD128 has no fused multiply-add: fma() below is
// a multiply and an add, so this copy rounds as the portable one does where their operations agree. A blended mat4 is
// four vectors per vertex, transposed to SoA by one 4×4 transpose per column; packed vec3 streams (stride 12) are
// three loads and six shuffles that de-interleave x, y, z.
#include <wasm_simd128.h>

#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

struct F4 {
  v128_t v;
};
inline F4 operator+(F4 a, F4 b) { return {wasm_f32x4_add(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {wasm_f32x4_sub(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {wasm_f32x4_mul(a.v, b.v)}; }
inline F4 fma(F4 a, F4 b, F4 c) { return {wasm_f32x4_add(wasm_f32x4_mul(a.v, b.v), c.v)}; }
inline F4 fms(F4 a, F4 b, F4 c) { return {wasm_f32x4_sub(wasm_f32x4_mul(a.v, b.v), c.v)}; }
inline F4 max(F4 a, F4 b) { return {wasm_f32x4_max(a.v, b.v)}; }
// A true square root and division, correctly rounded: no estimate to refine.
inline F4 rsqrt(F4 x) { return {wasm_f32x4_div(wasm_f32x4_splat(1.0f), wasm_f32x4_sqrt(x.v))}; }
inline F4 rcp(F4 x) { return {wasm_f32x4_div(wasm_f32x4_splat(1.0f), x.v)}; }
inline F4 flip_sign(F4 w, F4 d) {
  return {wasm_v128_xor(w.v, wasm_v128_and(d.v, wasm_i32x4_splat(static_cast<int>(0x80000000u))))};
}

// 4×4 transpose: out[e] lane l = element e of r[l].
inline void transpose4(const v128_t r[4], v128_t out[4]) {
  const v128_t t0 = wasm_i32x4_shuffle(r[0], r[1], 0, 4, 1, 5);  // a0 b0 a1 b1
  const v128_t t1 = wasm_i32x4_shuffle(r[0], r[1], 2, 6, 3, 7);  // a2 b2 a3 b3
  const v128_t t2 = wasm_i32x4_shuffle(r[2], r[3], 0, 4, 1, 5);  // c0 d0 c1 d1
  const v128_t t3 = wasm_i32x4_shuffle(r[2], r[3], 2, 6, 3, 7);  // c2 d2 c3 d3
  out[0] = wasm_i32x4_shuffle(t0, t2, 0, 1, 4, 5);
  out[1] = wasm_i32x4_shuffle(t0, t2, 2, 3, 6, 7);
  out[2] = wasm_i32x4_shuffle(t1, t3, 0, 1, 4, 5);
  out[3] = wasm_i32x4_shuffle(t1, t3, 2, 3, 6, 7);
}

struct Simd128 {
  using V = F4;
  static constexpr std::size_t width = 4;
  static constexpr bool can_stream = false;  // no non-temporal stores in WebAssembly
  static constexpr bool has_component_tables = false;
  static void fence() {}
  explicit Simd128(const SkinningJob&) {}

  static F4 splat(float x) { return {wasm_f32x4_splat(x)}; }

  static void blend_matrices(const SkinningJob& job, std::size_t i, const V*, V a[12]) {
    const float* palette = &job.matrices[0][0][0];
    v128_t columns[4][4];  // [column][vertex]
    for (int l = 0; l < 4; ++l) {
      const glm::u16vec4 b = job.bone_indices[i + std::size_t(l)];
      const glm::vec4 w = job.bone_weights[i + std::size_t(l)];
      v128_t sum[4] = {wasm_f32x4_splat(0.0f), wasm_f32x4_splat(0.0f), wasm_f32x4_splat(0.0f), wasm_f32x4_splat(0.0f)};
      for (int k = 0; k < 4; ++k) {
        const float* m = palette + 16 * std::size_t{b[k]};
        const v128_t weight = wasm_f32x4_splat(w[k]);
        for (int c = 0; c < 4; ++c) sum[c] = wasm_f32x4_add(sum[c], wasm_f32x4_mul(wasm_v128_load(m + 4 * c), weight));
      }
      for (int c = 0; c < 4; ++c) columns[c][l] = sum[c];
    }
    for (int c = 0; c < 4; ++c) {
      v128_t t[4];
      transpose4(columns[c], t);
      for (int r = 0; r < 3; ++r) a[3 * c + r].v = t[r];
    }
  }

  static void load_weights(const SkinningJob& job, std::size_t i, F4 w[4]) {
    v128_t rows[4], t[4];
    for (int l = 0; l < 4; ++l) rows[l] = wasm_v128_load(&job.bone_weights[i + std::size_t(l)].x);
    transpose4(rows, t);
    for (int e = 0; e < 4; ++e) w[e].v = t[e];
  }

  static void load_dual_quat(const SkinningJob& job, std::size_t i, int k, F4 q[8]) {
    const float* palette = &job.dual_quats[0].real.x;
    v128_t real[4], dual[4], t[4];
    for (int l = 0; l < 4; ++l) {
      const float* d = palette + 8 * std::size_t{job.bone_indices[i + std::size_t(l)][k]};
      real[l] = wasm_v128_load(d), dual[l] = wasm_v128_load(d + 4);
    }
    transpose4(real, t);
    for (int c = 0; c < 4; ++c) q[c].v = t[c];
    transpose4(dual, t);
    for (int c = 0; c < 4; ++c) q[4 + c].v = t[c];
  }

  static void load3(const float* base, std::size_t stride, std::size_t i, F4 out[3]) {
    const unsigned char* p = reinterpret_cast<const unsigned char*>(base) + i * stride;
    if (stride == 12) {
      const float* f = reinterpret_cast<const float*>(p);
      // a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3
      const v128_t a = wasm_v128_load(f), b = wasm_v128_load(f + 4), c = wasm_v128_load(f + 8);
      out[0].v = wasm_i32x4_shuffle(wasm_i32x4_shuffle(a, b, 0, 3, 6, 7), c, 0, 1, 2, 5);
      out[1].v = wasm_i32x4_shuffle(wasm_i32x4_shuffle(a, b, 1, 4, 7, 7), c, 0, 1, 2, 6);
      out[2].v = wasm_i32x4_shuffle(wasm_i32x4_shuffle(a, b, 2, 5, 5, 5), c, 0, 1, 4, 7);
      return;
    }
    float lanes[3][4];
    for (std::size_t l = 0; l < 4; ++l) {
      const float* v = reinterpret_cast<const float*>(p + l * stride);
      for (int c = 0; c < 3; ++c) lanes[c][l] = v[c];
    }
    for (int c = 0; c < 3; ++c) out[c].v = wasm_v128_load(lanes[c]);
  }

  static void store3(float* base, std::size_t stride, std::size_t i, const F4 in[3], bool /*stream*/) {
    unsigned char* p = reinterpret_cast<unsigned char*>(base) + i * stride;
    if (stride == 12) {
      float* f = reinterpret_cast<float*>(p);
      const v128_t x = in[0].v, y = in[1].v, z = in[2].v;
      wasm_v128_store(f, wasm_i32x4_shuffle(wasm_i32x4_shuffle(x, y, 0, 4, 1, 5), z, 0, 1, 4, 2));
      wasm_v128_store(f + 4, wasm_i32x4_shuffle(wasm_i32x4_shuffle(x, y, 1, 5, 2, 6), z, 1, 5, 2, 3));
      wasm_v128_store(f + 8, wasm_i32x4_shuffle(wasm_i32x4_shuffle(x, y, 3, 7, 2, 6), z, 6, 0, 1, 7));
      return;
    }
    float lanes[3][4];
    for (int c = 0; c < 3; ++c) wasm_v128_store(lanes[c], in[c].v);
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

void skin_lbs_simd128(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_lbs_blocks<Simd128>(job, begin, end);
}
void skin_dqs_simd128(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_dqs_blocks<Simd128>(job, begin, end);
}

}  // namespace deform::detail
