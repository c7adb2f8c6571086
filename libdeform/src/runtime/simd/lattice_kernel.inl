// The lattice evaluation kernel, included once per instruction set (lattice_evaluate_portable.cpp, _avx2.cpp,
// _avx512.cpp and, on aarch64, _neon.cpp, each compiled with its own flags). Everything here has internal linkage, so
// the copies never meet at link time; the includer defines DEFORM_KERNEL_ENTRY, the name of its one exported entry
// point.
//
// 16 vertices at once (one block of the binding), structure of arrays: loops over the 16 lanes around scalar code,
// which the compiler vectorises (lanes.hpp; four xmm registers per lane vector for the portable copy on x86-64, two
// ymm under AVX2, one zmm under AVX-512). Per block: the Bernstein basis of each axis from (u, v, w), then the
// contraction Σ_k B_k(w) Σ_j B_j(v) Σ_i B_i(u) P_ijk, each control point broadcast once per lane loop. The degrees
// are template parameters where they are equal and at most 6 (and for every B-spline): then the lane loops enclose
// fixed-length loops over the points, unrolled, and the sums stay in registers. Other degrees loop over the points
// outside and over the lanes inside, with the sums in memory: the same arithmetic, slower.
// B-spline blocks first convert their cell's 4×4×4 B-spline points into the equivalent tricubic Bézier points
// (uniform cubic B-spline → Bézier, per axis), then run the same Bézier contraction. Bézier lattices of degree 1 to
// 3 take the innermost sum, over u, in power form instead (PowerRow).
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "lanes.hpp"
#include "lattice_kernel.hpp"

