#pragma once
// Internal: the block loops of the SIMD skinning kernels, written once over an instruction-set traits class and
// instantiated by skinning_avx2.cpp (8 lanes) and skinning_avx512.cpp (16 lanes). Everything here is in an anonymous
// namespace on purpose: each including file compiles it with its own -m flags, so no symbol may be shared.
//
// A traits class `Isa`, constructed once per kernel call from the job (it may precompute per-palette tables), provides:
//   V, width                     the lane vector and its lane count
//   splat(x), fma(a, b, c) = a·b + c, operators + - *, rsqrt(x) and rcp(x) refined to ~1e-7 relative,
//   flip_sign(w, d)              w with its sign flipped in the lanes where d < 0
//   blend_matrices(job, i, w, a) a[12] = columns 0..2 and translation of Σₖ wₖ Mₖ for vertices i .. i+width-1 (SoA),
//                                w = the SoA weights from load_weights
//   load_weights(job, i, w)      w[4] = the four weights, per influence (SoA)
//   load_dual_quat(job, i, k, q) q[8] = real xyzw, dual xyzw of influence k (SoA)
//   load3 / store3               a stream's x, y, z for vertices i .. i+width-1 (SoA), any valid stride
// The math below is skin_lbs_scalar / skin_dqs_scalar on lanes, to float rounding (its reciprocals and square roots
// are refined estimates); the tests hold every path to the reference within 1e-5.
#include "skinning_kernels.hpp"

namespace deform::detail {
namespace {

template <class V>
void normalize_or_zero3(V n[3], V tiny) {
  const V length_squared = fma(n[0], n[0], fma(n[1], n[1], n[2] * n[2]));
  const V inverse_length = rsqrt(max(length_squared, tiny));  // a zero normal times a finite factor stays zero
  for (int c = 0; c < 3; ++c) n[c] = n[c] * inverse_length;
}

// out = cross(a, b)
template <class V>
void cross3(const V a[3], const V b[3], V out[3]) {
  out[0] = fms(a[1], b[2], a[2] * b[1]);
  out[1] = fms(a[2], b[0], a[0] * b[2]);
  out[2] = fms(a[0], b[1], a[1] * b[0]);
}

template <class Isa>
void skin_lbs_blocks(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  using V = typename Isa::V;
  const bool normals = !job.in_normals.empty();
  const V tiny = Isa::splat(1e-30f);
  const Isa isa(job);
  std::size_t i = begin;
  for (; i + Isa::width <= end; i += Isa::width) {
    V a[12], w[4], p[3], n[3], out[3];
    isa.load_weights(job, i, w);
    isa.blend_matrices(job, i, w, a);
    isa.load3(job.in_positions.data(), job.in_positions_stride, i, p);
    if (normals) isa.load3(job.in_normals.data(), job.in_normals_stride, i, n);
    const V inverse_sum = rcp((w[0] + w[1]) + (w[2] + w[3]));
    for (int r = 0; r < 3; ++r) out[r] = fma(a[r], p[0], fma(a[3 + r], p[1], fma(a[6 + r], p[2], a[9 + r]))) * inverse_sum;
    isa.store3(job.out_positions.data(), job.out_positions_stride, i, out);
    if (normals) {
      // Cofactor matrix of the blended 3×3 (columns a1×a2, a2×a0, a0×a1) times the normal.
      V c0[3], c1[3], c2[3];
      cross3(a + 3, a + 6, c0);
      cross3(a + 6, a + 0, c1);
      cross3(a + 0, a + 3, c2);
      for (int r = 0; r < 3; ++r) out[r] = fma(c0[r], n[0], fma(c1[r], n[1], c2[r] * n[2]));
      normalize_or_zero3(out, tiny);
      isa.store3(job.out_normals.data(), job.out_normals_stride, i, out);
    }
  }
  if (i < end) skin_lbs_scalar(job, i, end);
}

template <class Isa>
void skin_dqs_blocks(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  using V = typename Isa::V;
  const bool normals = !job.in_normals.empty();
  const V tiny = Isa::splat(1e-30f);
  const V two = Isa::splat(2.0f);
  const Isa isa(job);
  std::size_t i = begin;
  for (; i + Isa::width <= end; i += Isa::width) {
    V w[4], b[8], q[8];
    isa.load_weights(job, i, w);
    isa.load_dual_quat(job, i, 0, b);
    const V pivot[4] = {b[0], b[1], b[2], b[3]};
    for (int c = 0; c < 8; ++c) b[c] = b[c] * w[0];
    for (int k = 1; k < 4; ++k) {
      isa.load_dual_quat(job, i, k, q);
      // Antipodality: blend each influence in the hemisphere of the first one.
      const V d = fma(q[0], pivot[0], fma(q[1], pivot[1], fma(q[2], pivot[2], q[3] * pivot[3])));
      const V signed_weight = flip_sign(w[k], d);
      for (int c = 0; c < 8; ++c) b[c] = fma(q[c], signed_weight, b[c]);
    }
    const V inverse_length = rsqrt(fma(b[0], b[0], fma(b[1], b[1], fma(b[2], b[2], b[3] * b[3]))));
    for (int c = 0; c < 8; ++c) b[c] = b[c] * inverse_length;
    const V* real = b;
    const V* dual = b + 4;
    // translation = 2 (real.w · dual.xyz - dual.w · real.xyz + real.xyz × dual.xyz)
    V translation[3];
    cross3(real, dual, translation);
    for (int c = 0; c < 3; ++c)
      translation[c] = two * (fma(real[3], dual[c], translation[c]) - dual[3] * real[c]);

    V p[3], n[3], t[3], u[3];
    isa.load3(job.in_positions.data(), job.in_positions_stride, i, p);
    if (normals) isa.load3(job.in_normals.data(), job.in_normals_stride, i, n);
    // rotate(v) = v + 2 r × (r × v + w v)
    cross3(real, p, t);
    for (int c = 0; c < 3; ++c) t[c] = fma(real[3], p[c], t[c]);
    cross3(real, t, u);
    for (int c = 0; c < 3; ++c) u[c] = fma(u[c], two, p[c]) + translation[c];
    isa.store3(job.out_positions.data(), job.out_positions_stride, i, u);
    if (normals) {
      cross3(real, n, t);
      for (int c = 0; c < 3; ++c) t[c] = fma(real[3], n[c], t[c]);
      cross3(real, t, u);
      for (int c = 0; c < 3; ++c) u[c] = fma(u[c], two, n[c]);
      normalize_or_zero3(u, tiny);
      isa.store3(job.out_normals.data(), job.out_normals_stride, i, u);
    }
  }
  if (i < end) skin_dqs_scalar(job, i, end);
}

}  // namespace
}  // namespace deform::detail
