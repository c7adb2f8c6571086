#pragma once
// Internal: the block loops of the SIMD skinning kernels, written once over an instruction-set traits class and
// instantiated by skinning_avx2.cpp (8 lanes), skinning_avx512.cpp (16 lanes), skinning_neon.cpp (4 lanes, aarch64)
// and skinning_simd128.cpp (4 lanes, WebAssembly).
// Everything here is in an anonymous namespace on purpose: each including file compiles it with its own -m flags, so
// no symbol may be shared.
//
// A traits class `Isa`, constructed once per kernel call from the job (it may precompute per-palette tables), provides:
//   V, width                     the lane vector and its lane count
//   splat(x), fma(a, b, c) = a·b + c, operators + - *, rsqrt(x) and rcp(x) refined to ~1e-7 relative,
//   flip_sign(w, d)              w with its sign flipped in the lanes where d < 0
//   blend_matrices(job, i, w, a) a[12] = columns 0..2 and translation of Σₖ wₖ Mₖ for vertices i .. i+width-1 (SoA),
//                                w = the SoA weights from load_weights
//   load_weights(job, i, w)      w[4] = the four weights, per influence (SoA)
//   load_dual_quat(job, i, k, q) q[8] = real xyzw, dual xyzw of influence k (SoA)
//   has_component_tables         true when the Isa may hold the palette as per-component tables; then, when its
//                                use_tables is set, bone_ids(job, i, k) (type Ids) and component(c, ids) fetch one
//                                component of influence k for the block
//   load3 / store3               a stream's x, y, z for vertices i .. i+width-1 (SoA), any valid stride; store3's
//                                `stream` asks for non-temporal stores (the block's packed output 64-byte aligned)
//   can_stream, fence()          whether store3 honours `stream`; fence() ends a streaming call (store ordering)
// The math below is skin_lbs_portable / skin_dqs_portable on lanes, to float rounding (its reciprocals and square roots
// are refined estimates); the tests hold every path to the reference within 1e-5.
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "deform/runtime/portable.hpp"
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

// out = cof(A) n, A the 3×3 of a[0..8] (columns a0, a1, a2 as in blend_matrices): the cofactor matrix (columns
// a1×a2, a2×a0, a0×a1) times n, in 21 operations instead of the 27 of its three columns. With X, Y, Z the rows of A,
// component x of cof(A) n is n·(Y×Z) = (n×Y)·Z, y is (n×Z)·X and z is -(n×Y)·X; p = n×Y is formed with its third
// component negated (the operands of its fms swapped, no extra operation) so that no result needs a negation.
template <class V>
DEFORM_ALWAYS_INLINE inline void cofactor_times(const V a[12], const V n[3], V out[3]) {
  const V x[3] = {a[0], a[3], a[6]}, y[3] = {a[1], a[4], a[7]}, z[3] = {a[2], a[5], a[8]};
  const V p0 = fms(n[1], y[2], n[2] * y[1]);
  const V p1 = fms(n[2], y[0], n[0] * y[2]);
  const V minus_p2 = fms(n[1], y[0], n[0] * y[1]);
  V q[3];
  cross3(n, z, q);
  out[0] = fma(p0, z[0], fms(p1, z[1], minus_p2 * z[2]));
  out[1] = fma(q[0], x[0], fma(q[1], x[1], q[2] * x[2]));
  out[2] = fms(minus_p2, x[2], fma(p1, x[1], p0 * x[0]));
}