namespace {

constexpr int lanes = 16;
using Lane16 = Lanes<lanes>;
static_assert(deform::LatticeBinding::block_size == lanes);
constexpr int max_n = deform::max_bezier_degree + 1;

// The bases of a block, per axis and per lane: values B_i,n(t) and, with normals, derivatives dB_i,n/dt.
struct BlockBasis {
  Lane16 u;  // the parameter itself, for rows in power form (PowerRow)
  Lane16 bu[max_n], bv[max_n], bw[max_n];
  Lane16 du[max_n], dv[max_n], dw[max_n];
};

// B_0..N,N(t) in b[0..N] by the triangle of de Casteljau's recurrence and, with Normals, the derivatives in d[0..N]
// from the degree N − 1 basis (B'_i,N = N·(B_i−1,N−1 − B_i,N−1)). One lane's worth, for the lane loops of basis().
template <int N, bool Normals>
inline void bernstein(float t, float* b, float* d) {
  const float s = 1.0f - t;
  float lower[N];
  b[0] = 1.0f;
  DEFORM_UNROLL
  for (int r = 1; r <= N; ++r) {
    if (r == N && Normals)
      for (int i = 0; i < N; ++i) lower[i] = b[i];
    float saved = 0.0f;
    DEFORM_UNROLL
    for (int i = 0; i < r; ++i) {
      const float tmp = b[i];
      b[i] = mul_add(s, tmp, saved);
      saved = t * tmp;
    }
    b[r] = saved;
  }
  if constexpr (Normals) {
    const float fn = static_cast<float>(N);
    d[0] = lower[0] * -fn;
    for (int i = 1; i < N; ++i) d[i] = (lower[i - 1] - lower[i]) * fn;
    d[N] = lower[N - 1] * fn;
  }
}

// The basis of one axis for the block: b[i] lane l = B_i,n(t lane l), and with Normals its derivative in d. N = 0:
// the degree is `runtime_n`; the same recurrence with the lane loops innermost.
template <int N, bool Normals>
inline void basis(int runtime_n, const Lane16& t, Lane16* b, Lane16* d) {
  if constexpr (N > 0) {
    (void)runtime_n;
    for (int lane = 0; lane < lanes; ++lane) {
      float bl[N + 1], dl[N + 1];
      bernstein<N, Normals>(t[lane], bl, dl);
      for (int i = 0; i <= N; ++i) b[i][lane] = bl[i];
      if constexpr (Normals)
        for (int i = 0; i <= N; ++i) d[i][lane] = dl[i];
    }
  } else {
    const int n = runtime_n;  // >= 1
    Lane16 s, saved, lower[max_n];
    for (int lane = 0; lane < lanes; ++lane) s[lane] = 1.0f - t[lane], b[0][lane] = 1.0f;
    for (int r = 1; r <= n; ++r) {
      if (r == n && Normals)
        for (int i = 0; i < n; ++i) lower[i] = b[i];
      saved = Lane16::filled(0.0f);
      for (int i = 0; i < r; ++i)
        for (int lane = 0; lane < lanes; ++lane) {
          const float tmp = b[i][lane];
          b[i][lane] = mul_add(s[lane], tmp, saved[lane]);
          saved[lane] = t[lane] * tmp;
        }
      b[r] = saved;
    }
    if constexpr (Normals) {
      const float fn = static_cast<float>(n);
      for (int lane = 0; lane < lanes; ++lane) d[0][lane] = lower[0][lane] * -fn, d[n][lane] = lower[n - 1][lane] * fn;
      for (int i = 1; i < n; ++i)
        for (int lane = 0; lane < lanes; ++lane) d[i][lane] = (lower[i - 1][lane] - lower[i][lane]) * fn;
    }
  }
}

// When a Jacobian's normal is degenerate (bezier_block; the GPU shader decides alike): the Jacobian's second singular
// value below degenerate_normal times the largest control point coordinate P. Derivatives summed from points of size
// P carry about 2·degree·6e-8·P of rounding (2e-6·P at degree 16), so a lattice collapsed to a point or onto a line
// leaves a second singular value below that, of no direction; a lattice of any thickness above 1e-5 of its
// coordinates has its normals. The second singular value is measured as |cof(J)·m| / (|J|·|m|) (|J|² the sum of the
// squared columns), the test done squared and without a division.
constexpr float degenerate_normal = 1e-5f;

// (degenerate_normal · the largest coordinate of `count` points, taken from `origin`)².
inline float noise_floor2(const glm::vec3* points, std::size_t count, glm::vec3 origin = glm::vec3(0.0f)) {
  float largest = 0.0f;
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 p = glm::abs(points[i] - origin);
    largest = std::max(largest, std::max(p.x, std::max(p.y, p.z)));
  }
  return degenerate_normal * degenerate_normal * largest * largest;
}

// Per lane: Q = Σ_k B_k(w) Σ_j B_j(v) Σ_i B_i(u) P_ijk and, with normals, its derivatives ∂Q/∂u, ∂Q/∂v, ∂Q/∂w.
template <bool Normals>
struct BlockSums {
  Lane16 q[3];
  Lane16 du[Normals ? 3 : 1], dv[Normals ? 3 : 1], dw[Normals ? 3 : 1];
};

// Bézier lattices of degree 1 to 3 along u evaluate each row of points in power form: Σ_i B_i,L(u) P_i = Σ_i c_i u^i
// with c_i = C(L, i) Δ^i P_0 (forward differences), by Horner's rule, and its derivative Σ_i (i + 1) c_i+1 u^i
// likewise: 2L − 1 multiply-adds per coordinate where the Bernstein sums take 2(L + 1) (tricubic with normals: the u
// stage, two thirds of the block's arithmetic, from 384 to 240 per lane; 15-22% off the kernel,
// docs/performance.md). The coefficients are made once per call. Horner's rounding is about ε (|P_0| + Σ_i>0 |c_i|),
// the differences bounded by (3^L − 1) times the row's extent: at degree 3, within the 1e-5 relative tolerance the
// kernel is held to; not above it, where they grow as 3^L. B-spline lattices keep the Bernstein sums
// (bspline_blocks).
template <int L>
constexpr bool power_rows = L >= 1 && L <= 3;

// Per row (a fixed (j, k)), the value coefficients c_0..c_L then the derivative's d_0..d_L−1.
template <int L>
struct PowerRow {
  glm::vec3 c[L + 1], d[L];
};

