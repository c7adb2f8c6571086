// DirectDeltaMushJob: per point, the bones' matrices applied to the point's smoothed moments, the rotation nearest the
// cross-covariance that gives, and the point carried by it (Le and Lewis 2019). Sums are taken relative to where the
// point's strongest bone carries its rest point, so that no float sum cancels the model's distance from the origin.
#include "deform/runtime/direct_delta_mush.hpp"

#include <algorithm>
#include <cmath>

#include "deform/runtime/parallel.hpp"
#include "runtime/finite.hpp"

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

glm::mat3 symmetric(const DirectDeltaMushMoments& m) noexcept {
  return glm::mat3(m.xx, m.xy, m.xz, m.xy, m.yy, m.yz, m.xz, m.yz, m.zz);
}

// A unit quaternion near the 3×3 part of a bone matrix (its columns normalised; scale and shear only make it a start).
glm::quat start_rotation(const glm::mat3& a) noexcept {
  const float l0 = glm::length(a[0]), l1 = glm::length(a[1]), l2 = glm::length(a[2]);
  if (!(l0 > 0.0f && l1 > 0.0f && l2 > 0.0f)) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const glm::quat q = glm::normalize(glm::quat_cast(glm::mat3(a[0] / l0, a[1] / l1, a[2] / l2)));
  return finite(q) ? q : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
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
    glm::mat3 h = -0.5f * (s + glm::transpose(s));
    h[0][0] += trace, h[1][1] += trace, h[2][2] += trace;
    // H positive definite (its leading minors positive): the Newton step; else a gradient step.
    const float m2 = h[0][0] * h[1][1] - h[0][1] * h[1][0], m3 = glm::determinant(h);
    glm::vec3 omega;
    if (h[0][0] > 0.0f && m2 > 0.0f && m3 > 0.0f) {
      omega = glm::inverse(h) * g;
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
  for (std::size_t i = begin; i < end; ++i) {
    const glm::vec3 u = b.rest[i];
    const std::uint32_t first = b.offsets[i], last = b.offsets[i + 1];
    glm::quat rotation(1.0f, 0.0f, 0.0f, 0.0f);
    glm::vec3 position = u;
    if (first < last) {
      // Relative to where the strongest bone takes the rest point (the anchor).
      const glm::mat4& m0 = palette[b.bones[first]];
      const glm::vec3 anchor = glm::vec3(m0 * glm::vec4(u, 1.0f));
      glm::mat3 c(0.0f);
      glm::vec3 q(0.0f), centroid(0.0f);
      float psi = 0.0f;
      for (std::uint32_t e = first; e < last; ++e) {
        const glm::mat4& m = palette[b.bones[e]];
        const glm::mat3 a(m);
        const glm::vec3 d = glm::vec3(m * glm::vec4(u, 1.0f)) - anchor;
        const DirectDeltaMushMoments& o = b.moments[e];
        const glm::vec3 p(o.x, o.y, o.z);
        c += a * symmetric(o) + glm::outerProduct(d, p);
        q += a * p + d * o.w;
        centroid += p;
        psi += o.w;
      }
      if (psi > 0.0f) {
        const float inverse = 1.0f / psi;
        c -= glm::outerProduct(q, centroid * inverse);
        rotation = nearest_rotation(c, start_rotation(glm::mat3(m0)));
        position = anchor + (q - rotation * centroid) * inverse;
      }
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
  return {};
}

Status DirectDeltaMushJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  return run_parallel(*this, pool, min_chunk);
}

}  // namespace deform
