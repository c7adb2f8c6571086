// The closed-form two-bone solver: law of cosines in 3D with a pole vector (thesis eqs. 14–28 without the plane).
#include <algorithm>
#include <cmath>

#include "ik_chain.hpp"

namespace deform::detail {
namespace {

constexpr float tiny = 1e-12f;

// Any unit vector perpendicular to `v` (non-zero).
glm::vec3 perpendicular(glm::vec3 v) {
  const glm::vec3 helper = std::abs(v.x) < 0.6f * glm::length(v) ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(v, helper));
}

}  // namespace

IkResult solve_two_bone(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target, glm::vec3 pole,
                        float tolerance) noexcept {
  const EulerLimits* limits = chain.limits.data();  // root, middle
  glm::quat& upper = pose.rotations[static_cast<std::size_t>(chain.bones[0])];
  glm::quat& lower = pose.rotations[static_cast<std::size_t>(chain.bones[1])];
  const glm::vec3 u = pose.translations[static_cast<std::size_t>(chain.bones[1])];  // root → middle, upper's frame
  const glm::vec3 lower_offset = pose.translations[static_cast<std::size_t>(chain.bones[2])];
  // The start pose is only normalised: the answer's root rotation does not depend on it (the effector line and the
  // pole fix it) and the middle joint is clamped after its turn, so clamping the start as well would not change the
  // limits the answer keeps, only cost two more clamps.
  upper = glm::normalize(upper);
  lower = glm::normalize(lower);
  // Steps 2 and 3 work in the frame of the root's parent with the root's head at the origin, where the upper
  // bone's rotation turns the limb directly; the target and the pole are brought there once.
  const glm::quat to_base = glm::conjugate(base.rotation);
  const glm::vec3 to_target =
      to_base * (target - base.translation) - pose.translations[static_cast<std::size_t>(chain.bones[0])];
  const glm::vec3 base_pole = to_base * pole;
  const float target_distance = glm::length(to_target);
  const double a = glm::length(u), b = glm::length(lower_offset);
  glm::vec3 v = lower * lower_offset;  // middle → effector, upper's frame

  // 1. In the upper bone's frame, the middle joint opens or closes about the limb's bend axis until |effector −
  //    root| is the reachable distance c nearest the target's, c in [|a − b|, a + b]: the interior angle's cosine
  //    from the law of cosines. The turn (current − wanted interior angle) is built from cosines and sines.
  if (a > tiny && b > tiny) {
    const glm::dvec3 cross = glm::cross(glm::dvec3(u), glm::dvec3(v));
    const double sine = glm::length(cross);  // a · b · sin(interior angle)
    glm::vec3 axis;
    if (sine < 1e-7 * a * b) {  // a straight limb: bend toward the pole, or any way
      const glm::vec3 upper_pole = glm::conjugate(upper) * base_pole;
      axis = glm::cross(u, upper_pole - u * (glm::dot(upper_pole, u) / static_cast<float>(a * a)));
      axis = glm::length(axis) < 1e-7f * static_cast<float>(a) * glm::length(pole) || glm::length(pole) <= tiny
                 ? perpendicular(u)
                 : glm::normalize(axis);
    } else {
      axis = glm::vec3(cross / sine);
    }
    const glm::dvec2 current(-glm::dot(glm::dvec3(u), glm::dvec3(v)), sine);  // (cos, sin) · a · b
    const double c = std::clamp(static_cast<double>(target_distance), std::abs(a - b), a + b);
    const double cos_wanted = std::clamp((a * a + b * b - c * c) / (2.0 * a * b), -1.0, 1.0);
    const glm::dvec2 wanted(cos_wanted, std::sqrt(1.0 - cos_wanted * cos_wanted));
    const glm::dvec2 turn(current.x * wanted.x + current.y * wanted.y, current.y * wanted.x - current.x * wanted.y);
    // The turn's quaternion from its half angle, normalised by the clamp; v turned with it (Rodrigues, v ⊥ axis),
    // or from the pose again when a limit moved the joint.
    const glm::dvec2 half = scaled_half_angle(turn, a * b);
    const glm::vec3 turn_axis = axis * static_cast<float>(half.y);
    lower = glm::quat(static_cast<float>(half.x), turn_axis.x, turn_axis.y, turn_axis.z) * lower;
    const glm::vec3 turned_v = static_cast<float>(turn.x / (a * b)) * v +
                               static_cast<float>(turn.y / (a * b)) * glm::cross(axis, v);
    v = clamp_rotation(limits[1], lower) ? lower * lower_offset : turned_v;
  }
  // 2. The root turns the effector onto the line to the target, 3. then twists about that line so the middle joint
  //    lies on the pole's side. A target on the root leaves the direction as it is; a pole on the line, the plane.
  glm::vec3 effector = upper * (u + v);
  if (target_distance > tiny) {
    const glm::quat turned = rotation_between(effector, to_target) * upper;
    const glm::vec3 d = to_target * (1.0f / target_distance);
    const glm::vec3 mid = turned * u;
    const glm::vec3 mid_across = mid - d * glm::dot(mid, d);
    const glm::vec3 pole_across = base_pole - d * glm::dot(base_pole, d);
    const float mid_across2 = glm::dot(mid_across, mid_across), pole_across2 = glm::dot(pole_across, pole_across);
    upper = turned;
    if (mid_across2 > 1e-12f * static_cast<float>(a * a) && pole_across2 > 1e-12f * glm::dot(base_pole, base_pole)) {
      // The twist from mid_across to pole_across: cosine and sine times |mid_across| |pole_across|.
      const glm::dvec2 half = scaled_half_angle(
          glm::dvec2(glm::dot(mid_across, pole_across), glm::dot(glm::cross(mid_across, pole_across), d)),
          std::sqrt(static_cast<double>(mid_across2) * static_cast<double>(pole_across2)));
      const glm::vec3 twist_axis = d * static_cast<float>(half.y);
      upper = glm::quat(static_cast<float>(half.x), twist_axis.x, twist_axis.y, twist_axis.z) * turned;
    }
    // The limb now lies along the line to the target, unless a limit moved the root. (The clamp also normalises.)
    effector = clamp_rotation(limits[0], upper) ? upper * (u + v) : d * glm::length(effector);
  }
  const float distance = glm::length(effector - to_target);
  return IkResult{distance <= tolerance, distance, 1};
}

}  // namespace deform::detail