// `rows` rows of L + 1 points each (i-fastest) into power form, unrolled: about 15 vector operations a row at degree
// 3 (a loop with the binomials computed in it cost the built-in character's frame 7%).
template <int L>
inline void to_power_rows(const glm::vec3* points, int rows, PowerRow<L>* out) {
  constexpr float binomial[4][4] = {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};
  for (int r = 0; r < rows; ++r) {
    glm::vec3 diff[L + 1];
    DEFORM_UNROLL
    for (int i = 0; i <= L; ++i) diff[i] = points[(L + 1) * r + i];
    DEFORM_UNROLL
    for (int i = 0; i <= L; ++i) {
      out[r].c[i] = binomial[L][i] * diff[0];
      DEFORM_UNROLL
      for (int t = 0; t < L - i; ++t) diff[t] = diff[t + 1] - diff[t];
    }
    DEFORM_UNROLL
    for (int i = 0; i < L; ++i) out[r].d[i] = static_cast<float>(i + 1) * out[r].c[i + 1];
  }
}

// One lane's row sum Σ_i B_i(u) P_i (r[0..2]) and, with Normals, its u derivative (r[3..5]), for row j of a slice:
// from the row's Bézier points and the block's basis, or (power_rows) from its PowerRow by Horner's rule.
template <int L, bool Normals>
DEFORM_ALWAYS_INLINE inline void row_sums(const glm::vec3* slice, int j, const BlockBasis& basis, int lane, float* r) {
  const glm::vec3* row = slice + (L + 1) * j;
  for (int c = 0; c < 6; ++c) r[c] = 0.0f;
  DEFORM_UNROLL
  for (int i = 0; i <= L; ++i) {
    const float bu = basis.bu[i][lane];
    r[0] = mul_add(bu, row[i].x, r[0]);
    r[1] = mul_add(bu, row[i].y, r[1]);
    r[2] = mul_add(bu, row[i].z, r[2]);
    if constexpr (Normals) {
      const float du = basis.du[i][lane];
      r[3] = mul_add(du, row[i].x, r[3]);
      r[4] = mul_add(du, row[i].y, r[4]);
      r[5] = mul_add(du, row[i].z, r[5]);
    }
  }
}

template <int L, bool Normals>
DEFORM_ALWAYS_INLINE inline void row_sums(const PowerRow<L>* slice, int j, const BlockBasis& basis, int lane,
                                          float* r) {
  const PowerRow<L>& row = slice[j];
  const float u = basis.u[lane];
  if constexpr (!Normals) r[3] = r[4] = r[5] = 0.0f;
  r[0] = row.c[L].x, r[1] = row.c[L].y, r[2] = row.c[L].z;
  DEFORM_UNROLL
  for (int i = L - 1; i >= 0; --i) {
    r[0] = mul_add(r[0], u, row.c[i].x);
    r[1] = mul_add(r[1], u, row.c[i].y);
    r[2] = mul_add(r[2], u, row.c[i].z);
  }
  if constexpr (Normals) {
    r[3] = row.d[L - 1].x, r[4] = row.d[L - 1].y, r[5] = row.d[L - 1].z;
    DEFORM_UNROLL
    for (int i = L - 2; i >= 0; --i) {
      r[3] = mul_add(r[3], u, row.d[i].x);
      r[4] = mul_add(r[4], u, row.d[i].y);
      r[5] = mul_add(r[5], u, row.d[i].z);
    }
  }
}

// Slice k of a block's points: (l + 1) × (m + 1) Bézier points, or m + 1 PowerRows.
inline const glm::vec3* slice_at(const glm::vec3* points, int l, int m, int k) {
  return points + (l + 1) * (m + 1) * k;
}
template <int L>
const PowerRow<L>* slice_at(const PowerRow<L>* rows, int, int m, int k) {
  return rows + (m + 1) * k;
}

