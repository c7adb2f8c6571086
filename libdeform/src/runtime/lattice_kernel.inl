// The lattice evaluation kernel, included once per instruction set (lattice_evaluate.cpp: the baseline,
// lattice_evaluate_avx512.cpp: compiled with -mavx512f). Everything here has internal linkage, so the two copies never
// meet at link time; the includer defines DEFORM_KERNEL_ENTRY, the name of its one exported entry point.
//
// 16 vertices at once (one block of the binding), structure of arrays, GCC vector extensions (one zmm register per
// 16-float vector under AVX-512, four xmm otherwise). Per block: the Bernstein basis of each axis from (u, v, w),
// then the contraction Σ_k B_k(w) Σ_j B_j(v) Σ_i B_i(u) P_ijk, each control point broadcast once per block.
// B-spline blocks first convert their cell's 4×4×4 B-spline points into the equivalent tricubic Bézier points
// (uniform cubic B-spline → Bézier, per axis), then run the same Bézier contraction.
#include <cmath>
#include <cstring>

#include "lattice_kernel.hpp"

// The vectors never cross a non-inlined boundary between differently compiled code (internal linkage only), so GCC's
// note that a 64-byte vector argument changes the ABI without AVX-512 does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace {

typedef float Lanes __attribute__((vector_size(64)));
constexpr int lanes = 16;
static_assert(deform::LatticeBinding::block_size == lanes);

inline Lanes load(const float* p) {
  Lanes r;
  std::memcpy(&r, p, sizeof r);
  return r;
}

// B_0..n,n(t) in b[0..n] by the triangle of de Casteljau's recurrence; when `lower` is not null it receives the
// degree n − 1 basis first (for the derivative B'_i,n = n·(B_i−1,n−1 − B_i,n−1)).
template <int N>
inline void bernstein(int runtime_n, const Lanes& t, Lanes* b, Lanes* lower) {
  const int n = N > 0 ? N : runtime_n;
  const Lanes s = 1.0f - t;
  b[0] = s - s + 1.0f;
  for (int r = 1; r <= n; ++r) {
    if (r == n && lower)
      for (int i = 0; i < n; ++i) lower[i] = b[i];
    Lanes saved = s - s;
    for (int i = 0; i < r; ++i) {
      const Lanes tmp = b[i];
      b[i] = saved + s * tmp;
      saved = t * tmp;
    }
    b[r] = saved;
  }
}

template <int N>
inline void derivative(int runtime_n, const Lanes* lower, Lanes* d) {
  const int n = N > 0 ? N : runtime_n;
  const float fn = static_cast<float>(n);
  if (n == 1) {  // lower = {1}
    d[0] = lower[0] * -fn;
    d[1] = lower[0] * fn;
    return;
  }
  d[0] = lower[0] * -fn;
  for (int i = 1; i < n; ++i) d[i] = (lower[i - 1] - lower[i]) * fn;
  d[n] = lower[n - 1] * fn;
}

constexpr int max_n = deform::max_bezier_degree + 1;

