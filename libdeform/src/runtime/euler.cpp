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
  for (int axis = 0; axis < 3; ++axis) {
    const float angle = std::isnan(degrees[axis]) ? 0.0f : degrees[axis];
    degrees[axis] = std::min(std::max(angle, limits.min[axis]), limits.max[axis]);
  }
  return degrees;
}

namespace {

constexpr double pi = std::numbers::pi;

// `angle` (radians, in [-π, π]) plus the multiple of 2π that brings it nearest [lo, hi] (limits within [-π, π]),
// and how far outside [lo, hi] that is (0 within).
struct Fitted {
  double angle, outside;
};
Fitted fit(double angle, double lo, double hi) {
  Fitted best{angle, 0.0};
  double best_outside = 1e300;
  for (const double shift : {0.0, -2.0 * pi, 2.0 * pi}) {
    const double a = angle + shift;
    const double outside = std::max(0.0, lo - a) + std::max(0.0, a - hi);
    if (outside < best_outside) best = {a, outside}, best_outside = outside;
  }
  return best;
}

}  // namespace

glm::vec3 euler_within_limits(glm::quat rotation, const DofLimits& limits) noexcept {
  glm::dquat d(rotation);
  const double length = std::sqrt(glm::dot(d, d));
  d = length > 1e-12 && std::isfinite(length) ? d * (1.0 / length) : glm::dquat(1.0, 0.0, 0.0, 0.0);
  const glm::dmat3 r = glm::transpose(glm::mat3_cast(d));  // r[row][column]
  const glm::dvec3 lo = glm::dvec3(limits.min) / degrees_per_radian, hi = glm::dvec3(limits.max) / degrees_per_radian;
  // The first triple as euler_from_quat, then the other one.
  const double cos_b = std::hypot(r[0][0], r[0][1]);
  glm::dvec3 first(0.0, std::atan2(r[0][2], cos_b), 0.0);
  if (cos_b > 1e-9) {
    first.x = std::atan2(-r[1][2], r[2][2]);
    first.z = std::atan2(-r[0][1], r[0][0]);
  } else {
    first.x = std::atan2(r[2][1], r[1][1]);
  }
  auto wrap = [](double a) { return a > pi ? a - 2.0 * pi : (a <= -pi ? a + 2.0 * pi : a); };
  const glm::dvec3 second(wrap(first.x + pi), wrap(pi - first.y), wrap(first.z + pi));
  glm::dvec3 fitted[2];
  double outside[2] = {0.0, 0.0};
  for (int t = 0; t < 2; ++t)
    for (int axis = 0; axis < 3; ++axis) {
      const Fitted f = fit((t == 0 ? first : second)[axis], lo[axis], hi[axis]);
      fitted[t][axis] = f.angle;
      outside[t] += f.outside;
    }
  glm::dvec3 angles = outside[1] < outside[0] ? fitted[1] : fitted[0];
  if (std::min(outside[0], outside[1]) > 0.0) {
    // M = Rx(-x) · R is Ry(y) · Rz(z) when x is right: y from its entries (0,2) and (2,2); then N = Ry(-y) · M is
    // nearest Rz(z) at z = atan2(N10 - N01, N00 + N11).
    double x = std::clamp(angles.x, lo.x, hi.x);
    if (cos_b < 1e-2 && fit(angles.y, lo.y, hi.y).outside < 1e-5) {
      // Gimbal lock within the y limits: only s = x + z (y = 90°) or x − z (y = −90°) is defined, so x may go
      // anywhere in [lo.x, hi.x] that leaves z = ±(s − x) within [lo.z, hi.z]: the nearest such x to the triple's.
      // Near the lock too (|cos y| < 0.01), where a float rotation holds x and z apart only to 1e-7 / |cos y| rad:
      // an in-limit triple read back a hair outside both x and z limits is found again.
      const double sign = r[0][2] > 0.0 ? 1.0 : -1.0, s = angles.x + sign * angles.z;
      const double from = sign > 0.0 ? s - hi.z : s + lo.z, to = sign > 0.0 ? s - lo.z : s + hi.z;
      double best = 1e300;
      for (int k = -2; k <= 2; ++k) {
        // (1e-6 rad of slack: a locked z, or a triple on two limits at once, leaves a single point, and s comes
        // from a float quaternion.)
        const double a = std::max(from + 2.0 * pi * k, lo.x), b = std::min(to + 2.0 * pi * k, hi.x);
        if (a > b + 1e-6) continue;
        const double candidate = std::clamp(angles.x, std::min(a, b), std::max(a, b));
        if (std::abs(candidate - angles.x) < best) best = std::abs(candidate - angles.x), x = candidate;
      }
    }
    const double cx = std::cos(x), sx = std::sin(x);
    glm::dmat3 m;  // m[row][column]
    for (int j = 0; j < 3; ++j) {
      m[0][j] = r[0][j];
      m[1][j] = cx * r[1][j] + sx * r[2][j];
      m[2][j] = -sx * r[1][j] + cx * r[2][j];
    }
    const double y = std::clamp(fit(std::atan2(m[0][2], m[2][2]), lo.y, hi.y).angle, lo.y, hi.y);
    const double cy = std::cos(y), sy = std::sin(y);
    const double n00 = cy * m[0][0] - sy * m[2][0], n01 = cy * m[0][1] - sy * m[2][1];
    const double z = std::clamp(fit(std::atan2(m[1][0] - n01, n00 + m[1][1]), lo.z, hi.z).angle, lo.z, hi.z);
    angles = glm::dvec3(x, y, z);
  }
  // The float conversion may round just past a limit: clamp in float, where the limits are.
  return clamp_euler(glm::vec3(angles * degrees_per_radian), limits);
}

bool within_limits(glm::vec3 degrees, const DofLimits& limits, float slack) noexcept {
  for (int axis = 0; axis < 3; ++axis)
    if (!(degrees[axis] >= limits.min[axis] - slack && degrees[axis] <= limits.max[axis] + slack)) return false;
  return true;
}

}  // namespace deform