// How add_slice loops over the lanes with the degrees known at compile time, chosen per copy by measurement (AMD EPYC,
// GCC 12). Per slice: one lane loop around all of the slice's points (fixed-length loops, unrolled), the sums in
// registers. Per row: one lane loop per row of the slice, the row's sums in registers and the slice's in memory. When
// a lane vector is several registers, the compiler loads and broadcasts every point a lane loop reads once, before
// it: a tricubic slice's 48 broadcasts no longer fit in the AVX2 registers and are spilled, which made the per-slice
// loop 15% slower than the per-row one there; the portable copy (SSE2) measured the other way round, 10% faster per
// slice. Under AVX-512 a lane vector is one register, the lane loop a single pass.
#if defined(__AVX2__) && !defined(__AVX512F__)
constexpr bool lane_loop_per_row = true;
#else
constexpr bool lane_loop_per_row = false;
#endif

// Adds slice k, the (l + 1) × (m + 1) points from `slice` (i-fastest), to the sums: Σ_j B_j(v) Σ_i B_i(u) P_ijk times
// B_k(w) (and the derivatives). L, M: the degrees when known at compile time, else 0 (then l, m).
template <int L, int M, bool Normals, class Rows>
inline void add_slice(Rows slice, int l, int m, int k, const BlockBasis& basis, BlockSums<Normals>& sums) {
  if constexpr (L > 0 && M > 0 && !lane_loop_per_row) {
    (void)l, (void)m;
    for (int lane = 0; lane < lanes; ++lane) {
      float x = 0.0f, y = 0.0f, z = 0.0f, vx = 0.0f, vy = 0.0f, vz = 0.0f, ux = 0.0f, uy = 0.0f, uz = 0.0f;
      DEFORM_UNROLL
      for (int j = 0; j <= M; ++j) {
        float r[6];
        row_sums<L, Normals>(slice, j, basis, lane, r);
        const float rx = r[0], ry = r[1], rz = r[2], rdx = r[3], rdy = r[4], rdz = r[5];
        const float bv = basis.bv[j][lane];
        x = mul_add(bv, rx, x);
        y = mul_add(bv, ry, y);
        z = mul_add(bv, rz, z);
        if constexpr (Normals) {
          const float dv = basis.dv[j][lane];
          vx = mul_add(dv, rx, vx);
          vy = mul_add(dv, ry, vy);
          vz = mul_add(dv, rz, vz);
          ux = mul_add(bv, rdx, ux);
          uy = mul_add(bv, rdy, uy);
          uz = mul_add(bv, rdz, uz);
        }
      }
      const float bw = basis.bw[k][lane];
      sums.q[0][lane] = mul_add(bw, x, sums.q[0][lane]);
      sums.q[1][lane] = mul_add(bw, y, sums.q[1][lane]);
      sums.q[2][lane] = mul_add(bw, z, sums.q[2][lane]);
      if constexpr (Normals) {
        const float dw = basis.dw[k][lane];
        sums.dw[0][lane] = mul_add(dw, x, sums.dw[0][lane]);
        sums.dw[1][lane] = mul_add(dw, y, sums.dw[1][lane]);
        sums.dw[2][lane] = mul_add(dw, z, sums.dw[2][lane]);
        sums.dv[0][lane] = mul_add(bw, vx, sums.dv[0][lane]);
        sums.dv[1][lane] = mul_add(bw, vy, sums.dv[1][lane]);
        sums.dv[2][lane] = mul_add(bw, vz, sums.dv[2][lane]);
        sums.du[0][lane] = mul_add(bw, ux, sums.du[0][lane]);
        sums.du[1][lane] = mul_add(bw, uy, sums.du[1][lane]);
        sums.du[2][lane] = mul_add(bw, uz, sums.du[2][lane]);
      }
    }
  } else {
    // Σ_j B_j(v) · row sum (x, y, z), and with normals Σ_j B'_j(v) · row sum and Σ_j B_j(v) · row derivative sum.
    const int l1 = L > 0 ? L + 1 : l + 1, m1 = M > 0 ? M + 1 : m + 1;
    alignas(64) float s[3][lanes] = {}, sv[3][lanes] = {}, su[3][lanes] = {};
    for (int j = 0; j < m1; ++j) {
      if constexpr (L > 0) {
        // One lane loop around the row's points, its sums in registers.
        for (int lane = 0; lane < lanes; ++lane) {
          float r[6];
          row_sums<L, Normals>(slice, j, basis, lane, r);
          const float rx = r[0], ry = r[1], rz = r[2], rdx = r[3], rdy = r[4], rdz = r[5];
          const float bv = basis.bv[j][lane];
          s[0][lane] = mul_add(bv, rx, s[0][lane]);
          s[1][lane] = mul_add(bv, ry, s[1][lane]);
          s[2][lane] = mul_add(bv, rz, s[2][lane]);
          if constexpr (Normals) {
            const float dv = basis.dv[j][lane];
            sv[0][lane] = mul_add(dv, rx, sv[0][lane]);
            sv[1][lane] = mul_add(dv, ry, sv[1][lane]);
            sv[2][lane] = mul_add(dv, rz, sv[2][lane]);
            su[0][lane] = mul_add(bv, rdx, su[0][lane]);
            su[1][lane] = mul_add(bv, rdy, su[1][lane]);
            su[2][lane] = mul_add(bv, rdz, su[2][lane]);
          }
        }
      } else {
        // A lane loop per point, the row's sums in memory.
        const glm::vec3* row = slice + l1 * j;
        alignas(64) float r[3][lanes] = {}, rd[3][lanes] = {};
        for (int i = 0; i < l1; ++i) {
          const float x = row[i].x, y = row[i].y, z = row[i].z;
          for (int lane = 0; lane < lanes; ++lane) {
            const float bu = basis.bu[i][lane];
            r[0][lane] = mul_add(bu, x, r[0][lane]);
            r[1][lane] = mul_add(bu, y, r[1][lane]);
            r[2][lane] = mul_add(bu, z, r[2][lane]);
            if constexpr (Normals) {
              const float du = basis.du[i][lane];
              rd[0][lane] = mul_add(du, x, rd[0][lane]);
              rd[1][lane] = mul_add(du, y, rd[1][lane]);
              rd[2][lane] = mul_add(du, z, rd[2][lane]);
            }
          }
        }
        for (int lane = 0; lane < lanes; ++lane) {
          const float bv = basis.bv[j][lane];
          for (int c = 0; c < 3; ++c) {
            s[c][lane] = mul_add(bv, r[c][lane], s[c][lane]);
            if constexpr (Normals) {
              sv[c][lane] = mul_add(basis.dv[j][lane], r[c][lane], sv[c][lane]);
              su[c][lane] = mul_add(bv, rd[c][lane], su[c][lane]);
            }
          }
        }
      }
    }
    for (int lane = 0; lane < lanes; ++lane) {
      const float bw = basis.bw[k][lane];
      for (int c = 0; c < 3; ++c) {
        sums.q[c][lane] = mul_add(bw, s[c][lane], sums.q[c][lane]);
        if constexpr (Normals) {
          sums.dw[c][lane] = mul_add(basis.dw[k][lane], s[c][lane], sums.dw[c][lane]);
          sums.dv[c][lane] = mul_add(bw, sv[c][lane], sums.dv[c][lane]);
          sums.du[c][lane] = mul_add(bw, su[c][lane], sums.du[c][lane]);
        }
      }
    }
  }
}

