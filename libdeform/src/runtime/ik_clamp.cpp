// The solvers' per-frame DOF clamp: Skeleton::clamp_to_limits (convert to Euler X·Y·Z, clamp, convert back) without
// trigonometric calls. A joint's Euler angles are kept both as angles and as (cos, sin) directions: the directions
// come straight from the rotation matrix entries, an angle from a polynomial arctangent, and the quaternion back from
// half-angle directions. Clamped axes take directions precomputed by prepare_limits.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "deform/runtime/portable.hpp"
#include "ik_chain.hpp"

namespace deform {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double tan_pi_8 = 0.41421356237309503;  // √2 − 1

// atan2(y, x) in (-π, π], to within 7e-9 rad. The angle of (|x|, |y|) is reduced by 0, π/4 or π/2 to
// |atan t| <= π/8, where atan t = t · P(t²), P interpolating atan(√s)/√s at 5 Chebyshev nodes of [0, tan²(π/8)]
// (near-minimax). Written with selects, which GCC 12 compiles to branches; a branch-free form (min, max, sign
// copies and a second division) made the clamp slower (docs/performance.md, 2026-11-24).
inline double polynomial_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const bool low = ay <= tan_pi_8 * ax, high = ax < tan_pi_8 * ay;
  const double numerator = low ? ay : (high ? -ax : ay - ax);
  const double denominator = low ? ax : (high ? ay : ay + ax);
  const double base = low ? 0.0 : (high ? 0.5 * pi : 0.25 * pi);
  const double t = denominator > 0.0 ? numerator / denominator : 0.0;  // (0, 0) gives 0, as std::atan2
  const double s = t * t;
  const double angle =
      base + t * (0.99999998126461132 +
                  s * (-0.33332785771926865 +
                       s * (0.19974082415557812 + s * (-0.13848490212692172 + s * 0.079762918079436945))));
  const double quadrant = x < 0.0 ? pi - angle : angle;
  return y < 0.0 ? -quadrant : quadrant;
}

inline double wrap(double a) { return a > pi ? a - 2.0 * pi : (a <= -pi ? a + 2.0 * pi : a); }

// Whether the direction (cos a, sin a) · length of each axis, times `flip` as the triples take them (the second
// triple, flip −1, negates the x and z directions and the cosine of y), lies within its limits, from dot and cross
// products with the limits' directions: for a range of at most 180° the angle from min (its sine >= 0) may be at
// most the width; for a wider one, the angle is outside when strictly within the complementary range from max to
// min (never for a full circle, whose cos_width is 2). The sines' signs do not depend on the length and the cosine
// bound scales with it, so no direction needs dividing by its length. Agrees with comparing the angles except within
// rounding (1e-7 rad) of a limit.
inline bool raw_directions_within(const EulerLimits& limits, const glm::dvec2 (&raw)[3], glm::dvec3 length,
                                  double flip) {
  for (int axis = 0; axis < 3; ++axis) {
    const glm::dvec2 d = axis == 1 ? glm::dvec2(flip * raw[1].x, raw[1].y) : flip * raw[axis];
    const glm::dvec2 lo = limits.min_dir[axis], hi = limits.max_dir[axis];
    const double c = limits.cos_width[axis] * length[axis];
    if (!limits.wide[axis]) {
      if (!(lo.x * d.y - lo.y * d.x >= 0.0 && glm::dot(lo, d) >= c)) return false;
    } else if (hi.x * d.y - hi.y * d.x > 0.0 && glm::dot(hi, d) > c) {
      return false;
    }
  }
  return true;
}

// How far an angle in (-π, π] lies outside [min, max] (within [-π, π]) around the circle: 0 within, else the
// distance to the nearer limit, one of them possibly across ±π.
inline double outside(double angle, double min, double max) {
  if (angle < min) return std::min(min - angle, angle + 2.0 * pi - max);
  if (angle > max) return std::min(angle - max, min + 2.0 * pi - angle);
  return 0.0;
}

// outside() summed over the axes (radians).
inline double outside(const EulerLimits& limits, glm::dvec3 angle) {
  double sum = 0.0;
  for (int axis = 0; axis < 3; ++axis) sum += outside(angle[axis], limits.min[axis], limits.max[axis]);
  return sum;
}

