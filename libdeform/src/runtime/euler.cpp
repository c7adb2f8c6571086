// Euler angles (X·Y·Z, degrees) <-> quaternions, and DOF clamping (docs/formats.md).
//
// R = Rx(a) · Ry(b) · Rz(c) has, in row r / column k,
//   R02 = sin b,  R12 = -sin a cos b,  R22 = cos a cos b,  R01 = -cos b sin c,  R00 = cos b cos c,
// and at b = ±90° only a ± c is defined: R21 = sin(a ± c), R11 = cos(a ± c).
// The conversion runs in double so that near gimbal lock the small entries keep their precision.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "deform/runtime/skeleton.hpp"
namespace deform {
namespace {

constexpr double degrees_per_radian = 180.0 / std::numbers::pi;

}  // namespace

glm::quat quat_from_euler(glm::vec3 degrees) noexcept {
  const glm::dvec3 half = glm::dvec3(degrees) * (0.5 / degrees_per_radian);
  const glm::dquat qx(std::cos(half.x), std::sin(half.x), 0.0, 0.0);
  const glm::dquat qy(std::cos(half.y), 0.0, std::sin(half.y), 0.0);
  const glm::dquat qz(std::cos(half.z), 0.0, 0.0, std::sin(half.z));
  return glm::quat(qx * qy * qz);
}

glm::vec3 euler_from_quat(glm::quat q) noexcept {
  glm::dquat d(q);
  const double length = std::sqrt(glm::dot(d, d));
  if (!(length > 1e-12) || !std::isfinite(length)) return glm::vec3(0.0f);
  d = d * (1.0 / length);
  const double w = d.w, x = d.x, y = d.y, z = d.z;
  const double r00 = 1.0 - 2.0 * (y * y + z * z);
  const double r01 = 2.0 * (x * y - w * z);
  const double r02 = 2.0 * (x * z + w * y);
  const double r11 = 1.0 - 2.0 * (x * x + z * z);
  const double r12 = 2.0 * (y * z - w * x);
  const double r21 = 2.0 * (y * z + w * x);
  const double r22 = 1.0 - 2.0 * (x * x + y * y);
  const double cos_b = std::hypot(r00, r01);  // = |cos b|, better conditioned near ±90° than asin(r02)
  const double b = std::atan2(r02, cos_b);
  double a = 0.0, c = 0.0;
  if (cos_b > 1e-9) {
    a = std::atan2(-r12, r22);
    c = std::atan2(-r01, r00);
  } else {
    a = std::atan2(r21, r11);  // gimbal lock: the whole X/Z rotation on x, z = 0
  }
  return glm::vec3(glm::dvec3(a, b, c) * degrees_per_radian);
}

glm::vec3 clamp_euler(glm::vec3 degrees, const DofLimits& limits) noexcept {
  for (int axis = 0; axis < 3; ++axis)
    degrees[axis] = std::min(std::max(degrees[axis], limits.min[axis]), limits.max[axis]);
  return degrees;
}

bool within_limits(glm::vec3 degrees, const DofLimits& limits, float slack) noexcept {
  for (int axis = 0; axis < 3; ++axis)
    if (!(degrees[axis] >= limits.min[axis] - slack && degrees[axis] <= limits.max[axis] + slack)) return false;
  return true;
}

}  // namespace deform