// One block of a Bézier volume with (L+1, M+1, N+1) points (0 = runtime degree from `degree`), points i-fastest.
// `base` is added to the positions (the B-spline path evaluates relative to its cell, for precision).
template <int L, int M, int N, bool Normals, class Rows>
inline void bezier_block(const deform::detail::KernelArgs& a, std::size_t block, Rows points, glm::ivec3 degree,
                         glm::vec3 base, float noise2) {
  const int l = L > 0 ? L : degree.x, m = M > 0 ? M : degree.y, n = N > 0 ? N : degree.z;
  const std::size_t first = block * lanes;
  const deform::LatticeBinding& bind = *a.binding;
  BlockBasis b;
  if constexpr (std::is_same_v<Rows, const glm::vec3*>)
    basis<L, Normals>(l, Lane16::load(bind.u.data() + first), b.bu, b.du);
  else b.u = Lane16::load(bind.u.data() + first);
  basis<M, Normals>(m, Lane16::load(bind.v.data() + first), b.bv, b.dv);
  basis<N, Normals>(n, Lane16::load(bind.w.data() + first), b.bw, b.dw);

  BlockSums<Normals> sums;
  for (Lane16& q : sums.q) q = Lane16::filled(0.0f);
  if constexpr (Normals)
    for (int c = 0; c < 3; ++c) sums.du[c] = sums.dv[c] = sums.dw[c] = Lane16::filled(0.0f);
  for (int k = 0; k <= n; ++k) add_slice<L, M, Normals>(slice_at(points, l, m, k), l, m, k, b, sums);

  const std::uint32_t* vertex = bind.vertices.data() + first;
  const float* weight = a.weights ? a.weights + first : nullptr;
  if constexpr (Normals) {
    // m = G·n (G = binding.normal_basis · normals_in_to_binding), then n' = m.x (Qv × Qw) + m.y (Qw × Qu) +
    // m.z (Qu × Qv): cofactor(J)·m, the inverse transpose up to the positive factor det(J); normalised. Padding
    // lanes read a harmless (0, 0, 1).
    alignas(64) float in[3][lanes], out[3][lanes];
    for (int lane = 0; lane < lanes; ++lane) {
      const glm::vec3 nrm =
          vertex[lane] != deform::LatticeBinding::no_vertex ? a.normals_in[vertex[lane]] : glm::vec3(0.0f, 0.0f, 1.0f);
      in[0][lane] = nrm.x, in[1][lane] = nrm.y, in[2][lane] = nrm.z;
    }
    const glm::mat3& g = a.normal_basis;
    const glm::mat3& o = a.jacobian_offset;  // added to (Qu, Qv, Qw)
    const Lane16 *qu = sums.du, *qv = sums.dv, *qw = sums.dw;
    for (int lane = 0; lane < lanes; ++lane) {
      const float ix = in[0][lane], iy = in[1][lane], iz = in[2][lane];
      const float mx = ix * g[0][0] + iy * g[1][0] + iz * g[2][0];
      const float my = ix * g[0][1] + iy * g[1][1] + iz * g[2][1];
      const float mz = ix * g[0][2] + iy * g[1][2] + iz * g[2][2];
      const float ux = qu[0][lane] + o[0][0], uy = qu[1][lane] + o[0][1], uz = qu[2][lane] + o[0][2];
      const float vx = qv[0][lane] + o[1][0], vy = qv[1][lane] + o[1][1], vz = qv[2][lane] + o[1][2];
      const float wx = qw[0][lane] + o[2][0], wy = qw[1][lane] + o[2][1], wz = qw[2][lane] + o[2][2];
      const float nx = mx * (vy * wz - vz * wy) + my * (wy * uz - wz * uy) + mz * (uy * vz - uz * vy);
      const float ny = mx * (vz * wx - vx * wz) + my * (wz * ux - wx * uz) + mz * (uz * vx - ux * vz);
      const float nz = mx * (vx * wy - vy * wx) + my * (wx * uy - wy * ux) + mz * (ux * vy - uy * vx);
      const float length2 = nx * nx + ny * ny + nz * nz;
      const float inverse_length = 1.0f / std::sqrt(length2);
      const float rx = nx * inverse_length, ry = ny * inverse_length, rz = nz * inverse_length;
      // A degenerate Jacobian (a lattice collapsed to a point, onto a line, or nearly: degenerate_normal) has no
      // normal to give: the input normal is kept. Selected on the lanes, not tested per vertex in the scatter below:
      // that loop was a tenth of the kernel.
      const float scale2 = ux * ux + uy * uy + uz * uz + vx * vx + vy * vy + vz * vz + wx * wx + wy * wy + wz * wz;
      const float floor2 = noise2 * scale2 * (mx * mx + my * my + mz * mz);
      constexpr float largest = 3.40282347e38f;
      const bool usable =
          length2 > floor2 && std::abs(rx) <= largest && std::abs(ry) <= largest && std::abs(rz) <= largest;
      out[0][lane] = usable ? rx : ix, out[1][lane] = usable ? ry : iy, out[2][lane] = usable ? rz : iz;
    }
    if (weight) {
      // A displacement field's normals: the input moved toward the deformed normal by the lane's weight.
      for (int lane = 0; lane < lanes; ++lane) {
        const float w = weight[lane], ix = in[0][lane], iy = in[1][lane], iz = in[2][lane];
        const float bx = ix + w * (out[0][lane] - ix), by = iy + w * (out[1][lane] - iy),
                    bz = iz + w * (out[2][lane] - iz);
        const float length2 = bx * bx + by * by + bz * bz;
        const bool keep = !(length2 > 1e-12f);
        const float inverse_length = 1.0f / std::sqrt(keep ? 1.0f : length2);  // one division, not three
        out[0][lane] = keep ? ix : bx * inverse_length;
        out[1][lane] = keep ? iy : by * inverse_length;
        out[2][lane] = keep ? iz : bz * inverse_length;
      }
    }
    for (int lane = 0; lane < lanes; ++lane)
      if (vertex[lane] != deform::LatticeBinding::no_vertex)
        a.normals_out[vertex[lane]] = glm::vec3(out[0][lane], out[1][lane], out[2][lane]);
  }
  if (!a.positions) return;
  if (weight) {
    for (int lane = 0; lane < lanes; ++lane)
      if (vertex[lane] != deform::LatticeBinding::no_vertex)
        a.positions[vertex[lane]] +=
            weight[lane] * glm::vec3(sums.q[0][lane] + base.x, sums.q[1][lane] + base.y, sums.q[2][lane] + base.z);
    return;
  }
  for (int lane = 0; lane < lanes; ++lane)
    if (vertex[lane] != deform::LatticeBinding::no_vertex)
      a.positions[vertex[lane]] =
          glm::vec3(sums.q[0][lane] + base.x, sums.q[1][lane] + base.y, sums.q[2][lane] + base.z);
}