// v turned about Euler axis `axis` by the angle of the direction d (by its inverse when `inverse`).
inline glm::dvec3 turn_about(glm::dvec3 v, int axis, glm::dvec2 d, bool inverse) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double s = inverse ? -d.y : d.y;
  const double vi = v[i], vj = v[j];
  v[i] = d.x * vi - s * vj;
  v[j] = s * vi + d.x * vj;
  return v;
}

// (cos a, sin a) to within 1e-12 for |a| < 100 rad (the angles here lie within a few π).
glm::dvec2 direction(double angle) {
  // Reduced by the nearest multiple of π/2 to |r| <= π/4, where the Taylor series of sin to r^13 and cos to r^12
  // are within 5e-13.
  const auto quarter = static_cast<long>(angle * (2.0 / pi) + (angle >= 0.0 ? 0.5 : -0.5));
  const double r = angle - static_cast<double>(quarter) * (0.5 * pi), r2 = r * r;
  const double sine =
      r * (1.0 + r2 * (-1.0 / 6 +
                       r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
                                                                                        r2 * (1.0 / 6227020800.0)))))));
  const double cosine =
      1.0 +
      r2 * (-1.0 / 2 +
            r2 * (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600))))));
  switch (quarter & 3) {
    case 0: return {cosine, sine};
    case 1: return {-sine, cosine};
    case 2: return {-cosine, -sine};
    default: return {sine, -cosine};
  }
}

// The unit quaternion qx · qy · qz of the directions of `euler`, of any lengths (its angles are not read), inlined
// into the clamps below: their Euler angles then stay in registers instead of going through memory between two calls
// (~3 ns per clamp on the critical path of a two-bone solve).
inline glm::quat quaternion_of(const detail::EulerAngles& euler) noexcept {
  const glm::dvec3 r = euler.length;
  const glm::dvec2 x = detail::scaled_half_angle(euler.dir[0], r.x), y = detail::scaled_half_angle(euler.dir[1], r.y);
  const glm::dvec2 z = detail::scaled_half_angle(euler.dir[2], r.z);
  // qx · qy = (w, i, j, k), then · qz; the product of the three scaled factors, normalised once. The norm of a
  // product is the product of the norms, and a factor's is known from its direction, |scaled_half_angle(d, r)|² =
  // 2r (r + |d.x|) for |d| = r: so the square root and division run beside the products, not after them.
  auto norm2 = [](glm::dvec2 d, double length) { return 2.0 * length * (length + std::abs(d.x)); };
  const double inverse_norm =
      1.0 / std::sqrt(norm2(euler.dir[0], r.x) * norm2(euler.dir[1], r.y) * norm2(euler.dir[2], r.z));
  const double w = x.x * y.x, i = x.y * y.x, j = x.x * y.y, k = x.y * y.y;
  const glm::dquat q(w * z.x - k * z.y, i * z.x + j * z.y, j * z.x - i * z.y, w * z.y + k * z.x);
  return glm::quat(q * inverse_norm);
}