// One block of Isa::width vertices from vertex i. Forced inline: as a call per block it lost ~5% (the loop's
// constants reloaded every block).
template <class Isa>
DEFORM_ALWAYS_INLINE inline void skin_lbs_block(const SkinningJob& job, const Isa& isa, std::size_t i,
                                                bool stream) noexcept {
  using V = typename Isa::V;
  const bool normals = !job.in_normals.empty();
  V a[12], w[4], p[3], n[3], out[3];
  isa.load_weights(job, i, w);
  isa.blend_matrices(job, i, w, a);
  isa.load3(job.in_positions.data(), job.in_positions_stride, i, p);
  if (normals) isa.load3(job.in_normals.data(), job.in_normals_stride, i, n);
  const V inverse_sum = rcp((w[0] + w[1]) + (w[2] + w[3]));
  for (int r = 0; r < 3; ++r)
    out[r] = fma(a[r], p[0], fma(a[3 + r], p[1], fma(a[6 + r], p[2], a[9 + r]))) * inverse_sum;
  isa.store3(job.out_positions.data(), job.out_positions_stride, i, out, stream);
  if (normals) {
    cofactor_times(a, n, out);
    normalize_or_zero3(out, Isa::splat(1e-30f));
    isa.store3(job.out_normals.data(), job.out_normals_stride, i, out, stream);
  }
}

template <class Isa>
DEFORM_ALWAYS_INLINE inline void skin_dqs_block(const SkinningJob& job, const Isa& isa, std::size_t i,
                                                bool stream) noexcept {
  using V = typename Isa::V;
  const bool normals = !job.in_normals.empty();
  const V two = Isa::splat(2.0f);
  V w[4], b[8];
  isa.load_weights(job, i, w);
  bool blended = false;
  if constexpr (Isa::has_component_tables) {
    if (isa.use_tables) {
      // Components fetched one at a time from the tables: the real halves first (they decide each influence's
      // sign), then the dual halves with those signs, so that no influence's eight components are live at once
      // (all of them spilled registers).
      typename Isa::Ids ids[4];
      for (int k = 0; k < 4; ++k) ids[k] = isa.bone_ids(job, i, k);
      V pivot[4];
      for (int c = 0; c < 4; ++c) pivot[c] = isa.component(c, ids[0]), b[c] = pivot[c] * w[0];
      for (int k = 1; k < 4; ++k) {
        V q[4];
        for (int c = 0; c < 4; ++c) q[c] = isa.component(c, ids[k]);
        const V d = fma(q[0], pivot[0], fma(q[1], pivot[1], fma(q[2], pivot[2], q[3] * pivot[3])));
        w[k] = flip_sign(w[k], d);
        for (int c = 0; c < 4; ++c) b[c] = fma(q[c], w[k], b[c]);
      }
      for (int c = 4; c < 8; ++c) {
        b[c] = isa.component(c, ids[0]) * w[0];
        for (int k = 1; k < 4; ++k) b[c] = fma(isa.component(c, ids[k]), w[k], b[c]);
      }
      blended = true;
    }
  }
  if (!blended) {
    V q[8];
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
  }
  // The blend is not normalised: with L² = |real|², the translation (bilinear in real and dual) and the rotation's
  // correction term below (quadratic in real) each take a factor L², so both use s = 2 / L² where the unit form has 2:
  // eight multiplications and a square root fewer than dividing the eight components by L.
  const V s = two * rcp(fma(b[0], b[0], fma(b[1], b[1], fma(b[2], b[2], b[3] * b[3]))));
  const V* real = b;
  const V* dual = b + 4;
  // translation = 2 (real.w · dual.xyz - dual.w · real.xyz + real.xyz × dual.xyz) for a unit real part
  V translation[3];
  cross3(real, dual, translation);
  for (int c = 0; c < 3; ++c) translation[c] = s * (fma(real[3], dual[c], translation[c]) - dual[3] * real[c]);

  V p[3], n[3], t[3], u[3];
  isa.load3(job.in_positions.data(), job.in_positions_stride, i, p);
  if (normals) isa.load3(job.in_normals.data(), job.in_normals_stride, i, n);
  // rotate(v) = v + 2 r × (r × v + w v) for a unit quaternion (r, w); v + s r × (r × v + w v) for this one
  cross3(real, p, t);
  for (int c = 0; c < 3; ++c) t[c] = fma(real[3], p[c], t[c]);
  cross3(real, t, u);
  for (int c = 0; c < 3; ++c) u[c] = fma(u[c], s, p[c]) + translation[c];
  isa.store3(job.out_positions.data(), job.out_positions_stride, i, u, stream);
  if (normals) {
    cross3(real, n, t);
    for (int c = 0; c < 3; ++c) t[c] = fma(real[3], n[c], t[c]);
    cross3(real, t, u);
    for (int c = 0; c < 3; ++c) u[c] = fma(u[c], s, n[c]);
    normalize_or_zero3(u, Isa::splat(1e-30f));
    isa.store3(job.out_normals.data(), job.out_normals_stride, i, u, stream);
  }
}