template <int L, int M, int N, bool Normals>
void bezier_blocks(const deform::detail::KernelArgs& a) {
  const glm::ivec3 degree = a.binding->point_counts - 1;
  const glm::ivec3 counts = a.binding->point_counts;
  const float noise2 = Normals ? noise_floor2(a.control_points, std::size_t(counts.x * counts.y * counts.z)) : 0.0f;
  if constexpr (power_rows<L>) {
    PowerRow<L> rows[(M + 1) * (N + 1)];
    to_power_rows<L>(a.control_points, (M + 1) * (N + 1), rows);
    for (std::size_t b = a.begin_block; b < a.end_block; ++b)
      bezier_block<L, M, N, Normals, const PowerRow<L>*>(a, b, rows, degree, glm::vec3(0.0f), noise2);
  } else {
    for (std::size_t b = a.begin_block; b < a.end_block; ++b)
      bezier_block<L, M, N, Normals, const glm::vec3*>(a, b, a.control_points, degree, glm::vec3(0.0f), noise2);
  }
}

// Uniform cubic B-spline segment → cubic Bézier: b0 = (p0 + 4p1 + p2)/6, b1 = (2p1 + p2)/3, b2 = (p1 + 2p2)/3,
// b3 = (p1 + 4p2 + p3)/6 (Böhm's conversion), applied along each axis of the cell in turn.
inline void bspline_to_bezier(const glm::vec3* p, std::ptrdiff_t stride, glm::vec3* out, std::ptrdiff_t out_stride) {
  const glm::vec3 p0 = p[0], p1 = p[stride], p2 = p[2 * stride], p3 = p[3 * stride];
  out[0] = (p0 + 4.0f * p1 + p2) * (1.0f / 6.0f);
  out[out_stride] = (2.0f * p1 + p2) * (1.0f / 3.0f);
  out[2 * out_stride] = (p1 + 2.0f * p2) * (1.0f / 3.0f);
  out[3 * out_stride] = (p1 + 4.0f * p2 + p3) * (1.0f / 6.0f);
}