// One block of a Bézier volume with (L+1, M+1, N+1) points (0 = runtime degree from `degree`), points i-fastest.
// `base` is added to the positions (the B-spline path evaluates relative to its cell, for precision).
template <int L, int M, int N, bool Normals>
inline void bezier_block(const deform::detail::KernelArgs& a, std::size_t block, const glm::vec3* points,
                         glm::ivec3 degree, glm::vec3 base) {
  const int l = L > 0 ? L : degree.x, m = M > 0 ? M : degree.y, n = N > 0 ? N : degree.z;
  const int nu = l + 1, nv = m + 1;
  const std::size_t first = block * lanes;
  const deform::LatticeBinding& bind = *a.binding;
  const Lanes u = load(bind.u.data() + first), v = load(bind.v.data() + first), w = load(bind.w.data() + first);

  Lanes bu[max_n], bv[max_n], bw[max_n];
  Lanes lu[max_n], lv[max_n], lw[max_n];
  Lanes du[max_n], dv[max_n], dw[max_n];
  bernstein<L>(l, u, bu, Normals ? lu : nullptr);
  bernstein<M>(m, v, bv, Normals ? lv : nullptr);
  bernstein<N>(n, w, bw, Normals ? lw : nullptr);
  if constexpr (Normals) {
    derivative<L>(l, lu, du);
    derivative<M>(m, lv, dv);
    derivative<N>(n, lw, dw);
  }

  const Lanes zero = u - u;
  Lanes qx = zero, qy = zero, qz = zero;
  Lanes ux = zero, uy = zero, uz = zero, vx = zero, vy = zero, vz = zero, wx = zero, wy = zero, wz = zero;
  for (int k = 0; k <= n; ++k) {
    Lanes sx = zero, sy = zero, sz = zero;
    Lanes svx = zero, svy = zero, svz = zero, sux = zero, suy = zero, suz = zero;
    for (int j = 0; j <= m; ++j) {
      const glm::vec3* row = points + nu * (j + nv * k);
      Lanes rx = zero, ry = zero, rz = zero, rdx = zero, rdy = zero, rdz = zero;
      for (int i = 0; i <= l; ++i) {
        rx += bu[i] * row[i].x;
        ry += bu[i] * row[i].y;
        rz += bu[i] * row[i].z;
        if constexpr (Normals) {
          rdx += du[i] * row[i].x;
          rdy += du[i] * row[i].y;
          rdz += du[i] * row[i].z;
        }
      }
      sx += bv[j] * rx;
      sy += bv[j] * ry;
      sz += bv[j] * rz;
      if constexpr (Normals) {
        svx += dv[j] * rx;
        svy += dv[j] * ry;
        svz += dv[j] * rz;
        sux += bv[j] * rdx;
        suy += bv[j] * rdy;
        suz += bv[j] * rdz;
      }
    }
    qx += bw[k] * sx;
    qy += bw[k] * sy;
    qz += bw[k] * sz;
    if constexpr (Normals) {
      wx += dw[k] * sx;
      wy += dw[k] * sy;
      wz += dw[k] * sz;
      vx += bw[k] * svx;
      vy += bw[k] * svy;
      vz += bw[k] * svz;
      ux += bw[k] * sux;
      uy += bw[k] * suy;
      uz += bw[k] * suz;
    }
  }

  const std::uint32_t* vertex = bind.vertices.data() + first;
  if constexpr (Normals) {
    // m = G·n (G = binding.normal_basis), then n' = m.x (Qv × Qw) + m.y (Qw × Qu) + m.z (Qu × Qv): cofactor(J)·m,
    // the inverse transpose up to the positive factor det(J); normalised. Padding lanes read a harmless (0, 0, 1).
    alignas(64) float in[3][lanes];
    for (int lane = 0; lane < lanes; ++lane) {
      const glm::vec3 nrm = vertex[lane] != deform::LatticeBinding::no_vertex ? a.normals_in[vertex[lane]]
                                                                             : glm::vec3(0.0f, 0.0f, 1.0f);
      in[0][lane] = nrm.x, in[1][lane] = nrm.y, in[2][lane] = nrm.z;
    }
    const glm::mat3& g = bind.normal_basis;
    const Lanes ix = load(in[0]), iy = load(in[1]), iz = load(in[2]);
    const Lanes mx = ix * g[0][0] + iy * g[1][0] + iz * g[2][0];
    const Lanes my = ix * g[0][1] + iy * g[1][1] + iz * g[2][1];
    const Lanes mz = ix * g[0][2] + iy * g[1][2] + iz * g[2][2];
    const Lanes nx = mx * (vy * wz - vz * wy) + my * (wy * uz - wz * uy) + mz * (uy * vz - uz * vy);
    const Lanes ny = mx * (vz * wx - vx * wz) + my * (wz * ux - wx * uz) + mz * (uz * vx - ux * vz);
    const Lanes nz = mx * (vx * wy - vy * wx) + my * (wx * uy - wy * ux) + mz * (ux * vy - uy * vx);
    const Lanes len2 = nx * nx + ny * ny + nz * nz;
    alignas(64) float out[4][lanes];
    std::memcpy(out[3], &len2, sizeof len2);
    for (int lane = 0; lane < lanes; ++lane) out[3][lane] = 1.0f / std::sqrt(out[3][lane]);  // vectorised
    const Lanes inv = load(out[3]);
    const Lanes ox = nx * inv, oy = ny * inv, oz = nz * inv;
    std::memcpy(out[0], &ox, sizeof ox);
    std::memcpy(out[1], &oy, sizeof oy);
    std::memcpy(out[2], &oz, sizeof oz);
    for (int lane = 0; lane < lanes; ++lane) {
      if (vertex[lane] == deform::LatticeBinding::no_vertex) continue;
      const glm::vec3 result(out[0][lane], out[1][lane], out[2][lane]);
      // A degenerate Jacobian (a collapsed lattice) has no normal to give: the input normal is kept.
      if (std::isfinite(result.x) && std::isfinite(result.y) && std::isfinite(result.z) && out[3][lane] < 1e30f)
        a.normals_out[vertex[lane]] = result;
      else
        a.normals_out[vertex[lane]] = glm::vec3(in[0][lane], in[1][lane], in[2][lane]);
    }
  }
  qx += base.x;
  qy += base.y;
  qz += base.z;
  alignas(64) float out[3][lanes];
  std::memcpy(out[0], &qx, sizeof qx);
  std::memcpy(out[1], &qy, sizeof qy);
  std::memcpy(out[2], &qz, sizeof qz);
  for (int lane = 0; lane < lanes; ++lane)
    if (vertex[lane] != deform::LatticeBinding::no_vertex)
      a.positions[vertex[lane]] = glm::vec3(out[0][lane], out[1][lane], out[2][lane]);
}

template <int L, int M, int N, bool Normals>
void bezier_blocks(const deform::detail::KernelArgs& a) {
  const glm::ivec3 degree = a.binding->point_counts - 1;
  for (std::size_t b = a.begin_block; b < a.end_block; ++b)
    bezier_block<L, M, N, Normals>(a, b, a.control_points, degree, glm::vec3(0.0f));
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
  std::uint32_t cell = deform::LatticeBinding::no_vertex;
  for (std::size_t b = a.begin_block; b < a.end_block; ++b) {
    const std::uint32_t first = a.binding->block_first_point[b];
    if (first != cell) cell_to_bezier(a.control_points, a.binding->point_counts, cell = first, bezier, base);
    bezier_block<3, 3, 3, Normals>(a, b, bezier, glm::ivec3(3), base);
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
