// DirectDeltaMushJob: per point, the bones' matrices applied to the point's smoothed moments, the rotation nearest the
// cross-covariance that gives, and the point carried by it (Le and Lewis 2019). Sums are taken relative to where the
// point's strongest bone carries its rest point, so that no float sum cancels the model's distance from the origin.
#include "deform/runtime/direct_delta_mush.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/portable.hpp"
#include "finite.hpp"

namespace deform {
namespace {

// The O(1) checks of run(): the binding's arrays sized consistently and the spans one per point.
Status shape_ok(const DirectDeltaMushJob& job) noexcept {
  const DirectDeltaMushBinding* b = job.binding;
  if (b == nullptr) return Status::failure("no binding");
  const std::size_t n = b->point_count();
  if (b->offsets.size() != n + 1 || b->moments.size() != b->bones.size())
    return Status::failure("binding is malformed: arrays differ in size");
  if (b->offsets.back() != b->bones.size())
    return Status::failure("binding is malformed: offsets do not end at the end");
  if (job.matrices.size() < b->bone_count) return Status::failure("palette is too small");
  if (job.out_positions.size() != n || (!job.in_positions.empty() && job.in_positions.size() != n))
    return Status::failure("positions are not one per point");
  if (job.in_normals.size() != job.out_normals.size() || (!job.in_normals.empty() && job.in_normals.size() != n))
    return Status::failure("normals are not one per point");
  if (!job.out_rotations.empty() && job.out_rotations.size() != n)
    return Status::failure("rotations are not one per point");
  return {};
}

// A unit quaternion near the 3×3 part of a bone matrix (its columns normalised; scale and shear only make it a start).
glm::quat start_rotation(const glm::mat3& a) noexcept {
  const float l0 = glm::length(a[0]), l1 = glm::length(a[1]), l2 = glm::length(a[2]);
  if (!(l0 > 0.0f && l1 > 0.0f && l2 > 0.0f)) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const glm::quat q = glm::normalize(glm::quat_cast(glm::mat3(a[0] / l0, a[1] / l1, a[2] / l2)));
  return finite(q) ? q : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
}

// nearest_rotation for a block of points at once, in structure-of-arrays form: the same steps, the same stopping rule
// per point (a point stops when its own step is below 1e-4 rad or cannot be taken, and then keeps its rotation while
// the others go on), written as one loop over the lanes with selects for branches. A point's result does not depend on
// the other points of its block. The step's division is a reciprocal times the cofactors (a rounding apart from
// nearest_rotation's). What it gains (measured: 10 to 20 % of the frame): the points' chains of dependent divisions,
// square roots and 3×3 products are independent and overlap; GCC 12 does not vectorise the loop yet (its
// if-conversion leaves the step's selects as branches), which a lane kernel per ISA would.
constexpr int rotation_block = 8;
struct RotationBlock {
  float c[9][rotation_block];  // C column-major: c[3 · column + row]
  float q[4][rotation_block];  // in: the start, out: the rotation (w, x, y, z)
};

void nearest_rotations(RotationBlock& block) noexcept {
  constexpr float largest = std::numeric_limits<float>::max();
  int active[rotation_block];
  for (int l = 0; l < rotation_block; ++l) active[l] = 1;
  for (int iteration = 0; iteration < 16; ++iteration) {
    int any = 0;
    for (int l = 0; l < rotation_block; ++l) {
      const float w = block.q[0][l], x = block.q[1][l], y = block.q[2][l], z = block.q[3][l];
      // R = mat3_cast(q), r[column][row].
      const float r00 = 1.0f - 2.0f * (y * y + z * z), r01 = 2.0f * (x * y + w * z), r02 = 2.0f * (x * z - w * y);
      const float r10 = 2.0f * (x * y - w * z), r11 = 1.0f - 2.0f * (x * x + z * z), r12 = 2.0f * (y * z + w * x);
      const float r20 = 2.0f * (x * z + w * y), r21 = 2.0f * (y * z - w * x), r22 = 1.0f - 2.0f * (x * x + y * y);
      float cc[9];
      DEFORM_UNROLL
      for (int k = 0; k < 9; ++k) cc[k] = block.c[k][l];
      // S = Rᵀ C: s[i][j] (column i, row j) = R's column j · C's column i.
      float sm[3][3];
      DEFORM_UNROLL
      for (int i = 0; i < 3; ++i) {
        const float c0 = cc[3 * i], c1 = cc[3 * i + 1], c2 = cc[3 * i + 2];
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
      const bool newton = (h00 > 0.0f) & (k22 > 0.0f) & (det > 0.0f);  // & not &&: no branches of its own
      const float scale = std::abs(trace);
      const bool can = newton | (scale > 0.0f);
      // Both steps computed, one kept.
      const float kx = k00 * gx + k01 * gy + k02 * gz, ky = k01 * gx + k11 * gy + k12 * gz;
      const float kz = k02 * gx + k12 * gy + k22 * gz;
      const float gradient_divisor = can ? scale : 1.0f;
      const float inverse = 1.0f / (newton ? det : gradient_divisor);
      const float ox = (newton ? kx : gx) * inverse, oy = (newton ? ky : gy) * inverse,
                  oz = (newton ? kz : gz) * inverse;
      const float angle2 = ox * ox + oy * oy + oz * oz;
      const bool step = (active[l] != 0) & can & (angle2 > 0.0f) & (angle2 <= largest);
      const float limit = 1.0f / std::sqrt(angle2 > 1.0f ? angle2 : 1.0f);  // at most a radian a step
      const float hx = 0.5f * limit * ox, hy = 0.5f * limit * oy, hz = 0.5f * limit * oz;
      // q · (1, h), normalised.
      const float nw = w - x * hx - y * hy - z * hz, nx = x + w * hx + y * hz - z * hy;
      const float ny = y + w * hy + z * hx - x * hz, nz = z + w * hz + x * hy - y * hx;
      const float norm = 1.0f / std::sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
      block.q[0][l] = step ? nw * norm : w, block.q[1][l] = step ? nx * norm : x;
      block.q[2][l] = step ? ny * norm : y, block.q[3][l] = step ? nz * norm : z;
      active[l] = int(step & !(angle2 < 1e-8f));
      any |= active[l];
    }
    if (any == 0) break;
  }
}

}  // namespace

glm::quat nearest_rotation(const glm::mat3& c, glm::quat q) noexcept {
  // Newton's method on f(R) = trace(Rᵀ C) over rotations R · exp([ω]×): with S = Rᵀ C, f grows by g · ω − ½ ωᵀ H ω,
  // g = (S₂₁ − S₁₂, S₀₂ − S₂₀, S₁₀ − S₀₁) and H = trace(S) I − (S + Sᵀ) / 2, positive definite near the maximum
  // (its eigenvalues are sums of two of C's singular values there). Where H is not (far from the maximum), a gradient
  // step of size |g| / |trace S| instead. Quadratic near the answer: from a bone's rotation, 2 to 4 steps.
  for (int iteration = 0; iteration < 16; ++iteration) {
    const glm::mat3 s = glm::transpose(glm::mat3_cast(q)) * c;
    const glm::vec3 g(s[1][2] - s[2][1], s[2][0] - s[0][2], s[0][1] - s[1][0]);
    const float trace = s[0][0] + s[1][1] + s[2][2];
    // H = trace(S) I − (S + Sᵀ) / 2, symmetric: its six entries, and its cofactors (H⁻¹ = cofactors / det).
    const float h00 = trace - s[0][0], h11 = trace - s[1][1], h22 = trace - s[2][2];
    const float h01 = -0.5f * (s[0][1] + s[1][0]), h02 = -0.5f * (s[0][2] + s[2][0]), h12 = -0.5f * (s[1][2] + s[2][1]);
    const float k00 = h11 * h22 - h12 * h12, k01 = h02 * h12 - h01 * h22, k02 = h01 * h12 - h02 * h11;
    const float k11 = h00 * h22 - h02 * h02, k12 = h01 * h02 - h00 * h12, k22 = h00 * h11 - h01 * h01;
    const float det = h00 * k00 + h01 * k01 + h02 * k02;
    glm::vec3 omega;
    // H positive definite (its leading minors positive): the Newton step; else a gradient step.
    if (h00 > 0.0f && k22 > 0.0f && det > 0.0f) {
      omega = glm::vec3(k00 * g.x + k01 * g.y + k02 * g.z, k01 * g.x + k11 * g.y + k12 * g.z,
                        k02 * g.x + k12 * g.y + k22 * g.z) /
              det;
    } else {
      const float scale = std::abs(trace);
      if (!(scale > 0.0f)) break;
      omega = g / scale;
    }
    const float angle2 = glm::dot(omega, omega);
    if (!(angle2 > 0.0f) || !std::isfinite(angle2)) break;
    // At most a radian a step; turned by the quaternion (1, ω/2) normalised (a turn of 2 atan(|ω|/2), |ω| to third
    // order: no trigonometry, and Newton's convergence kept).
    if (angle2 > 1.0f) omega /= std::sqrt(angle2);
    q = glm::normalize(q * glm::quat(1.0f, 0.5f * omega.x, 0.5f * omega.y, 0.5f * omega.z));
    // Quadratic convergence: after a step of 1e-4 the turn left is about 1e-8, below float rounding of the sums.
    if (angle2 < 1e-8f) break;
  }
  return q;
}

Status DirectDeltaMushJob::validate() const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  const DirectDeltaMushBinding& b = *binding;
  if (b.offsets[0] != 0) return Status::failure("binding is malformed: offsets do not ascend from 0");
  for (std::size_t i = 0; i < b.point_count(); ++i) {
    if (b.offsets[i + 1] < b.offsets[i]) return Status::failure("binding is malformed: offsets do not ascend from 0");
    if (!finite(b.rest[i])) return Status::failure("binding is not finite");
    float weight = 0.0f;
    for (std::uint32_t e = b.offsets[i]; e < b.offsets[i + 1]; ++e) weight += b.moments[e].w;
    if (b.offsets[i + 1] > b.offsets[i] && !(weight > 0.0f))
      return Status::failure("binding is malformed: a point's smoothed weights do not sum above 0");
  }
  for (std::size_t e = 0; e < b.influence_count(); ++e) {
    if (b.bones[e] >= b.bone_count) return Status::failure("binding is malformed: bone out of range");
    const DirectDeltaMushMoments& m = b.moments[e];
    for (const float v : {m.xx, m.xy, m.xz, m.yy, m.yz, m.zz, m.x, m.y, m.z, m.w})
      if (!std::isfinite(v)) return Status::failure("binding is not finite");
  }
  for (std::size_t j = 0; j < b.bone_count; ++j)
    if (!finite(matrices[j])) return Status::failure("palette matrix is not finite");
  return {};
}

Status DirectDeltaMushJob::run() const noexcept { return run(0, count()); }

Status DirectDeltaMushJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  if (begin > end || end > count()) return Status::failure("range outside the job");
  const DirectDeltaMushBinding& b = *binding;
  const glm::mat4* palette = matrices.data();
  // Blocks of points: each point's C and start rotation into the block (the lanes past the range, and points without
  // a rotation to find, hold the identity, which stops at once), the rotations found together, then each point's
  // outputs.
  for (std::size_t block_begin = begin; block_begin < end; block_begin += rotation_block) {
    const int lanes = int(std::min<std::size_t>(rotation_block, end - block_begin));
    RotationBlock block;
    glm::vec3 anchors[rotation_block], sums[rotation_block], centroids[rotation_block];
    float inverses[rotation_block];
    bool turned[rotation_block];
    for (int l = 0; l < rotation_block; ++l) {
      for (int k = 0; k < 9; ++k) block.c[k][l] = k % 4 == 0 ? 1.0f : 0.0f;
      block.q[0][l] = 1.0f, block.q[1][l] = 0.0f, block.q[2][l] = 0.0f, block.q[3][l] = 0.0f;
      turned[l] = false;
    }
    for (int l = 0; l < lanes; ++l) {
      const std::size_t i = block_begin + std::size_t(l);
      const glm::vec3 u = b.rest[i];
      const std::uint32_t first = b.offsets[i], last = b.offsets[i + 1];
      if (first < last) {
        // Relative to where the strongest bone takes the rest point (the anchor).
        const glm::mat4& m0 = palette[b.bones[first]];
        const glm::vec3 anchor = glm::vec3(m0 * glm::vec4(u, 1.0f));
        // C = Σ A P + d pᵀ, q = Σ A p + d ψ (d = M u − anchor), written out in scalars: the compiler keeps the twelve
        // sums in registers, where glm's matrix temporaries went through memory (a third of the job's time).
        float c00 = 0.0f, c01 = 0.0f, c02 = 0.0f, c10 = 0.0f, c11 = 0.0f, c12 = 0.0f, c20 = 0.0f, c21 = 0.0f,
              c22 = 0.0f;
        float qx = 0.0f, qy = 0.0f, qz = 0.0f, sx = 0.0f, sy = 0.0f, sz = 0.0f, psi = 0.0f;
        for (std::uint32_t e = first; e < last; ++e) {
          const float* m = &palette[b.bones[e]][0][0];  // column-major: m[4 · column + row]
          const float a00 = m[0], a10 = m[1], a20 = m[2], a01 = m[4], a11 = m[5], a21 = m[6], a02 = m[8], a12 = m[9],
                      a22 = m[10];
          const float dx = a00 * u.x + a01 * u.y + a02 * u.z + m[12] - anchor.x;
          const float dy = a10 * u.x + a11 * u.y + a12 * u.z + m[13] - anchor.y;
          const float dz = a20 * u.x + a21 * u.y + a22 * u.z + m[14] - anchor.z;
          const DirectDeltaMushMoments& o = b.moments[e];
          c00 += a00 * o.xx + a01 * o.xy + a02 * o.xz + dx * o.x;
          c01 += a00 * o.xy + a01 * o.yy + a02 * o.yz + dx * o.y;
          c02 += a00 * o.xz + a01 * o.yz + a02 * o.zz + dx * o.z;
          c10 += a10 * o.xx + a11 * o.xy + a12 * o.xz + dy * o.x;
          c11 += a10 * o.xy + a11 * o.yy + a12 * o.yz + dy * o.y;
          c12 += a10 * o.xz + a11 * o.yz + a12 * o.zz + dy * o.z;
          c20 += a20 * o.xx + a21 * o.xy + a22 * o.xz + dz * o.x;
          c21 += a20 * o.xy + a21 * o.yy + a22 * o.yz + dz * o.y;
          c22 += a20 * o.xz + a21 * o.yz + a22 * o.zz + dz * o.z;
          qx += a00 * o.x + a01 * o.y + a02 * o.z + dx * o.w;
          qy += a10 * o.x + a11 * o.y + a12 * o.z + dy * o.w;
          qz += a20 * o.x + a21 * o.y + a22 * o.z + dz * o.w;
          sx += o.x, sy += o.y, sz += o.z, psi += o.w;
        }
        glm::mat3 c(c00, c10, c20, c01, c11, c21, c02, c12, c22);  // columns
        const glm::vec3 q(qx, qy, qz), centroid(sx, sy, sz);
        if (psi > 0.0f) {
          const float inverse = 1.0f / psi;
          c -= glm::outerProduct(q, centroid * inverse);
          for (int k = 0; k < 9; ++k) block.c[k][l] = c[k / 3][k % 3];
          const glm::quat start = start_rotation(glm::mat3(m0));
          block.q[0][l] = start.w, block.q[1][l] = start.x, block.q[2][l] = start.y, block.q[3][l] = start.z;
          anchors[l] = anchor, sums[l] = q, centroids[l] = centroid, inverses[l] = inverse, turned[l] = true;
        }
      }
    }
    nearest_rotations(block);
    for (int l = 0; l < lanes; ++l) {
      const std::size_t i = block_begin + std::size_t(l);
      const glm::vec3 u = b.rest[i];
      glm::quat rotation(1.0f, 0.0f, 0.0f, 0.0f);
      glm::vec3 position = u;
      if (turned[l]) {
        rotation = glm::quat(block.q[0][l], block.q[1][l], block.q[2][l], block.q[3][l]);
        position = anchors[l] + (sums[l] - rotation * centroids[l]) * inverses[l];
      }
      if (!in_positions.empty()) position += rotation * (in_positions[i] - u);
      out_positions[i] = position;
      if (!out_normals.empty()) {
        const glm::vec3 n = rotation * in_normals[i];
        const float length = glm::length(n);
        out_normals[i] = length > 0.0f ? n / length : glm::vec3(0.0f);
      }
      if (!out_rotations.empty()) out_rotations[i] = rotation;
    }
  }
  return {};
}

Status DirectDeltaMushJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  return run_parallel(*this, pool, min_chunk);
}

}  // namespace deform