// One block of either method.
template <class Isa, SkinningMethod method>
DEFORM_ALWAYS_INLINE inline void skin_block(const SkinningJob& job, const Isa& isa, std::size_t i, bool stream) {
  if constexpr (method == SkinningMethod::lbs) {
    skin_lbs_block(job, isa, i, stream);
  } else {
    skin_dqs_block(job, isa, i, stream);
  }
}

// Vertices [i, i + count), count < width, through the block code: staged in packed local arrays padded with a
// harmless vertex (bone 0, weight 1, at the origin), so that a partial block gives the bits a full one would — the
// lanes never mix — and a vertex's result does not depend on where a block or a thread's range begins.
template <class Isa, SkinningMethod method>
void skin_partial_block(const SkinningJob& job, const Isa& isa, std::size_t i, std::size_t count) noexcept {
  constexpr std::size_t width = Isa::width;
  const bool normals = !job.in_normals.empty();
  glm::u16vec4 bones[width];
  glm::vec4 weights[width];
  float in_positions[3 * width] = {}, in_normals[3 * width] = {}, out_positions[3 * width], out_normals[3 * width];
  for (std::size_t l = 0; l < width; ++l) {
    bones[l] = l < count ? job.bone_indices[i + l] : glm::u16vec4(0);
    weights[l] = l < count ? job.bone_weights[i + l] : glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
  }
  for (std::size_t l = 0; l < count; ++l) {
    std::memcpy(in_positions + 3 * l, stream_at(job.in_positions, job.in_positions_stride, i + l), 12);
    if (normals) std::memcpy(in_normals + 3 * l, stream_at(job.in_normals, job.in_normals_stride, i + l), 12);
  }
  SkinningJob local = job;
  local.bone_indices = bones;
  local.bone_weights = weights;
  local.in_positions = in_positions, local.out_positions = out_positions;
  local.in_positions_stride = local.out_positions_stride = 12;
  if (normals) {
    local.in_normals = in_normals, local.out_normals = out_normals;
    local.in_normals_stride = local.out_normals_stride = 12;
  }
  skin_block<Isa, method>(local, isa, 0, false);
  for (std::size_t l = 0; l < count; ++l) {
    std::memcpy(stream_at(job.out_positions, job.out_positions_stride, i + l), out_positions + 3 * l, 12);
    if (normals) std::memcpy(stream_at(job.out_normals, job.out_normals_stride, i + l), out_normals + 3 * l, 12);
  }
}

// The first vertex at or after `begin` whose outputs start on a 64-byte line, when the job asks for streaming
// stores and they can be used: packed outputs (stride 12) whose lines fall alike for positions and normals. Else
// `end` (no streaming).
template <class Isa>
std::size_t first_streaming_vertex(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  if (!Isa::can_stream || !job.stream_outputs || job.out_positions_stride != 12) return end;
  const auto address = [&](std::span<float> s) { return reinterpret_cast<std::uintptr_t>(s.data()) + 12 * begin; };
  const std::uintptr_t positions = address(job.out_positions);
  if (positions % 4 != 0) return end;
  if (!job.out_normals.empty() && (job.out_normals_stride != 12 || address(job.out_normals) % 64 != positions % 64))
    return end;
  // 12 · k runs through every multiple of 4 modulo 64 for k in [0, 16).
  std::size_t k = 0;
  while ((positions + 12 * k) % 64 != 0) ++k;
  return std::min(end, begin + k);
}