// The cell's Bézier points relative to `base` (one of its own points), so that the float sums and, above all, the
// derivatives (differences of nearby points) keep their precision far from the origin.
inline void cell_to_bezier(const glm::vec3* points, glm::ivec3 counts, std::uint32_t first, glm::vec3* bezier,
                           glm::vec3& base) {
  const std::ptrdiff_t sv = counts.x, sw = static_cast<std::ptrdiff_t>(counts.x) * counts.y;
  base = points[first + 1 + sv + sw];
  glm::vec3 local[4], a[64], b[64];
  for (int k = 0; k < 4; ++k)  // along u
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 4; ++i) local[i] = points[first + i + j * sv + k * sw] - base;
      bspline_to_bezier(local, 1, a + 4 * (j + 4 * k), 1);
    }
  for (int k = 0; k < 4; ++k)  // along v
    for (int i = 0; i < 4; ++i) bspline_to_bezier(a + i + 16 * k, 4, b + i + 16 * k, 4);
  for (int j = 0; j < 4; ++j)  // along w
    for (int i = 0; i < 4; ++i) bspline_to_bezier(b + i + 4 * j, 16, bezier + i + 4 * j, 16);
}

template <bool Normals>
void bspline_blocks(const deform::detail::KernelArgs& a) {
  glm::vec3 bezier[64], base(0.0f);
  // A cell's Bézier points are taken from one of its points (cell_to_bezier): within twice the lattice's extent
  // from its first point, which bounds them for every cell at once.
  const glm::ivec3 counts = a.binding->point_counts;
  const float noise2 =
      Normals ? 4.0f * noise_floor2(a.control_points, std::size_t(counts.x * counts.y * counts.z), a.control_points[0])
              : 0.0f;
  std::uint32_t cell = deform::LatticeBinding::no_vertex;
  for (std::size_t b = a.begin_block; b < a.end_block; ++b) {
    const std::uint32_t first = a.binding->block_first_point[b];
    // Not in power form (power_rows): the cells change every block or two, and converting each cost more than the
    // block saved (1,500 points: 1.4× slower).
    if (first != cell) cell_to_bezier(a.control_points, a.binding->point_counts, cell = first, bezier, base);
    bezier_block<3, 3, 3, Normals, const glm::vec3*>(a, b, bezier, glm::ivec3(3), base, noise2);
  }
}

template <bool Normals>
void dispatch(const deform::detail::KernelArgs& a) {
  if (a.binding->kind == deform::LatticeKind::bspline) return bspline_blocks<Normals>(a);
  const glm::ivec3 d = a.binding->point_counts - 1;
  if (d.x == d.y && d.y == d.z) switch (d.x) {
      case 1: return bezier_blocks<1, 1, 1, Normals>(a);
      case 2: return bezier_blocks<2, 2, 2, Normals>(a);
      case 3: return bezier_blocks<3, 3, 3, Normals>(a);
      case 4: return bezier_blocks<4, 4, 4, Normals>(a);
      case 5: return bezier_blocks<5, 5, 5, Normals>(a);
      case 6: return bezier_blocks<6, 6, 6, Normals>(a);
      default: break;
    }
  bezier_blocks<0, 0, 0, Normals>(a);
}

}  // namespace

namespace deform::detail {

void DEFORM_KERNEL_ENTRY(const KernelArgs& args) {
  if (args.normals_out) dispatch<true>(args);
  else dispatch<false>(args);
}

}  // namespace deform::detail