// detail::limit_euler, inlined into the clamps below (its result then stays in registers instead of going through
// memory to quaternion_of; the options are constants there).
template <bool angles_needed, bool raw_directions>
DEFORM_ALWAYS_INLINE inline bool limit_euler_inline(const EulerLimits& limits, glm::quat rotation,
                                                    detail::EulerAngles& euler) noexcept {
  using detail::EulerAngles;
  // R = Rx(a) · Ry(b) · Rz(c): R02 = sin b, (R22, −R12) = cos b (cos a, sin a), (R00, −R01) = cos b (cos c, sin c);
  // at cos b = 0 only a ± c is defined and all of it goes on x: (R11, R21) = (cos a, sin a), c = 0 (as
  // euler_from_quat). The entries below are R · |q|² (no normalisation needed), in double so that near gimbal lock
  // the small ones keep their precision.
  glm::dquat q(rotation);
  double ww = q.w * q.w, xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z, norm2 = ww + xx + yy + zz;
  if (!(norm2 > 1e-24) || !std::isfinite(norm2)) {  // read as the identity
    q = glm::dquat(1.0, 0.0, 0.0, 0.0);
    ww = 1.0, xx = yy = zz = 0.0, norm2 = 1.0;
  }
  const double r00 = ww + xx - yy - zz, r01 = 2.0 * (q.x * q.y - q.w * q.z), r02 = 2.0 * (q.x * q.z + q.w * q.y);
  const double r11 = ww - xx + yy - zz, r12 = 2.0 * (q.y * q.z - q.w * q.x), r21 = 2.0 * (q.y * q.z + q.w * q.x);
  const double r22 = ww - xx - yy + zz;
  const double cos_b = std::sqrt(r00 * r00 + r01 * r01);
  // The directions up to positive scale (all that polynomial_atan2 needs), then made unit: the angles do not wait
  // for the square root and division.
  const bool regular = cos_b > 1e-9 * norm2;
  const glm::dvec2 raw[3] = {regular ? glm::dvec2(r22, -r12) : glm::dvec2(r11, r21), glm::dvec2(cos_b, r02),
                             regular ? glm::dvec2(r00, -r01) : glm::dvec2(1.0, 0.0)};
  EulerAngles first, second;
  if constexpr (!angles_needed) {
    // A rotation within the limits returns here, before any division: the test takes the raw directions with their
    // lengths (|raw[1]| = norm2, R's first row being unit; |raw[0]| = |raw[2]| = cos_b, or at gimbal lock norm2
    // and 1).
    const glm::dvec3 raw_length(regular ? cos_b : norm2, norm2, regular ? cos_b : 1.0);
    if (raw_directions_within(limits, raw, raw_length, 1.0) || raw_directions_within(limits, raw, raw_length, -1.0))
      return false;
  }
  if constexpr (angles_needed || !raw_directions) {  // (raw directions are returned without the unit ones)
    const double inverse_norm2 = 1.0 / norm2;
    first.dir[1] = raw[1] * inverse_norm2;
    if (regular) {
      const double scale = 1.0 / cos_b;
      first.dir[0] = raw[0] * scale;
      first.dir[2] = raw[2] * scale;
    } else {
      first.dir[0] = raw[0] * inverse_norm2;
      first.dir[2] = raw[2];
    }
    second.dir[0] = -first.dir[0];
    second.dir[1] = glm::dvec2(-first.dir[1].x, first.dir[1].y);
    second.dir[2] = -first.dir[2];
  }
  for (int axis = 0; axis < 3; ++axis) first.angle[axis] = polynomial_atan2(raw[axis].y, raw[axis].x);
  const double first_outside = outside(limits, first.angle);
  if (first_outside == 0.0) {
    euler = first;
    return false;
  }
  // The same rotation's other triple (a + 180°, 180° − b, c + 180°).
  second.angle = glm::dvec3(wrap(first.angle.x + pi), wrap(pi - first.angle.y), wrap(first.angle.z + pi));
  const double second_outside = outside(limits, second.angle);
  const bool take_second = second_outside < first_outside;
  euler = take_second ? second : first;
  if (second_outside == 0.0) return false;
  if constexpr (!angles_needed && raw_directions) {
    // The axes left unclamped below keep the raw directions (the second triple's with its sign changes), whose
    // lengths are known without the division: |raw[2]| = cos_b (1 at gimbal lock), |raw[1]| = norm2 (R's first row
    // is unit), |raw[0]| = cos_b too (R's third column is unit) — but only to rounding relative to cos_b, and
    // quaternion_of's norm relies on the lengths: within 1e-4 of gimbal lock (and at it, norm2) it is measured
    // instead.
    const double length0 = regular && cos_b > 1e-4 * norm2 ? cos_b : glm::length(raw[0]);
    euler.length = glm::dvec3(length0, norm2, regular ? cos_b : 1.0);
    const double flip = take_second ? -1.0 : 1.0;
    euler.dir[0] = raw[0] * flip;
    euler.dir[1] = glm::dvec2(raw[1].x * flip, raw[1].y);
    euler.dir[2] = raw[2] * flip;
  }
  // Each axis outside goes to its nearer limit around the circle (across ±π when that one is nearer).
  for (int axis = 0; axis < 3; ++axis) {
    const double angle = euler.angle[axis], min = limits.min[axis], max = limits.max[axis];
    if (angle >= min && angle <= max) continue;
    const double to_min = angle < min ? min - angle : min + 2.0 * pi - angle;
    const double to_max = angle > max ? angle - max : angle + 2.0 * pi - max;
    if (to_min <= to_max) {
      euler.angle[axis] = min, euler.dir[axis] = limits.min_dir[axis];
    } else {
      euler.angle[axis] = max, euler.dir[axis] = limits.max_dir[axis];
    }
    euler.length[axis] = 1.0;
  }
  return true;
}

}  // namespace

