// The closed-form two-bone solver (TwoBoneIkJob, ik.hpp): law of cosines in 3D (thesis eqs. 14–28 without the
// plane) with a pole, swivel, soft extension, stretch and a weight.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "ik_chain.hpp"
#include "finite.hpp"

namespace deform {
namespace {

constexpr float tiny = 1e-12f;
// A bone shorter than this fraction of the limb counts as zero-length (validate refuses it).
constexpr float zero_bone_fraction = 1e-6f;

// Normalises `rotation` and clamps it into `limits` (clamp_rotation), the normalisation inline for a free joint.
// True when the limits moved it.
inline bool clamp_joint(const EulerLimits& limits, glm::quat& rotation) noexcept {
  if (!limits.free) return clamp_rotation(limits, rotation);
  rotation = glm::normalize(rotation);
  return false;
}

// The axis a straight or folded limb with no pole bends about: the middle joint's widest-ranging Euler axis (in its
// parent's frame, where its X·Y·Z rotations turn) that is not along the bone, made perpendicular to it, signed toward
// the side its range allows more of — so an elbow whose limits leave one hinge axis bends about that hinge. A free
// joint, or no such axis: any perpendicular.
glm::vec3 hinge_axis(const EulerLimits& middle, glm::vec3 bone) noexcept;

// Any unit vector perpendicular to `v` (non-zero).
glm::vec3 perpendicular(glm::vec3 v) noexcept {
  const glm::vec3 helper = std::abs(v.x) < 0.6f * glm::length(v) ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(v, helper));
}

// `rotation` turned toward `solved` by the fraction `weight` in (0, 1) of the shortest rotation between them (slerp
// on the nearer hemisphere; unit inputs, unit result). Nearly equal rotations blend linearly, normalised.
glm::quat slerp(glm::quat rotation, glm::quat solved, float weight) noexcept {
  float cosine = glm::dot(rotation, solved);
  if (cosine < 0.0f) solved = -solved, cosine = -cosine;
  float from = 1.0f - weight, to = weight;
  if (cosine < 0.9995f) {
    // sin((1 − w)θ) / sin θ = cos wθ − cos θ · sin wθ / sin θ: one arc cosine, one sine and cosine.
    const float angle = weight * std::acos(cosine), sine = std::sqrt(1.0f - cosine * cosine);
    const float part_sine = std::sin(angle) / sine;
    from = std::cos(angle) - cosine * part_sine;
    to = part_sine;
  }
  return glm::normalize(glm::quat(rotation.w * from + solved.w * to, rotation.x * from + solved.x * to,
                                  rotation.y * from + solved.y * to, rotation.z * from + solved.z * to));
}

// The quaternion (not normalised) of the turn about unit `axis` whose cosine and sine, both times `length`, are
// `turn`. `axis` may instead be the unit axis times `axis_length` > 0: the quaternion is then that much larger.
glm::quat turn_quat(glm::vec3 axis, glm::dvec2 turn, double length, float axis_length = 1.0f) noexcept {
  const glm::dvec2 half = detail::scaled_half_angle(turn, length);
  const glm::vec3 v = axis * static_cast<float>(half.y);
  return glm::quat(static_cast<float>(half.x) * axis_length, v.x, v.y, v.z);
}

// The solve at full weight: the joints' new local rotations (unit), the stretch factor, the unstretched limb root →
// effector in the upper bone's frame (u + lower · lower_offset) and, when no limit moved a joint, the effector
// relative to the root's head in the root parent's frame (it lies on the line to the target).
struct Solved {
  glm::quat upper, lower;
  double stretch = 1.0;
  bool clamped = false;
  glm::vec3 limb{0.0f};
  glm::vec3 effector{0.0f};
};

// Steps 1–4 of ik.hpp. `upper` and `lower` are the normalised input rotations; `u` and `lower_offset` the middle and
// effector bones' translations (lengths a, b > 0); `to_target` and `pole` are in the root parent's frame relative to
// the root's head (`pole` already a vector, from the root for a point).
Solved solve(const TwoBoneIkJob& job, glm::quat upper, glm::quat lower, glm::vec3 u, glm::vec3 lower_offset, double a,
             double b, glm::vec3 to_target, glm::vec3 pole) noexcept {
  const EulerLimits* limits = job.chain->limits.data();  // root, middle
  Solved out;
  // 1. The limb's root–effector distance c: the target's, softened near full extension, at least the folded limb's.
  const double r2 = glm::dot(glm::dvec3(to_target), glm::dvec3(to_target)), r = std::sqrt(r2);
  const double reach = a + b, fold = std::abs(a - b), inverse_ab = 1.0 / (a * b);
  double c = std::min(r, reach);
  if (job.soften > 0.0f) {
    const double zone = static_cast<double>(job.soften) * reach, start = reach - zone;
    // c = L − kL·exp((L − r)/(kL) − 1) = start − zone·expm1((start − r)/zone), exact near r = start.
    if (r > start) c = start - zone * std::expm1((start - r) / zone);
  }
  c = std::max(c, fold);
  // c² for the law of cosines: unsoftened, min(r², reach²) kept at least fold², which is c · c to rounding without
  // waiting for the square root of r² (the longest path into the bend).
  const double c2 = job.soften > 0.0f ? c * c : std::max(std::min(r2, reach * reach), fold * fold);
  if (job.max_stretch > 1.0f && r > c && c > 0.0) out.stretch = std::min(r / c, static_cast<double>(job.max_stretch));

  // 2. In the upper bone's frame, the middle joint turns about the bend axis until |u + v| = c: the turn (current −
  //    wanted interior angle) from cosines and sines, the wanted one's from the law of cosines.
  glm::vec3 v = lower * lower_offset;  // middle → effector, upper's frame
  const glm::dvec3 cross = glm::cross(glm::dvec3(u), glm::dvec3(v));
  const double sine = glm::length(cross);  // a · b · sin(interior angle)
  glm::vec3 axis;                          // unit
  glm::vec3 turn_axis;  // axis times turn_axis_length: the turn's quaternion need not wait for the division
  float turn_axis_length = 1.0f;
  if (sine < 1e-7 * a * b) {  // straight or folded: bend toward the pole, or about any perpendicular
    const glm::vec3 upper_pole = glm::conjugate(upper) * pole;
    axis = glm::cross(u, upper_pole);
    const float axis_length = glm::length(axis);
    axis = axis_length > 1e-6f * static_cast<float>(a) * glm::length(upper_pole) && axis_length > tiny
               ? axis / axis_length
               : hinge_axis(limits[1], u);
    turn_axis = axis;
  } else {
    axis = glm::vec3(cross * (1.0 / sine));
    turn_axis = glm::vec3(cross);
    turn_axis_length = static_cast<float>(sine);
  }
  const glm::dvec2 current(-glm::dot(glm::dvec3(u), glm::dvec3(v)), sine);  // (cos, sin) · a · b
  const double cos_wanted = std::clamp((a * a + b * b - c2) * (0.5 * inverse_ab), -1.0, 1.0);
  const glm::dvec2 wanted(cos_wanted, std::sqrt(1.0 - cos_wanted * cos_wanted));
  const glm::dvec2 turn(current.x * wanted.x + current.y * wanted.y, current.y * wanted.x - current.x * wanted.y);
  lower = turn_quat(turn_axis, turn, a * b, turn_axis_length) * lower;
  // v turned (Rodrigues, v ⊥ axis), or from the pose again when the limit moved the joint (the clamp normalises).
  const glm::vec3 turned_v =
      static_cast<float>(turn.x * inverse_ab) * v + static_cast<float>(turn.y * inverse_ab) * glm::cross(axis, v);
  out.clamped = clamp_joint(limits[1], lower);
  v = out.clamped ? lower * lower_offset : turned_v;
  // The bend plane's normal, u × v, or the turn's axis where the limb ends straight or folded.
  glm::vec3 normal = glm::cross(u, v);
  if (glm::dot(normal, normal) <= 1e-12f * static_cast<float>(a * a * b * b)) normal = axis;

  // 3. The root turns the effector onto the line to the target; a target on the root keeps the limb's direction.
  glm::vec3 effector = upper * (u + v);
  glm::vec3 d;
  if (r > 1e-9 * reach) {
    upper = detail::rotation_between(effector, to_target) * upper;
    d = to_target * static_cast<float>(1.0 / r);
  } else {
    const float length = glm::length(effector);
    d = length > 1e-9f * static_cast<float>(reach) ? effector / length : glm::vec3(0.0f);
  }
  //    Then it twists about that line, turning the middle joint's direction across it (d × normal) onto the
  //    reference: the pole's part across the line, blended into the limb's own direction inside the cone.
  //    (bend is the unit direction times bend_length, left unscaled: the twist below is then that much longer, which
  //    it is told; only the blend inside the cone divides.)
  const glm::vec3 bend = glm::cross(d, upper * normal);
  const float bend_length = glm::length(bend);
  if (bend_length > tiny) {
    glm::vec3 reference = bend * (1.0f / bend_length);  // (not on the path of a pole outside the cone)
    bool unit_reference = true;
    const float pole2 = glm::dot(pole, pole);
    if (pole2 > 0.0f) {
      const glm::vec3 across = pole - d * glm::dot(pole, d);
      const float across2 = glm::dot(across, across);
      constexpr float cone2 = two_bone_pole_cone_sine * two_bone_pole_cone_sine;
      if (across2 >= cone2 * pole2) {
        reference = across / std::sqrt(across2);
      } else if (across2 > 0.0f) {
        const float across_length = std::sqrt(across2);
        const float t = across_length / (std::sqrt(pole2) * two_bone_pole_cone_sine);
        const float blend = t * t * (3.0f - 2.0f * t);
        reference = across * (blend / across_length) + bend * ((1.0f - blend) / bend_length);
        unit_reference = false;
      }
    }
    if (job.swivel_degrees != 0.0f) {
      const float angle = job.swivel_degrees * (std::numbers::pi_v<float> / 180.0f);
      reference = reference * std::cos(angle) + glm::cross(d, reference) * std::sin(angle);
    }
    // (cos, sin) of the twist times bend_length · |reference|, |reference| being 1 to rounding outside the cone: the
    // clamp below normalises what that leaves.
    const glm::dvec2 twist(glm::dot(bend, reference), glm::dot(glm::cross(bend, reference), d));
    const double twist_length = unit_reference ? static_cast<double>(bend_length) : glm::length(twist);
    if (twist_length > 1e-6 * bend_length) upper = turn_quat(d, twist, twist_length) * upper;
  }
  if (clamp_joint(limits[0], upper)) out.clamped = true;  // (normalises)
  out.upper = upper;
  out.lower = lower;
  // The twist keeps the effector on the line; |u + v| is the bent limb's length.
  out.limb = u + v;
  if (!out.clamped) out.effector = d * (glm::length(out.limb) * static_cast<float>(out.stretch));
  return out;
}

// validate() with the bone lengths it measured (a, b) for run(), one check after another, each failure named: the
// slow path, which run() takes only when passes() has failed.
Status explain(const TwoBoneIkJob& job, float& a, float& b) noexcept {
  const IkChain* chain = job.chain;
  const auto& rotations = job.rotations;
  const auto& translations = job.translations;
  const float tolerance = job.tolerance, soften = job.soften, weight = job.weight, max_stretch = job.max_stretch;
  if (chain == nullptr || chain->joint_count() != 2 || chain->limits.size() != 2)
    return Status::failure("chain does not have two joints");
  for (const SwingTwistLimits& joint : chain->swing_twist)
    if (joint.active) return Status::failure("chain has swing-twist limits (the two-bone solver takes Euler limits)");
  const auto needed = static_cast<std::size_t>(chain->max_bone) + 1;
  if (chain->max_bone < 0 || rotations.size() < needed || translations.size() < needed)
    return Status::failure("pose spans do not hold every chain bone");
  if (!job.stretched_translations.empty() && job.stretched_translations.size() < needed)
    return Status::failure("stretched_translations do not hold every chain bone");
  if (!std::isfinite(tolerance) || tolerance < 0.0f) return Status::failure("tolerance not finite and >= 0");
  if (!(soften >= 0.0f && soften <= 1.0f)) return Status::failure("soften not within [0, 1]");
  if (!(weight >= 0.0f && weight <= 1.0f)) return Status::failure("weight not within [0, 1]");
  if (!(max_stretch >= 1.0f) || !std::isfinite(max_stretch)) return Status::failure("max_stretch not finite and >= 1");
  if (!(std::abs(job.swivel_degrees) <= 360.0f)) return Status::failure("swivel_degrees not within [-360, 360]");
  if (job.pole_kind != PoleKind::direction && job.pole_kind != PoleKind::point)
    return Status::failure("pole_kind is not direction or point");
  if (!finite(job.target)) return Status::failure("target is not finite");
  if (!finite(job.pole)) return Status::failure("pole is not finite");
  if (!finite(job.base.rotation) || !finite(job.base.translation)) return Status::failure("base is not finite");
  // Each number times 0 is 0 when finite and NaN when not: one test for the 21 (no -ffinite-math-only here).
  float zero = 0.0f;
  for (const std::int32_t id : chain->bones) {
    const glm::quat q = rotations[static_cast<std::size_t>(id)];
    const glm::vec3 t = translations[static_cast<std::size_t>(id)];
    zero += q.x * 0.0f + q.y * 0.0f + q.z * 0.0f + q.w * 0.0f + t.x * 0.0f + t.y * 0.0f + t.z * 0.0f;
  }
  if (!(zero == 0.0f)) return Status::failure("chain pose is not finite");
  a = glm::length(translations[static_cast<std::size_t>(chain->bones[1])]);
  b = glm::length(translations[static_cast<std::size_t>(chain->bones[2])]);
  if (!std::isfinite(a + b)) return Status::failure("chain length overflows");
  if (!(std::min(a, b) > zero_bone_fraction * (a + b))) return Status::failure("limb has a zero-length bone");
  return {};
}

// The checks of explain() folded for the job that passes them, which is every job of a running rig: the comparisons
// joined with & (no branch each) and the finiteness of the 28 numbers read as one sum (each times 0 is 0 when
// finite, NaN when not; no -ffinite-math-only here). True only when explain() would succeed, with the same a and b
// (it measures them alike); false sends run() to explain() for the verdict and its message. It was 11% of a free
// solve as a chain of 30 tests. (Clang warns on & between bools; here it is the point.)
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wbitwise-instead-of-logical"
#endif
bool passes(const TwoBoneIkJob& job, float& a, float& b) noexcept {
  const IkChain* chain = job.chain;
  if (chain == nullptr || chain->bones.size() != 3 || chain->limits.size() != 2 || !chain->swing_twist.empty())
    return false;  // (inactive swing-twist entries are allowed: explain() says so)
  const auto needed = static_cast<std::size_t>(chain->max_bone) + 1;
  const bool fits = (chain->max_bone >= 0) & (job.rotations.size() >= needed) & (job.translations.size() >= needed) &
                    (job.stretched_translations.empty() | (job.stretched_translations.size() >= needed));
  const bool in_range = (job.tolerance >= 0.0f) & (job.soften >= 0.0f) & (job.soften <= 1.0f) & (job.weight >= 0.0f) &
                        (job.weight <= 1.0f) & (job.max_stretch >= 1.0f) & (std::abs(job.swivel_degrees) <= 360.0f) &
                        ((job.pole_kind == PoleKind::direction) | (job.pole_kind == PoleKind::point));
  if (!(fits & in_range)) return false;
  const glm::quat r = job.base.rotation;
  const glm::vec3 sum = job.target + job.pole + job.base.translation + glm::vec3(r.x, r.y, r.z) +
                        glm::vec3(r.w, job.tolerance, job.max_stretch);
  glm::vec3 zero = sum * 0.0f;
  for (const std::int32_t id : chain->bones) {
    const glm::quat q = job.rotations[static_cast<std::size_t>(id)];
    zero += (glm::vec3(q.x, q.y, q.z) + glm::vec3(q.w) + job.translations[static_cast<std::size_t>(id)]) * 0.0f;
  }
  a = glm::length(job.translations[static_cast<std::size_t>(chain->bones[1])]);
  b = glm::length(job.translations[static_cast<std::size_t>(chain->bones[2])]);
  // (a + b) · 0 is NaN when the length overflows.
  return (zero.x + zero.y + zero.z + (a + b) * 0.0f == 0.0f) & (std::min(a, b) > zero_bone_fraction * (a + b));
}
#if defined(__clang__)
#pragma clang diagnostic pop
#endif

glm::vec3 hinge_axis(const EulerLimits& middle, glm::vec3 bone) noexcept {
  const glm::vec3 along = glm::normalize(bone);
  if (middle.free) return perpendicular(bone);
  int best = -1;
  double widest = 0.0;
  for (int k = 0; k < 3; ++k) {
    glm::vec3 e(0.0f);
    e[k] = 1.0f;
    const double width = middle.max[k] - middle.min[k];
    if (std::abs(glm::dot(e, along)) < 0.9f && width > widest) widest = width, best = k;
  }
  if (best < 0) return perpendicular(bone);
  glm::vec3 e(0.0f);
  e[best] = middle.max[best] >= -middle.min[best] ? 1.0f : -1.0f;
  return glm::normalize(e - glm::dot(e, along) * along);
}

}  // namespace

