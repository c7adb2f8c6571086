// The DirectDeltaMushJob kernel, included once per instruction set (ddm_portable.cpp, _avx2.cpp, _avx512.cpp,
// _neon.cpp, _simd128.cpp, each compiled with its own flags). Everything here has internal linkage but the one entry
// point the includer names with DEFORM_DDM_ENTRY, so the copies never meet at link time.
//
// Points are taken in the binding's blocks of 16 (DirectDeltaMushLanes, packed at bind time), one lane each, as loops
// over the lanes around scalar code that the compiler vectorises (lanes.hpp). Per block: the bones' matrices applied to
// its lanes' smoothed moments, round after round as the binding lays them out (a shared round reads one bone's matrix
// for every lane, the others copy each lane's; the moments are already in lanes), give C (3×3) and the sums for each
// position, relative to where its strongest bone carries its rest point (the anchor), so that no float sum cancels the
// model's distance from the origin. Then the start rotation from the strongest bone's matrix (its columns normalised,
// quat_cast written with selects), a fixed number of Newton steps towards the rotation nearest C (nearest_rotation's
// step, selects for its branches), further steps only for the lanes that still turn, and the outputs (normals only
// when asked for). Each lane computes alone in an order its block fixes, so a point's result does not depend on the
// range it is run in. The lanes past the binding, and points without a rotation to find, hold C = I and the identity,
// which never steps.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ddm_kernel.hpp"
#include "lanes.hpp"