EulerLimits prepare_limits(const DofLimits& limits) noexcept {
  EulerLimits prepared;
  for (int axis = 0; axis < 3; ++axis) {
    prepared.min[axis] = static_cast<double>(limits.min[axis]) * (pi / 180.0);
    prepared.max[axis] = static_cast<double>(limits.max[axis]) * (pi / 180.0);
    prepared.min_dir[axis] = glm::dvec2(std::cos(prepared.min[axis]), std::sin(prepared.min[axis]));
    prepared.max_dir[axis] = glm::dvec2(std::cos(prepared.max[axis]), std::sin(prepared.max[axis]));
    const double width = prepared.max[axis] - prepared.min[axis];
    // (−1 for a full circle would call half of its directions outside: the dot with max then exceeds it.)
    prepared.cos_width[axis] = width >= 2.0 * pi ? 2.0 : std::cos(width);
    prepared.wide[axis] = width > pi;
  }
  prepared.free = glm::all(glm::lessThanEqual(limits.min, glm::vec3(-180.0f))) &&
                  glm::all(glm::greaterThanEqual(limits.max, glm::vec3(180.0f)));
  return prepared;
}

bool clamp_rotation(const EulerLimits& limits, glm::quat& rotation) noexcept {
  const float norm2 = glm::dot(rotation, rotation);
  if (!(norm2 > 1e-30f) || !std::isfinite(norm2)) {
    rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    clamp_rotation(limits, rotation);
    return true;
  }
  // limit_euler reads the rotation up to scale and quaternion_of returns a unit quaternion, so the normalisation is
  // needed only on the unclamped path, and off the clamp's critical path there.
  detail::EulerAngles euler;
  if (limits.free || !limit_euler_inline<false, true>(limits, rotation, euler)) {
    rotation = glm::normalize(rotation);
    return false;
  }
  rotation = quaternion_of(euler);
  return true;
}

namespace detail {

bool limit_euler(const EulerLimits& limits, glm::quat rotation, EulerAngles& euler, bool angles_needed,
                 bool raw_directions) noexcept {
  if (angles_needed) return limit_euler_inline<true, false>(limits, rotation, euler);
  return raw_directions ? limit_euler_inline<false, true>(limits, rotation, euler)
                        : limit_euler_inline<false, false>(limits, rotation, euler);
}

glm::quat quat_at(glm::dvec3 angle, glm::vec4& xy_dirs) noexcept {
  // The factors' half-angle directions directly (unit: no normalisation after the product), and the X and Y
  // directions from them by the double-angle formulas. For |angle| <= π (every angle here but a limit beyond
  // ±180°) the half angle's direction is the double angle of the quarter angle's, |quarter| <= π/4, where the
  // series need no reduction (no quadrant branch); within 2e-12.
  glm::dvec2 half[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double a = angle[axis];
    if (std::abs(a) <= pi) {
      const double r = 0.25 * a, r2 = r * r;
      const double sine =
          r *
          (1.0 + r2 * (-1.0 / 6 +
                       r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
                                                                                        r2 * (1.0 / 6227020800.0)))))));
      const double cosine =
          1.0 + r2 * (-1.0 / 2 +
                      r2 * (1.0 / 24 +
                            r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600))))));
      half[axis] = glm::dvec2(cosine * cosine - sine * sine, 2.0 * cosine * sine);
    } else {
      half[axis] = direction(0.5 * a);
    }
  }
  const glm::dvec2 x = half[0], y = half[1], z = half[2];
  xy_dirs = glm::vec4(glm::dvec4(x.x * x.x - x.y * x.y, 2.0 * x.x * x.y, y.x * y.x - y.y * y.y, 2.0 * y.x * y.y));
  const double w = x.x * y.x, i = x.y * y.x, j = x.x * y.y, k = x.y * y.y;
  return glm::quat(glm::dquat(w * z.x - k * z.y, i * z.x + j * z.y, j * z.x - i * z.y, w * z.y + k * z.x));
}