Status TwoBoneIkJob::validate() const noexcept {
  float a = 0.0f, b = 0.0f;
  return passes(*this, a, b) ? Status() : explain(*this, a, b);
}

Status TwoBoneIkJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (begin > end || end > count()) return Status::failure("range out of bounds");
  return begin == end ? Status() : run();
}

Status TwoBoneIkJob::run() const noexcept {
  float a = 0.0f, b = 0.0f;
  if (!passes(*this, a, b))
    if (const Status status = explain(*this, a, b); !status) return status;
  const auto root = static_cast<std::size_t>(chain->bones[0]);
  const auto middle = static_cast<std::size_t>(chain->bones[1]);
  const auto end = static_cast<std::size_t>(chain->bones[2]);
  // (glm turns vectors by unit quaternions only.)
  const glm::quat upper_in = glm::normalize(rotations[root]), lower_in = glm::normalize(rotations[middle]);
  const glm::vec3 u = translations[middle], lower_offset = translations[end];
  // The target and the pole in the root parent's frame, relative to the root's head.
  const glm::quat to_base = glm::conjugate(base.rotation);
  const glm::vec3 to_target = to_base * (target - base.translation) - translations[root];
  const glm::vec3 base_pole =
      pole_kind == PoleKind::point ? to_base * (pole - base.translation) - translations[root] : to_base * pole;

  glm::quat upper = upper_in, lower = lower_in;
  float factor = 1.0f;
  bool effector_known = false, limb_known = false;
  glm::vec3 effector(0.0f), limb(0.0f);
  if (weight > 0.0f) {
    const Solved solved = solve(*this, upper_in, lower_in, u, lower_offset, a, b, to_target, base_pole);
    upper = solved.upper;
    lower = solved.lower;
    factor = static_cast<float>(solved.stretch);
    effector_known = weight == 1.0f && !solved.clamped;
    effector = solved.effector;
    limb_known = weight == 1.0f;  // (a blend moves the lower joint: its limb is measured again below)
    limb = solved.limb;
    if (weight < 1.0f) {
      upper = slerp(upper_in, upper, weight);
      lower = slerp(lower_in, lower, weight);
      // (slerp normalised them: a free joint needs nothing more.)
      if (!chain->limits[0].free) clamp_rotation(chain->limits[0], upper);
      if (!chain->limits[1].free) clamp_rotation(chain->limits[1], lower);
      factor = 1.0f + weight * (factor - 1.0f);
    }
    rotations[root] = upper;
    rotations[middle] = lower;
  }
  if (!stretched_translations.empty()) {
    stretched_translations[middle] = u * factor;
    stretched_translations[end] = lower_offset * factor;
  }
  if (!limb_known) limb = u + lower * lower_offset;
  if (!effector_known) effector = upper * (limb * factor);
  const float distance = glm::length(effector - to_target);
  if (stretch != nullptr) *stretch = factor;
  if (result != nullptr) *result = IkResult{distance <= tolerance, distance, 1};
  return {};
}

}  // namespace deform