namespace {

constexpr int lanes = 16;
using L = Lanes<lanes>;

struct Block {
  L c[9];             // C column-major: c[3 · column + row]
  L a[9];             // the strongest bone's 3×3, column-major: the start rotation's source
  L q[4];             // the rotation (w, x, y, z)
  L anchor[3];        // where the strongest bone carries the rest point
  L sum[3];           // Σ A p + d ψ
  L centroid[3];      // Σ p
  L inverse;          // 1 / Σ ψ
  L offset[3];        // in_positions − rest (0 without in_positions)
  L normal[3];        // in_normals (0 without them)
  L turned;           // 1 where a rotation is found, else 0 (the point stays put)
  int moving[lanes];  // per lane: its last step turned by at least 1e-3 rad (ddm_settled)
};

// The start rotation: the strongest bone's columns normalised, the quaternion glm::quat_cast would give (the largest
// of 4w², 4x², 4y², 4z² chosen by selects; scaled by 4·that component, which the normalisation removes, so no square
// root for it), normalised; the identity where a column is zero or anything is not finite.
inline void start_rotations(Block& b) noexcept {
  constexpr float largest = std::numeric_limits<float>::max();
  for (int l = 0; l < lanes; ++l) {
    float m[9];
    DEFORM_UNROLL
    for (int k = 0; k < 9; ++k) m[k] = b.a[k][l];
    bool ok = true;
    DEFORM_UNROLL
    for (int col = 0; col < 3; ++col) {
      const float x = m[3 * col], y = m[3 * col + 1], z = m[3 * col + 2];
      const float length = std::sqrt(x * x + y * y + z * z);
      ok = ok & (length > 0.0f);
      const float inverse = 1.0f / (length > 0.0f ? length : 1.0f);
      m[3 * col] = x * inverse, m[3 * col + 1] = y * inverse, m[3 * col + 2] = z * inverse;
    }
    // m[3 · column + row]; glm's m[column][row].
    const float m00 = m[0], m01 = m[1], m02 = m[2], m10 = m[3], m11 = m[4], m12 = m[5], m20 = m[6], m21 = m[7],
                m22 = m[8];
    const float fw = m00 + m11 + m22, fx = m00 - m11 - m22, fy = m11 - m00 - m22, fz = m22 - m00 - m11;
    const float dx = m12 - m21, dy = m20 - m02, dz = m01 - m10;
    const float sxy = m01 + m10, sxz = m20 + m02, syz = m12 + m21;
    // glm's order of comparisons: w, then x, y, z each if strictly larger.
    float big = fw, w = fw + 1.0f, x = dx, y = dy, z = dz;
    const bool bx = fx > big;
    big = bx ? fx : big;
    w = bx ? dx : w, x = bx ? fx + 1.0f : x, y = bx ? sxy : y, z = bx ? sxz : z;
    const bool by = fy > big;
    big = by ? fy : big;
    w = by ? dy : w, x = by ? sxy : x, y = by ? fy + 1.0f : y, z = by ? syz : z;
    const bool bz = fz > big;
    w = bz ? dz : w, x = bz ? sxz : x, y = bz ? syz : y, z = bz ? fz + 1.0f : z;
    const float n2 = w * w + x * x + y * y + z * z;
    const bool good = ok & (n2 > 0.0f) & (n2 <= largest);
    const float inverse = 1.0f / std::sqrt(good ? n2 : 1.0f);
    b.q[0][l] = good ? w * inverse : 1.0f, b.q[1][l] = good ? x * inverse : 0.0f;
    b.q[2][l] = good ? y * inverse : 0.0f, b.q[3][l] = good ? z * inverse : 0.0f;
  }
}

// One of nearest_rotation's steps (direct_delta_mush.cpp says what it is) in every lane whose `active` is set, written
// with selects: the Newton step where H is positive definite, else the gradient step; none where neither can be taken.
// Sets b.moving to whether the lane stepped by at least 1e-3 rad (ddm_settled).
inline void newton_step(Block& b, const int* active) noexcept {
  constexpr float largest = std::numeric_limits<float>::max();
  for (int l = 0; l < lanes; ++l) {
    const float w = b.q[0][l], x = b.q[1][l], y = b.q[2][l], z = b.q[3][l];
    // R = mat3_cast(q), r[column][row].
    const float r00 = 1.0f - 2.0f * (y * y + z * z), r01 = 2.0f * (x * y + w * z), r02 = 2.0f * (x * z - w * y);
    const float r10 = 2.0f * (x * y - w * z), r11 = 1.0f - 2.0f * (x * x + z * z), r12 = 2.0f * (y * z + w * x);
    const float r20 = 2.0f * (x * z + w * y), r21 = 2.0f * (y * z - w * x), r22 = 1.0f - 2.0f * (x * x + y * y);
    // S = Rᵀ C: s[i][j] (column i, row j) = R's column j · C's column i.
    float sm[3][3];
    DEFORM_UNROLL
    for (int i = 0; i < 3; ++i) {
      const float c0 = b.c[3 * i][l], c1 = b.c[3 * i + 1][l], c2 = b.c[3 * i + 2][l];
      sm[i][0] = r00 * c0 + r01 * c1 + r02 * c2;
      sm[i][1] = r10 * c0 + r11 * c1 + r12 * c2;
      sm[i][2] = r20 * c0 + r21 * c1 + r22 * c2;
    }
    const float gx = sm[1][2] - sm[2][1], gy = sm[2][0] - sm[0][2], gz = sm[0][1] - sm[1][0];
    const float trace = sm[0][0] + sm[1][1] + sm[2][2];
    const float h00 = trace - sm[0][0], h11 = trace - sm[1][1], h22 = trace - sm[2][2];
    const float h01 = -0.5f * (sm[0][1] + sm[1][0]), h02 = -0.5f * (sm[0][2] + sm[2][0]);
    const float h12 = -0.5f * (sm[1][2] + sm[2][1]);
    const float k00 = h11 * h22 - h12 * h12, k01 = h02 * h12 - h01 * h22, k02 = h01 * h12 - h02 * h11;
    const float k11 = h00 * h22 - h02 * h02, k12 = h01 * h02 - h00 * h12, k22 = h00 * h11 - h01 * h01;
    const float det = h00 * k00 + h01 * k01 + h02 * k02;
    const bool newton = (h00 > 0.0f) & (k22 > 0.0f) & (det > 0.0f);
    const float scale = trace < 0.0f ? -trace : trace;
    const bool can = newton | (scale > 0.0f);
    // Both steps computed, one kept; one reciprocal.
    const float kx = k00 * gx + k01 * gy + k02 * gz, ky = k01 * gx + k11 * gy + k12 * gz;
    const float kz = k02 * gx + k12 * gy + k22 * gz;
    const float gradient_divisor = can ? scale : 1.0f;
    const float inverse = 1.0f / (newton ? det : gradient_divisor);
    const float ox = (newton ? kx : gx) * inverse, oy = (newton ? ky : gy) * inverse, oz = (newton ? kz : gz) * inverse;
    const float angle2 = ox * ox + oy * oy + oz * oz;
    const bool step = (active[l] != 0) & can & (angle2 > 0.0f) & (angle2 <= largest);
    // At most a radian a step: (1, ω/2) scaled by 1/|ω| past a radian, which is (|ω|, ω/2) once normalised.
    const float s = std::sqrt(angle2 > 1.0f ? angle2 : 1.0f);
    const float hx = 0.5f * ox, hy = 0.5f * oy, hz = 0.5f * oz;
    // q · (s, h), normalised.
    const float nw = s * w - x * hx - y * hy - z * hz, nx = s * x + w * hx + y * hz - z * hy;
    const float ny = s * y + w * hy + z * hx - x * hz, nz = s * z + w * hz + x * hy - y * hx;
    const float norm = 1.0f / std::sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
    b.q[0][l] = step ? nw * norm : w, b.q[1][l] = step ? nx * norm : x;
    b.q[2][l] = step ? ny * norm : y, b.q[3][l] = step ? nz * norm : z;
    b.moving[l] = int(step & !(angle2 < deform::detail::ddm_settled));
  }
}

// A whole block's points in[0..lanes) read into three lanes' values.
inline void load(L* v, const glm::vec3* in) noexcept {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  const float* f = reinterpret_cast<const float*>(in);
  for (int l = 0; l < lanes; ++l) v[0][l] = f[3 * l], v[1][l] = f[3 * l + 1], v[2][l] = f[3 * l + 2];
}

// Lanes [low, high) of three lanes' values written as points out[low..high): a whole block as one loop of a fixed
// count, which the vectoriser takes as interleaved stores.
inline void store(const L* v, glm::vec3* out, int low, int high) noexcept {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  if (low == 0 && high == lanes) {
    float* f = reinterpret_cast<float*>(out);
    for (int l = 0; l < lanes; ++l) f[3 * l] = v[0][l], f[3 * l + 1] = v[1][l], f[3 * l + 2] = v[2][l];
    return;
  }
  for (int l = low; l < high; ++l) out[l] = glm::vec3(v[0][l], v[1][l], v[2][l]);
}

// One round of a block's influences (DirectDeltaMushLanes): C += A P + d pᵀ, q += A p + d ψ (d = M u − anchor), Σ p,
// Σ ψ, with each lane's moments from `moment` (10 × lanes floats) and its matrix (3×4, m[4 · column + row] less the
// last row) from `one` (a shared round: one bone's, read once) or `each` (a lane's own). An empty slot's moments are
// zero, so it adds exact zeros.
template <bool shared>
inline void accumulate(L* acc, const float* one, const L* each, const float* moment, const L* rest,
                       const L* anchor) noexcept {
  for (int l = 0; l < lanes; ++l) {
    float m[16];
    DEFORM_UNROLL
    for (int k = 0; k < 12; ++k) m[k + k / 3] = shared ? one[k] : each[k][l];
    const float xx = moment[l], xy = moment[lanes + l], xz = moment[2 * lanes + l], yy = moment[3 * lanes + l];
    const float yz = moment[4 * lanes + l], zz = moment[5 * lanes + l], px = moment[6 * lanes + l];
    const float py = moment[7 * lanes + l], pz = moment[8 * lanes + l], psi = moment[9 * lanes + l];
    const float ux = rest[0][l], uy = rest[1][l], uz = rest[2][l];
    float d[3];
    DEFORM_UNROLL
    for (int r = 0; r < 3; ++r)
      d[r] = mul_add(m[r], ux, mul_add(m[4 + r], uy, mul_add(m[8 + r], uz, m[12 + r]))) - anchor[r][l];
    DEFORM_UNROLL
    for (int r = 0; r < 3; ++r) {
      const float a0 = m[r], a1 = m[4 + r], a2 = m[8 + r];
      acc[r][l] += mul_add(a0, xx, mul_add(a1, xy, mul_add(a2, xz, d[r] * px)));
      acc[3 + r][l] += mul_add(a0, xy, mul_add(a1, yy, mul_add(a2, yz, d[r] * py)));
      acc[6 + r][l] += mul_add(a0, xz, mul_add(a1, yz, mul_add(a2, zz, d[r] * pz)));
      acc[9 + r][l] += mul_add(a0, px, mul_add(a1, py, mul_add(a2, pz, d[r] * psi)));
    }
    acc[12][l] += px, acc[13][l] += py, acc[14][l] += pz, acc[15][l] += psi;
  }
}

// Each lane's outputs: position = anchor + (Σ A p + d ψ − R Σ p) / Σ ψ + R (in − rest), or the rest point (plus the
// offset) where no rotation is found; normal = R in, normalised (zero stays zero).
struct Outputs {
  L position[3];
  L normal[3];
};
template <bool normals>
inline void outputs(const Block& b, const L* rest, Outputs& o) noexcept {
  for (int l = 0; l < lanes; ++l) {
    const float w = b.q[0][l], x = b.q[1][l], y = b.q[2][l], z = b.q[3][l];
    const float r00 = 1.0f - 2.0f * (y * y + z * z), r01 = 2.0f * (x * y + w * z), r02 = 2.0f * (x * z - w * y);
    const float r10 = 2.0f * (x * y - w * z), r11 = 1.0f - 2.0f * (x * x + z * z), r12 = 2.0f * (y * z + w * x);
    const float r20 = 2.0f * (x * z + w * y), r21 = 2.0f * (y * z - w * x), r22 = 1.0f - 2.0f * (x * x + y * y);
    const float cx = b.centroid[0][l], cy = b.centroid[1][l], cz = b.centroid[2][l];
    const float inverse = b.inverse[l];
    const bool turned = b.turned[l] != 0.0f;
    const float tx = b.anchor[0][l] + (b.sum[0][l] - (r00 * cx + r10 * cy + r20 * cz)) * inverse;
    const float ty = b.anchor[1][l] + (b.sum[1][l] - (r01 * cx + r11 * cy + r21 * cz)) * inverse;
    const float tz = b.anchor[2][l] + (b.sum[2][l] - (r02 * cx + r12 * cy + r22 * cz)) * inverse;
    const float ux = b.offset[0][l], uy = b.offset[1][l], uz = b.offset[2][l];
    o.position[0][l] = (turned ? tx : rest[0][l]) + (r00 * ux + r10 * uy + r20 * uz);
    o.position[1][l] = (turned ? ty : rest[1][l]) + (r01 * ux + r11 * uy + r21 * uz);
    o.position[2][l] = (turned ? tz : rest[2][l]) + (r02 * ux + r12 * uy + r22 * uz);
    if (!normals) continue;
    const float ix = b.normal[0][l], iy = b.normal[1][l], iz = b.normal[2][l];
    const float nx = r00 * ix + r10 * iy + r20 * iz, ny = r01 * ix + r11 * iy + r21 * iz;
    const float nz = r02 * ix + r12 * iy + r22 * iz;
    const float length2 = nx * nx + ny * ny + nz * nz;
    const float scale = length2 > 0.0f ? 1.0f / std::sqrt(length2 > 0.0f ? length2 : 1.0f) : 0.0f;
    o.normal[0][l] = nx * scale, o.normal[1][l] = ny * scale, o.normal[2][l] = nz * scale;
  }
}

}  // namespace