void reaim_euler(const EulerLimits& limits, EulerAngles& euler, glm::dvec3 carried, glm::dvec3 wanted) noexcept {
  for (int axis = 0; axis < 3; ++axis) {
    if (limits.min[axis] == limits.max[axis]) continue;
    // R = Rx · Ry · Rz: axis k turns v = (the rotations after k) · carried; compare with (those before k)⁻¹ · wanted.
    glm::dvec3 v = carried, u = wanted;
    for (int later = 2; later > axis; --later) v = turn_about(v, later, euler.dir[later], false);
    for (int earlier = 0; earlier < axis; ++earlier) u = turn_about(u, earlier, euler.dir[earlier], true);
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;  // the plane the axis turns
    if (v[i] * v[i] + v[j] * v[j] < 1e-20 || u[i] * u[i] + u[j] * u[j] < 1e-20) continue;
    // The best angle turns v's direction in the plane onto u's: the direction of u · conj(v) as complex numbers.
    const glm::dvec2 best_dir(u[i] * v[i] + u[j] * v[j], u[j] * v[i] - u[i] * v[j]);
    // Whether it lies within [min, max], from the sines of its angles to the limits (cross products, which keep
    // full precision at a limit; best_dir's length does not matter): for a range of at most 180° it must be
    // counter-clockwise of min and clockwise of max; a wider one excludes only the strictly opposite case.
    const glm::dvec2 lo = limits.min_dir[axis], hi = limits.max_dir[axis];
    const double from_min = lo.x * best_dir.y - lo.y * best_dir.x, to_max = best_dir.x * hi.y - best_dir.y * hi.x;
    const bool inside = limits.max[axis] - limits.min[axis] >= 2.0 * pi ||
                        (limits.wide[axis] ? !(from_min < 0.0 && to_max < 0.0) : from_min >= 0.0 && to_max >= 0.0);
    if (inside) {
      euler.dir[axis] = best_dir * (1.0 / glm::length(best_dir));
    } else {
      // The nearer limit around the circle: the one with the larger cosine to best_dir.
      euler.dir[axis] = glm::dot(best_dir, lo) >= glm::dot(best_dir, hi) ? lo : hi;
    }
  }
}

bool clamp_joint(const EulerLimits& limits, glm::quat& local, bool reaim, glm::vec3 carried,
                 glm::vec3 wanted) noexcept {
  EulerAngles euler;
  const bool within = limits.free || (reaim ? !limit_euler_inline<false, false>(limits, local, euler)
                                            : !limit_euler_inline<false, true>(limits, local, euler));
  if (within) {  // (limit_euler reads `local` up to scale)
    local = glm::normalize(local);
    return false;
  }
  if (reaim) reaim_euler(limits, euler, carried, wanted);
  local = quaternion_of(euler);
  return true;
}

}  // namespace detail
}  // namespace deform