// Asks for the input cache lines of the block `prefetch_distance` vertices ahead. At 1M vertices the hardware
// prefetchers alone left the kernel waiting on memory: this measured about 7% (LBS) and 2% (DQS) faster there, and
// nothing at cache-resident sizes. A prefetch never faults, so addresses past the end are harmless (formed as
// integers).
constexpr std::size_t prefetch_distance = 128;

// The lines of `bytes` bytes from base + offset, for reading or (`write`) for writing: PREFETCHW where the file is
// compiled with -mprfchw, else an ordinary hint.
template <std::size_t bytes, bool write = false>
DEFORM_ALWAYS_INLINE inline void prefetch_lines(const void* base, std::size_t offset) noexcept {
  const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(base) + offset;
  for (std::size_t line = 0; line < bytes; line += 64)
    DEFORM_PREFETCH(reinterpret_cast<const char*>(start + line), write ? 1 : 0);
}

// Branch-free: for a strided stream (a line per vertex) the first lines are asked for, for absent normals an
// address near zero; neither costs more than the request. Outputs written in place through the caches are asked for
// too, for writing: a crowd's character writes 71 KB of positions and normals that are cold when its frame starts,
// and read-for-ownership misses the hardware prefetchers left to the stores cost 3-5% of the crowd's frame (not
// when streaming: those stores bypass the caches).
template <std::size_t width, bool stream>
DEFORM_ALWAYS_INLINE inline void prefetch_inputs(const SkinningJob& job, std::size_t i) noexcept {
  const std::size_t ahead = i + prefetch_distance;
  prefetch_lines<width * sizeof(glm::vec4)>(job.bone_weights.data(), ahead * sizeof(glm::vec4));
  prefetch_lines<width * sizeof(glm::u16vec4)>(job.bone_indices.data(), ahead * sizeof(glm::u16vec4));
  prefetch_lines<width * 12>(job.in_positions.data(), ahead * job.in_positions_stride);
  prefetch_lines<width * 12>(job.in_normals.data(), ahead * job.in_normals_stride);
  if constexpr (!stream) {
    prefetch_lines<width * 12, true>(job.out_positions.data(), ahead * job.out_positions_stride);
    prefetch_lines<width * 12, true>(job.out_normals.data(), ahead * job.out_normals_stride);
  }
}

// Full blocks from `begin` (or from the first 64-byte-aligned vertex, streaming), partial blocks at either end.
// The two loops differ only in the constant `stream`, so each inlines its block with no per-store test.
template <class Isa, SkinningMethod method>
void skin_blocks(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  const Isa isa(job);
  const std::size_t aligned = first_streaming_vertex<Isa>(job, begin, end);
  const bool stream = aligned < end;
  std::size_t i = begin;
  if (stream) {
    if (aligned > begin) skin_partial_block<Isa, method>(job, isa, begin, aligned - begin);
    for (i = aligned; i + Isa::width <= end; i += Isa::width) {
      prefetch_inputs<Isa::width, true>(job, i);
      skin_block<Isa, method>(job, isa, i, true);
    }
  } else {
    for (; i + Isa::width <= end; i += Isa::width) {
      prefetch_inputs<Isa::width, false>(job, i);
      skin_block<Isa, method>(job, isa, i, false);
    }
  }
  if (i < end) skin_partial_block<Isa, method>(job, isa, i, end - i);
  if (stream) Isa::fence();
}

template <class Isa>
void skin_lbs_blocks(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_blocks<Isa, SkinningMethod::lbs>(job, begin, end);
}

template <class Isa>
void skin_dqs_blocks(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept {
  skin_blocks<Isa, SkinningMethod::dqs>(job, begin, end);
}

}  // namespace
}  // namespace deform::detail
