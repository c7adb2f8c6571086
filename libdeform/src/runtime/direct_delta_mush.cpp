// DirectDeltaMushJob: per point, the bones' matrices applied to the point's smoothed moments, the rotation nearest the
// cross-covariance that gives, and the point carried by it (Le and Lewis 2019). Sums are taken relative to where the
// point's strongest bone carries its rest point, so that no float sum cancels the model's distance from the origin.
// run() hands its range to the lane kernel (simd/ddm_kernel.inl), in the copy its Isa picks (the widest by default);
// nearest_rotation below is the same step for one point, for callers and the tests.
#include "deform/runtime/direct_delta_mush.hpp"

#include <cmath>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/isa.hpp"
#include "finite.hpp"
#include "simd/ddm_kernel.hpp"

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
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  return {};
}

using KernelEntry = void (*)(const detail::DdmKernelArgs&) noexcept;

// The copy for `isa`, which isa_available() has accepted.
KernelEntry kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::direct_delta_mush_avx512;
  if (isa == Isa::avx2) return detail::direct_delta_mush_avx2;
#endif
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return detail::direct_delta_mush_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return detail::direct_delta_mush_simd128;
#endif
  return detail::direct_delta_mush_portable;
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
  if (begin == end) return {};
  kernel_for(isa)({binding, matrices.data(), in_positions.empty() ? nullptr : in_positions.data(),
                   in_normals.empty() ? nullptr : in_normals.data(), out_positions.data(),
                   out_normals.empty() ? nullptr : out_normals.data(),
                   out_rotations.empty() ? nullptr : out_rotations.data(), begin, end});
  return {};
}

Status DirectDeltaMushJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  return run_parallel(*this, pool, min_chunk);
}

}  // namespace deform