// --- swing-twist limits ---
namespace deform {
namespace {

glm::dvec3 unit_or_x(glm::vec3 v) {
  const glm::dvec3 d(v);
  const double length = glm::length(d);
  return length > 1e-30 && std::isfinite(length) ? d / length : glm::dvec3(1.0, 0.0, 0.0);
}

// `e` made perpendicular to the unit `axis` and unit; the coordinate axis least aligned with `axis` when `e` is
// (nearly) along it.
glm::dvec3 perpendicular(glm::dvec3 axis, glm::dvec3 e) {
  glm::dvec3 r = e - glm::dot(e, axis) * axis;
  if (glm::dot(r, r) < 1e-6) {
    const glm::dvec3 m = glm::abs(axis);
    e = m.x <= m.y && m.x <= m.z ? glm::dvec3(1, 0, 0) : (m.y <= m.z ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1));
    r = e - glm::dot(e, axis) * axis;
  }
  return glm::normalize(r);
}

float radians_within(float degrees, float lo, float hi) {
  return glm::radians(std::clamp(std::isnan(degrees) ? 0.0f : degrees, lo, hi));
}

// A rotation split about the limits' axis: the swing (w >= 0), its rotation-vector components, the twist angle.
struct Split {
  glm::dquat swing{1.0, 0.0, 0.0, 0.0};
  glm::dvec2 s{0.0};
  double twist = 0.0;
};

Split split(const SwingTwistLimits& limits, glm::quat rotation) {
  glm::dquat q(rotation);
  const double norm = std::sqrt(glm::dot(q, q));
  q = norm > 1e-30 && std::isfinite(norm) ? q * (1.0 / norm) : glm::dquat(1.0, 0.0, 0.0, 0.0);
  if (q.w < 0.0) q = -q;
  const glm::dvec3 axis(limits.axis), b1(limits.reference), b2 = glm::cross(axis, b1);
  const double p = q.x * axis.x + q.y * axis.y + q.z * axis.z, twist_norm = std::sqrt(q.w * q.w + p * p);
  Split result;
  glm::dquat twist(1.0, 0.0, 0.0, 0.0);
  if (twist_norm > 1e-12) {
    twist = glm::dquat(q.w / twist_norm, axis * (p / twist_norm));
    result.twist = 2.0 * std::atan2(p, q.w);
    if (result.twist > pi) result.twist -= 2.0 * pi;  // q.w >= 0 keeps it within [-π, π]; π rather than -π is kept
  }
  glm::dquat swing = q * glm::conjugate(twist);
  if (swing.w < 0.0) swing = -swing;
  result.swing = swing;
  const glm::dvec3 v(swing.x, swing.y, swing.z);
  const double sine = glm::length(v);
  if (sine > 1e-300) {
    const double angle = 2.0 * std::atan2(sine, swing.w);
    result.s = glm::dvec2(glm::dot(v, b1), glm::dot(v, b2)) * (angle / sine);
  }
  return result;
}

// The point of the ellipse (x / a)² + (y / b)² <= 1 (a, b >= 0) nearest (x, y), which lies outside it: (a² x / (t +
// a²), b² y / (t + b²)) at the root t > 0 of f(t) = (a x / (t + a²))² + (b y / (t + b²))² - 1, which is convex and
// decreasing there, so Newton's method from below climbs to it without overshooting. It starts where either term
// alone reaches 1 (f >= 0 there, so the root is not below): from t = 0 a flat cone (b a thousandth of a or less) took
// more than 32 steps, each growing t + b² by about half, and the point stayed outside.
glm::dvec2 nearest_on_ellipse(glm::dvec2 p, double a, double b) {
  if (a <= 0.0 && b <= 0.0) return glm::dvec2(0.0);
  if (a <= 0.0) return glm::dvec2(0.0, std::clamp(p.y, -b, b));
  if (b <= 0.0) return glm::dvec2(std::clamp(p.x, -a, a), 0.0);
  const double a2 = a * a, b2 = b * b, ax = a * p.x, by = b * p.y;
  double t = std::max({0.0, std::abs(ax) - a2, std::abs(by) - b2});
  for (int step = 0; step < 32; ++step) {
    const double u = ax / (t + a2), v = by / (t + b2);
    const double f = u * u + v * v - 1.0;
    if (f <= 1e-15) break;
    const double slope = -2.0 * (u * u / (t + a2) + v * v / (t + b2));
    const double next = t - f / slope;
    if (!(next > t)) break;
    t = next;
  }
  return glm::dvec2(a2 * p.x / (t + a2), b2 * p.y / (t + b2));
}

bool within_cone(glm::dvec2 s, double a, double b) {
  const double tiny = 1e-12;
  if (a <= 0.0 && std::abs(s.x) > tiny) return false;
  if (b <= 0.0 && std::abs(s.y) > tiny) return false;
  const double x = a > 0.0 ? s.x / a : 0.0, y = b > 0.0 ? s.y / b : 0.0;
  return x * x + y * y <= 1.0 + 1e-12;
}

}  // namespace

SwingTwistLimits make_swing_twist_limits(glm::vec3 axis, float swing1_degrees, float swing2_degrees,
                                         float twist_min_degrees, float twist_max_degrees) noexcept {
  SwingTwistLimits limits;
  const glm::dvec3 a = unit_or_x(axis);
  limits.axis = glm::vec3(a);
  limits.reference = glm::vec3(perpendicular(a, glm::dvec3(0.0)));
  limits.swing1 = radians_within(swing1_degrees, 0.0f, 180.0f);
  limits.swing2 = radians_within(swing2_degrees, 0.0f, 180.0f);
  limits.twist_min = radians_within(twist_min_degrees, -180.0f, 180.0f);
  limits.twist_max = radians_within(twist_max_degrees, -180.0f, 180.0f);
  if (limits.twist_min > limits.twist_max) std::swap(limits.twist_min, limits.twist_max);
  limits.active = true;
  return limits;
}