namespace deform::detail {

void DEFORM_DDM_ENTRY(const DdmKernelArgs& args) noexcept {
  const DirectDeltaMushBinding& bd = *args.binding;
  const DirectDeltaMushLanes& pack = bd.lanes;
  static_assert(DirectDeltaMushLanes::width == lanes && sizeof(DirectDeltaMushMoments) == 10 * sizeof(float));
  static_assert(sizeof(glm::mat4) == 16 * sizeof(float));
  const std::size_t n = bd.point_count();
  // The palette read as flat floats: a matrix is 16, column-major (m[4 · column + row]). (A cast, not
  // &palette[0][0][0]: an empty palette is a null pointer, not an element to bind.)
  const float* matrix_floats = reinterpret_cast<const float*>(args.palette);
  // The binding's blocks that meet [begin, end): each computed whole, its lanes in the range written.
  for (std::size_t block = args.begin / lanes; block * lanes < args.end; ++block) {
    const std::size_t block_begin = block * lanes;
    const int count = int(std::min<std::size_t>(lanes, n - block_begin));
    const int low = int(std::max(args.begin, block_begin) - block_begin);
    const int high = int(std::min(args.end, block_begin + lanes) - block_begin);
    Block b;
    L rest[3];
    // Per lane: its strongest bone (its row's first influence) for the anchor and the start; lanes past the binding
    // have none.
    std::uint32_t first[lanes], influences[lanes];
    if (count == lanes) {
      // A whole block: loops of a fixed count, which the vectoriser takes as interleaved loads.
      const std::uint32_t* offsets = bd.offsets.data() + block_begin;
      for (int l = 0; l < lanes; ++l) first[l] = offsets[l], influences[l] = offsets[l + 1] - offsets[l];
      load(rest, bd.rest.data() + block_begin);
      if (args.in_positions != nullptr) {
        load(b.offset, args.in_positions + block_begin);
        for (int l = 0; l < lanes; ++l)
          for (int c = 0; c < 3; ++c) b.offset[c][l] -= rest[c][l];
      } else {
        for (int c = 0; c < 3; ++c) b.offset[c] = L::filled(0.0f);
      }
      if (args.in_normals != nullptr) load(b.normal, args.in_normals + block_begin);
      else
        for (int c = 0; c < 3; ++c) b.normal[c] = L::filled(0.0f);
    } else {
      for (int l = 0; l < lanes; ++l) {
        const std::size_t i = block_begin + std::size_t(l < count ? l : 0);
        first[l] = bd.offsets[i];
        influences[l] = l < count ? bd.offsets[i + 1] - bd.offsets[i] : 0;
        const glm::vec3 u = bd.rest[i];
        rest[0][l] = u.x, rest[1][l] = u.y, rest[2][l] = u.z;
        const glm::vec3 d = args.in_positions != nullptr ? args.in_positions[i] - u : glm::vec3(0.0f);
        b.offset[0][l] = d.x, b.offset[1][l] = d.y, b.offset[2][l] = d.z;
        const glm::vec3 nv = args.in_normals != nullptr ? args.in_normals[i] : glm::vec3(0.0f);
        b.normal[0][l] = nv.x, b.normal[1][l] = nv.y, b.normal[2][l] = nv.z;
      }
    }
    // The anchor, and the start rotation's matrix, from each lane's strongest bone (the identity where it has none):
    // selected from the block's shared rounds' bones where one of them is it, else copied from the palette.
    const std::uint32_t round_begin = pack.rounds[block], round_end = pack.rounds[block + 1];
    const std::uint32_t shared = pack.shared[block];
    const std::uint32_t* start = pack.start.data() + block * lanes;
    L strongest[12];  // its 3×4, m[k + k / 3]
    for (int l = 0; l < lanes; ++l) {
      DEFORM_UNROLL
      for (int k = 0; k < 12; ++k) strongest[k][l] = k % 4 == 0 ? 1.0f : 0.0f;
    }
    for (std::uint32_t j = 0; j < shared; ++j) {
      const float* m = matrix_floats + 16 * std::size_t(pack.bones[std::size_t(round_begin + j) * lanes]);
      float one[12];
      DEFORM_UNROLL
      for (int k = 0; k < 12; ++k) one[k] = m[k + k / 3];
      for (int l = 0; l < lanes; ++l) {
        const bool chosen = start[l] == j;
        DEFORM_UNROLL
        for (int k = 0; k < 12; ++k) strongest[k][l] = chosen ? one[k] : strongest[k][l];
      }
    }
    for (int l = 0; l < lanes; ++l)
      if (influences[l] > 0 && start[l] == DirectDeltaMushLanes::none) {
        const float* m = matrix_floats + 16 * std::size_t(bd.bones[first[l]]);
        for (int k = 0; k < 12; ++k) strongest[k][l] = m[k + k / 3];
      }
    for (int l = 0; l < lanes; ++l) {
      const bool has = influences[l] > 0;
      const float ux = rest[0][l], uy = rest[1][l], uz = rest[2][l];
      DEFORM_UNROLL
      for (int k = 0; k < 9; ++k) b.a[k][l] = strongest[k][l];
      DEFORM_UNROLL
      for (int r = 0; r < 3; ++r) {
        const float at =
            mul_add(strongest[r][l], ux,
                    mul_add(strongest[3 + r][l], uy, mul_add(strongest[6 + r][l], uz, strongest[9 + r][l])));
        b.anchor[r][l] = has ? at : 0.0f;
      }
    }
    // The block's rounds (DirectDeltaMushLanes): the shared ones read one matrix; the others copy each lane's.
    L acc[16];  // C column-major (9), q (3), Σ p (3), Σ ψ
    for (int k = 0; k < 16; ++k) acc[k] = L::filled(0.0f);
    const std::uint32_t shared_end = round_begin + shared;
    for (std::uint32_t r = round_begin; r < round_end; ++r) {
      const float* moment = pack.moments.data() + std::size_t(r) * 10 * lanes;
      const std::uint16_t* bone = pack.bones.data() + std::size_t(r) * lanes;
      if (r < shared_end) {
        const float* m = matrix_floats + 16 * std::size_t(bone[0]);
        float one[12];
        DEFORM_UNROLL
        for (int k = 0; k < 12; ++k) one[k] = m[k + k / 3];
        accumulate<true>(acc, one, nullptr, moment, rest, b.anchor);
      } else {
        L each[12];
        for (int l = 0; l < lanes; ++l) {
          const float* m = matrix_floats + 16 * std::size_t(bone[l]);
          DEFORM_UNROLL
          for (int k = 0; k < 12; ++k) each[k][l] = m[k + k / 3];
        }
        accumulate<false>(acc, nullptr, each, moment, rest, b.anchor);
      }
    }
    // C −= q (Σ p / ψ)ᵀ where Σ ψ > 0; else C = I, the start the identity, and the point stays put.
    for (int l = 0; l < lanes; ++l) {
      const float psi = acc[15][l];
      const bool turned = psi > 0.0f;
      const float inverse = 1.0f / (turned ? psi : 1.0f);
      const float p[3] = {acc[12][l] * inverse, acc[13][l] * inverse, acc[14][l] * inverse};
      DEFORM_UNROLL
      for (int k = 0; k < 9; ++k) {
        b.c[k][l] = turned ? acc[k][l] - acc[9 + k % 3][l] * p[k / 3] : (k % 4 == 0 ? 1.0f : 0.0f);
        b.a[k][l] = turned ? b.a[k][l] : (k % 4 == 0 ? 1.0f : 0.0f);
      }
      DEFORM_UNROLL
      for (int r = 0; r < 3; ++r) {
        b.sum[r][l] = acc[9 + r][l], b.centroid[r][l] = acc[12 + r][l];
        b.anchor[r][l] = turned ? b.anchor[r][l] : 0.0f;
      }
      b.inverse[l] = turned ? inverse : 0.0f;
      b.turned[l] = turned ? 1.0f : 0.0f;
    }
    start_rotations(b);
    int all[lanes];
    for (int l = 0; l < lanes; ++l) all[l] = 1;
    for (int step = 0; step < ddm_fixed_steps; ++step) newton_step(b, all);
    // Lanes still turning go on by themselves, up to nearest_rotation's 16 steps.
    for (int step = ddm_fixed_steps; step < 16; ++step) {
      int any = 0;
      for (int l = 0; l < lanes; ++l) any |= b.moving[l];
      if (any == 0) break;
      int active[lanes];
      for (int l = 0; l < lanes; ++l) active[l] = b.moving[l];
      newton_step(b, active);
    }
    Outputs o;
    if (args.out_normals != nullptr) outputs<true>(b, rest, o);
    else outputs<false>(b, rest, o);
    store(o.position, args.out_positions + block_begin, low, high);
    if (args.out_normals != nullptr) store(o.normal, args.out_normals + block_begin, low, high);
    if (args.out_rotations != nullptr)
      for (int l = low; l < high; ++l)
        args.out_rotations[block_begin + std::size_t(l)] = glm::quat(b.q[0][l], b.q[1][l], b.q[2][l], b.q[3][l]);
  }
}

}  // namespace deform::detail

