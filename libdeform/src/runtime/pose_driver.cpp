// The pose driver's per-frame job (pose_driver.hpp): distances to the sample poses, kernel values, weights.
#include "deform/runtime/pose_driver.hpp"

#include <algorithm>
#include <cmath>

#include "finite.hpp"

namespace deform {

float swing_twist_distance_squared(glm::quat a, glm::quat b, glm::vec3 axis, float twist_weight) noexcept {
  // r = a⁻¹ b = (w, v). Its twist about the axis is (w, τ·axis)/|(w, τ)| with τ = v·axis, so the twist's half-angle
  // sine is |τ| / |(w, τ)|; the swing r · twist⁻¹ has real part |(w, τ)|, so its half-angle sine is
  // sqrt(1 − w² − τ²) = sqrt(|v|² − τ²). Chords are twice the half-angle sines.
  const glm::quat r = glm::conjugate(a) * b;
  const glm::vec3 v(r.x, r.y, r.z);
  const float tau = glm::dot(v, axis);
  const float twist_norm2 = r.w * r.w + tau * tau;
  const float swing_half2 = std::max(0.0f, glm::dot(v, v) - tau * tau);
  const float twist_half2 = twist_norm2 > 0.0f ? tau * tau / twist_norm2 : 0.0f;
  return 4.0f * (swing_half2 + twist_weight * twist_weight * twist_half2);
}

float rbf_kernel(RbfKernel kernel, float distance_squared, float radius) noexcept {
  const float x = distance_squared / (radius * radius);
  return kernel == RbfKernel::gaussian ? std::exp(-x) : 1.0f / std::sqrt(1.0f + x);
}

namespace {

Status check_sizes(const PoseDriverJob& job) noexcept {
  const PoseDriverBinding* b = job.binding;
  if (b == nullptr) return Status::failure("the pose driver has no binding");
  if (b->bones.empty()) return Status::failure("the pose driver has no driver bone");
  if (b->twist_axes.size() != b->bones.size()) return Status::failure("twist axes and driver bones differ in count");
  if (b->sample_poses.size() % b->bones.size() != 0) return Status::failure("sample poses are not whole rows");
  if (b->coefficients.size() != b->pose_count() * b->shape_count)
    return Status::failure("coefficients are not one per sample pose and shape");
  if (job.weights.size() != b->shape_count) return Status::failure("weights are not one per shape");
  return Status();
}

}  // namespace

Status PoseDriverJob::validate() const noexcept {
  if (const Status sizes = check_sizes(*this); !sizes) return sizes;
  const PoseDriverBinding& b = *binding;
  if (!(b.radius > 0.0f) || !std::isfinite(b.radius)) return Status::failure("radius is not positive and finite");
  if (!(b.twist_weight >= 0.0f) || !std::isfinite(b.twist_weight))
    return Status::failure("twist weight is negative or not finite");
  for (const std::int32_t bone : b.bones)
    if (bone < 0 || std::size_t(bone) >= rotations.size()) return Status::failure("driver bone out of range");
  for (const glm::vec3& axis : b.twist_axes)
    if (!finite(axis) || std::abs(glm::length(axis) - 1.0f) > 1e-3f) return Status::failure("twist axis is not unit");
  for (const glm::quat& q : b.sample_poses)
    if (!finite(q)) return Status::failure("sample pose is not finite");
  for (const float c : b.coefficients)
    if (!std::isfinite(c)) return Status::failure("coefficient is not finite");
  return Status();
}

Status PoseDriverJob::run() const noexcept { return run(0, count()); }

Status PoseDriverJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status sizes = check_sizes(*this); !sizes) return sizes;
  const PoseDriverBinding& b = *binding;
  if (begin > end || end > b.shape_count) return Status::failure("range out of bounds");
  const std::size_t bone_count = b.bones.size(), shapes = b.shape_count;
  for (const std::int32_t bone : b.bones)
    if (bone < 0 || std::size_t(bone) >= rotations.size()) return Status::failure("driver bone out of range");
  std::fill(weights.begin() + std::ptrdiff_t(begin), weights.begin() + std::ptrdiff_t(end), 0.0f);
  for (std::size_t k = 0; k < b.pose_count(); ++k) {
    float d2 = 0.0f;
    for (std::size_t j = 0; j < bone_count; ++j)
      d2 += swing_twist_distance_squared(b.sample_poses[k * bone_count + j], rotations[std::size_t(b.bones[j])],
                                         b.twist_axes[j], b.twist_weight);
    const float phi = rbf_kernel(b.kernel, d2, b.radius);
    const float* row = b.coefficients.data() + k * shapes;
    for (std::size_t s = begin; s < end; ++s) weights[s] += phi * row[s];
  }
  if (b.clamp)
    for (std::size_t s = begin; s < end; ++s) weights[s] = std::clamp(weights[s], 0.0f, 1.0f);
  return Status();
}

}  // namespace deform