SwingTwistLimits swing_twist_from_euler(const DofLimits& euler, glm::vec3 axis) noexcept {
  const glm::dvec3 a = unit_or_x(axis), m = glm::abs(a);
  const int t = m.x >= m.y && m.x >= m.z ? 0 : (m.y >= m.z ? 1 : 2), i = (t + 1) % 3, j = (t + 2) % 3;
  const bool flipped = a[t] < 0.0;
  auto larger_bound = [&](int k) { return std::max(std::abs(euler.min[k]), std::abs(euler.max[k])); };
  SwingTwistLimits limits =
      make_swing_twist_limits(glm::vec3(a), larger_bound(i), larger_bound(j), flipped ? -euler.max[t] : euler.min[t],
                              flipped ? -euler.min[t] : euler.max[t]);
  glm::dvec3 e(0.0);
  e[i] = 1.0;
  limits.reference = glm::vec3(perpendicular(a, e));
  return limits;
}

glm::vec3 swing_twist_angles(const SwingTwistLimits& limits, glm::quat rotation) noexcept {
  const Split parts = split(limits, rotation);
  return glm::vec3(static_cast<float>(parts.s.x), static_cast<float>(parts.s.y), static_cast<float>(parts.twist));
}

bool clamp_swing_twist(const SwingTwistLimits& limits, glm::quat& rotation) noexcept {
  const float norm2 = glm::dot(rotation, rotation);
  const bool usable = norm2 > 1e-30f && std::isfinite(norm2);
  rotation = usable ? glm::normalize(rotation) : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const Split parts = split(limits, rotation);
  const double a = limits.swing1, b = limits.swing2, lo = limits.twist_min, hi = limits.twist_max;
  const bool cone = within_cone(parts.s, a, b);
  const bool twisted_in = outside(parts.twist, lo, hi) == 0.0;
  if (cone && twisted_in) return !usable;
  glm::dquat swing = parts.swing;
  if (!cone) {
    const glm::dvec2 s = nearest_on_ellipse(parts.s, a, b);
    const double angle = glm::length(s);
    const glm::dvec3 axis(limits.axis), b1(limits.reference), b2 = glm::cross(axis, b1);
    const glm::dvec3 u = angle > 1e-300 ? (s.x * b1 + s.y * b2) / angle : glm::dvec3(0.0);
    swing = glm::dquat(std::cos(0.5 * angle), u * std::sin(0.5 * angle));
  }
  double twist = parts.twist;
  if (!twisted_in) {
    const double to_min = twist < lo ? lo - twist : lo + 2.0 * pi - twist;
    const double to_max = twist > hi ? twist - hi : twist + 2.0 * pi - hi;
    twist = to_min <= to_max ? lo : hi;
  }
  const glm::dquat turn(std::cos(0.5 * twist), glm::dvec3(limits.axis) * std::sin(0.5 * twist));
  rotation = glm::quat(glm::normalize(swing * turn));
  return true;
}

void set_swing_twist(IkChain& chain, std::size_t joint, const SwingTwistLimits& limits) {
  if (joint >= chain.joint_count())
    throw Error::invalid_argument("joint " + std::to_string(joint), "not a joint of the chain");
  if (chain.swing_twist.empty()) chain.swing_twist.resize(chain.joint_count());
  chain.swing_twist[joint] = limits;
  chain.swing_twist[joint].active = true;
  chain.limits[joint] = EulerLimits{};
}

namespace detail {

bool clamp_chain_joint(const IkChain& chain, std::size_t k, glm::quat& rotation) noexcept {
  if (const SwingTwistLimits* limits = swing_twist_of(chain, k)) return clamp_swing_twist(*limits, rotation);
  return clamp_rotation(chain.limits[k], rotation);
}

bool clamp_chain_joint(const IkChain& chain, std::size_t k, glm::quat& local, bool reaim, glm::vec3 carried,
                       glm::vec3 wanted) noexcept {
  if (const SwingTwistLimits* limits = swing_twist_of(chain, k)) return clamp_swing_twist(*limits, local);
  return clamp_joint(chain.limits[k], local, reaim, carried, wanted);
}

}  // namespace detail
}  // namespace deform