// --- the reduced form's kernel (DirectDeltaMushReducedJob; the header says what it computes) ---
//
// The same blocks of 16 points and rounds as the full kernel (the reduced binding's lanes, which carry no moments: a
// slot's ψ and p̃ʳ come from the rows through its influence). Per block: each lane's strongest bone's matrix M₀ and
// quaternion q₀ (from a shared round where it is one, else copied), the anchor c = M₀ r; per round, for each lane,
// Σ ψ (M r − c), Σ A p̃ʳ, Σ p̃ʳ and Σ ±ψ q; then the rotation of the blended quaternion and the outputs, as the scalar
// equations in the header. No iteration: every lane does the same work. A lane without influences gives its input
// point back, its normal normalised and the identity.

namespace {

struct ReducedSums {
  L blend[3];     // Σ ψ (M r − c)
  L moved[3];     // Σ A p̃ʳ
  L centroid[3];  // Σ p̃ʳ
  L q[4];         // Σ ±ψ q (x, y, z, w)
};

// One round: `one`/`one_q` (a shared round: one bone's 3×4, m[k + k / 3], and quaternion x, y, z, w) or
// `each`/`each_q` (a bone per lane); each lane's p̃ʳ and ψ from `moment` (4 × lanes floats: x, y, z, ψ; zero for
// an empty slot, which so adds exact zeros).
template <bool shared>
inline void accumulate_reduced(ReducedSums& s, const float* one, const float* one_q, const L* each, const L* each_q,
                               const float* moment, const L* rest, const L* anchor, const L* q0) noexcept {
  for (int l = 0; l < lanes; ++l) {
    float m[16], q[4];
    DEFORM_UNROLL
    for (int k = 0; k < 12; ++k) m[k + k / 3] = shared ? one[k] : each[k][l];
    DEFORM_UNROLL
    for (int k = 0; k < 4; ++k) q[k] = shared ? one_q[k] : each_q[k][l];
    const float px = moment[l], py = moment[lanes + l], pz = moment[2 * lanes + l], psi = moment[3 * lanes + l];
    const float ux = rest[0][l], uy = rest[1][l], uz = rest[2][l];
    DEFORM_UNROLL
    for (int r = 0; r < 3; ++r) {
      const float d = mul_add(m[r], ux, mul_add(m[4 + r], uy, mul_add(m[8 + r], uz, m[12 + r]))) - anchor[r][l];
      s.blend[r][l] = mul_add(psi, d, s.blend[r][l]);
      s.moved[r][l] += mul_add(m[r], px, mul_add(m[4 + r], py, m[8 + r] * pz));
    }
    s.centroid[0][l] += px, s.centroid[1][l] += py, s.centroid[2][l] += pz;
    // Aligned with the strongest bone's quaternion as dual quaternion skinning aligns them.
    const float dot = q[0] * q0[0][l] + q[1] * q0[1][l] + q[2] * q0[2][l] + q[3] * q0[3][l];
    const float w = dot < 0.0f ? -psi : psi;
    DEFORM_UNROLL
    for (int k = 0; k < 4; ++k) s.q[k][l] = mul_add(w, q[k], s.q[k][l]);
  }
}

// Each lane's outputs from its sums: R the rotation of q (not normalised first: R = I + (2 / |q|²)(w [v]× + [v]×²));
// position = c + ((Σ ψ (M r − c) + (Σ A p̃ʳ − R Σ p̃ʳ)) + R (x − r)), which a lane without influences (its sums zero,
// its q (0, 0, 0, 1), its anchor x and its offset 0) gives as x exactly; normal = R n normalised (zero stays zero).
template <bool normals>
inline void reduced_outputs(const ReducedSums& s, const L* anchor, const L* offset, const L* normal,
                            Outputs& o) noexcept {
  for (int l = 0; l < lanes; ++l) {
    // (A lane without influences has q = (0, 0, 0, 1) from the start: R = I. No select here: GCC would split the loop
    // into two paths for the constant one, and not vectorise it.)
    const float qx = s.q[0][l], qy = s.q[1][l], qz = s.q[2][l], qw = s.q[3][l];
    const float k = 2.0f / (qx * qx + qy * qy + qz * qz + qw * qw);
    const float xx = k * qx * qx, yy = k * qy * qy, zz = k * qz * qz;
    const float xy = k * qx * qy, xz = k * qx * qz, yz = k * qy * qz;
    const float wx = k * qw * qx, wy = k * qw * qy, wz = k * qw * qz;
    // Columns.
    const float r00 = 1.0f - yy - zz, r01 = xy + wz, r02 = xz - wy;
    const float r10 = xy - wz, r11 = 1.0f - xx - zz, r12 = yz + wx;
    const float r20 = xz + wy, r21 = yz - wx, r22 = 1.0f - xx - yy;
    const float cx = s.centroid[0][l], cy = s.centroid[1][l], cz = s.centroid[2][l];
    const float ux = offset[0][l], uy = offset[1][l], uz = offset[2][l];
    const float rc[3] = {r00 * cx + r10 * cy + r20 * cz, r01 * cx + r11 * cy + r21 * cz,
                         r02 * cx + r12 * cy + r22 * cz};
    const float ru[3] = {r00 * ux + r10 * uy + r20 * uz, r01 * ux + r11 * uy + r21 * uz,
                         r02 * ux + r12 * uy + r22 * uz};
    const float px = anchor[0][l] + ((s.blend[0][l] + (s.moved[0][l] - rc[0])) + ru[0]);
    const float py = anchor[1][l] + ((s.blend[1][l] + (s.moved[1][l] - rc[1])) + ru[1]);
    const float pz = anchor[2][l] + ((s.blend[2][l] + (s.moved[2][l] - rc[2])) + ru[2]);
    o.position[0][l] = px, o.position[1][l] = py, o.position[2][l] = pz;
    if constexpr (normals) {
      const float ix = normal[0][l], iy = normal[1][l], iz = normal[2][l];
      const float nx = r00 * ix + r10 * iy + r20 * iz, ny = r01 * ix + r11 * iy + r21 * iz;
      const float nz = r02 * ix + r12 * iy + r22 * iz;
      const float length2 = nx * nx + ny * ny + nz * nz;
      const float scale = length2 > 0.0f ? 1.0f / std::sqrt(length2 > 0.0f ? length2 : 1.0f) : 0.0f;
      o.normal[0][l] = nx * scale, o.normal[1][l] = ny * scale, o.normal[2][l] = nz * scale;
    }
  }
}

}  // namespace

namespace deform::detail {

void DEFORM_DDM_REDUCED_ENTRY(const DdmReducedKernelArgs& args) noexcept {
  const DirectDeltaMushReducedBinding& bd = *args.binding;
  const DirectDeltaMushLanes& pack = bd.lanes;
  const std::size_t n = bd.point_count();
  const float* matrix_floats = reinterpret_cast<const float*>(args.palette);
  const DualQuat* dq = args.dual_quats;
  for (std::size_t block = args.begin / lanes; block * lanes < args.end; ++block) {
    const std::size_t block_begin = block * lanes;
    const int count = int(std::min<std::size_t>(lanes, n - block_begin));
    const int low = int(std::max(args.begin, block_begin) - block_begin);
    const int high = int(std::min(args.end, block_begin + lanes) - block_begin);
    L rest[3], input[3], normal[3];
    std::uint32_t first[lanes];
    L has;  // 1 where the point has influences, else 0
    if (count == lanes) {
      const std::uint32_t* offsets = bd.offsets.data() + block_begin;
      for (int l = 0; l < lanes; ++l) first[l] = offsets[l], has[l] = offsets[l + 1] != offsets[l] ? 1.0f : 0.0f;
      load(rest, bd.rest.data() + block_begin);
      if (args.in_positions != nullptr) load(input, args.in_positions + block_begin);
      else
        for (int c = 0; c < 3; ++c) input[c] = rest[c];
      if (args.in_normals != nullptr) load(normal, args.in_normals + block_begin);
      else
        for (int c = 0; c < 3; ++c) normal[c] = L::filled(0.0f);
    } else {
      for (int l = 0; l < lanes; ++l) {
        const std::size_t i = block_begin + std::size_t(l < count ? l : 0);
        first[l] = bd.offsets[i];
        has[l] = l < count && bd.offsets[i + 1] != bd.offsets[i] ? 1.0f : 0.0f;
        const glm::vec3 u = bd.rest[i];
        rest[0][l] = u.x, rest[1][l] = u.y, rest[2][l] = u.z;
        const glm::vec3 x = args.in_positions != nullptr ? args.in_positions[i] : u;
        input[0][l] = x.x, input[1][l] = x.y, input[2][l] = x.z;
        const glm::vec3 nv = args.in_normals != nullptr ? args.in_normals[i] : glm::vec3(0.0f);
        normal[0][l] = nv.x, normal[1][l] = nv.y, normal[2][l] = nv.z;
      }
    }
    // Each lane's strongest bone: its 3×4 and quaternion (the identity where it has none), selected from the shared
    // rounds' bones where one of them is it, else copied.
    const std::uint32_t round_begin = pack.rounds[block], round_end = pack.rounds[block + 1];
    const std::uint32_t shared = pack.shared[block];
    const std::uint32_t* start = pack.start.data() + block * lanes;
    L strongest[12], q0[4];
    for (int l = 0; l < lanes; ++l) {
      DEFORM_UNROLL
      for (int k = 0; k < 12; ++k) strongest[k][l] = k % 4 == 0 ? 1.0f : 0.0f;
      DEFORM_UNROLL
      for (int k = 0; k < 4; ++k) q0[k][l] = k == 3 ? 1.0f : 0.0f;
    }
    for (std::uint32_t j = 0; j < shared; ++j) {
      const std::uint16_t bone = pack.bones[std::size_t(round_begin + j) * lanes];
      const float* m = matrix_floats + 16 * std::size_t(bone);
      const glm::quat& qb = dq[bone].real;
      float one[12];
      DEFORM_UNROLL
      for (int k = 0; k < 12; ++k) one[k] = m[k + k / 3];
      const float one_q[4] = {qb.x, qb.y, qb.z, qb.w};
      for (int l = 0; l < lanes; ++l) {
        const bool chosen = start[l] == j;
        DEFORM_UNROLL
        for (int k = 0; k < 12; ++k) strongest[k][l] = chosen ? one[k] : strongest[k][l];
        DEFORM_UNROLL
        for (int k = 0; k < 4; ++k) q0[k][l] = chosen ? one_q[k] : q0[k][l];
      }
    }
    for (int l = 0; l < lanes; ++l)
      if (has[l] != 0.0f && start[l] == DirectDeltaMushLanes::none) {
        const std::uint16_t bone = bd.bones[first[l]];
        const float* m = matrix_floats + 16 * std::size_t(bone);
        for (int k = 0; k < 12; ++k) strongest[k][l] = m[k + k / 3];
        const glm::quat& qb = dq[bone].real;
        q0[0][l] = qb.x, q0[1][l] = qb.y, q0[2][l] = qb.z, q0[3][l] = qb.w;
      }
    L anchor[3];
    for (int l = 0; l < lanes; ++l) {
      const float ux = rest[0][l], uy = rest[1][l], uz = rest[2][l];
      DEFORM_UNROLL
      for (int r = 0; r < 3; ++r)
        anchor[r][l] = mul_add(strongest[r][l], ux,
                               mul_add(strongest[3 + r][l], uy, mul_add(strongest[6 + r][l], uz, strongest[9 + r][l])));
    }
    ReducedSums s;
    for (int c = 0; c < 3; ++c) s.blend[c] = s.moved[c] = s.centroid[c] = L::filled(0.0f);
    for (int c = 0; c < 3; ++c) s.q[c] = L::filled(0.0f);
    for (int l = 0; l < lanes; ++l) s.q[3][l] = has[l] != 0.0f ? 0.0f : 1.0f;
    const std::uint32_t shared_end = round_begin + shared;
    for (std::uint32_t r = round_begin; r < round_end; ++r) {
      const std::uint16_t* bone = pack.bones.data() + std::size_t(r) * lanes;
      const float* moment = pack.moments.data() + std::size_t(r) * 4 * lanes;
      if (r < shared_end) {
        const float* m = matrix_floats + 16 * std::size_t(bone[0]);
        const glm::quat& qb = dq[bone[0]].real;
        float one[12];
        DEFORM_UNROLL
        for (int k = 0; k < 12; ++k) one[k] = m[k + k / 3];
        const float one_q[4] = {qb.x, qb.y, qb.z, qb.w};
        accumulate_reduced<true>(s, one, one_q, nullptr, nullptr, moment, rest, anchor, q0);
      } else {
        L each[12], each_q[4];
        for (int l = 0; l < lanes; ++l) {
          const float* m = matrix_floats + 16 * std::size_t(bone[l]);
          DEFORM_UNROLL
          for (int k = 0; k < 12; ++k) each[k][l] = m[k + k / 3];
          const glm::quat& qb = dq[bone[l]].real;
          each_q[0][l] = qb.x, each_q[1][l] = qb.y, each_q[2][l] = qb.z, each_q[3][l] = qb.w;
        }
        accumulate_reduced<false>(s, nullptr, nullptr, each, each_q, moment, rest, anchor, q0);
      }
    }
    Outputs o;
    // The anchor and offset a lane without influences gives x back with (reduced_outputs).
    L offset[3];
    for (int l = 0; l < lanes; ++l) {
      const bool any = has[l] != 0.0f;
      DEFORM_UNROLL
      for (int c = 0; c < 3; ++c) {
        const float x = input[c][l];
        offset[c][l] = any ? x - rest[c][l] : 0.0f;
        anchor[c][l] = any ? anchor[c][l] : x;
      }
    }
    if (args.out_normals != nullptr) reduced_outputs<true>(s, anchor, offset, normal, o);
    else reduced_outputs<false>(s, anchor, offset, normal, o);
    store(o.position, args.out_positions + block_begin, low, high);
    if (args.out_normals != nullptr) store(o.normal, args.out_normals + block_begin, low, high);
    if (args.out_rotations != nullptr)
      for (int l = low; l < high; ++l)
        args.out_rotations[block_begin + std::size_t(l)] =
            has[l] != 0.0f ? glm::normalize(glm::quat(s.q[3][l], s.q[0][l], s.q[1][l], s.q[2][l]))
                           : glm::quat(1, 0, 0, 0);
  }
}

}  // namespace deform::detail
