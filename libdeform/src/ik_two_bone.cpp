// The closed-form two-bone solver: law of cosines in 3D with a pole vector (thesis eqs. 14–28 without the plane).
#include <algorithm>
#include <cmath>

#include "deform/error.hpp"
#include "ik_chain.hpp"

namespace deform {
namespace {

constexpr float tiny = 1e-12f;

// Any unit vector perpendicular to `v` (non-zero).
glm::vec3 perpendicular(glm::vec3 v) {
  const glm::vec3 helper = std::abs(v.x) < 0.6f * glm::length(v) ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(v, helper));
}

// Angle at the vertex between directions u and v, radians in [0, π], accurate near 0 and π.
double angle_between(glm::vec3 u, glm::vec3 v) {
  const glm::dvec3 a(u), b(v);
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

}  // namespace

TwoBoneSolver::TwoBoneSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector)
    : skeleton_(&skeleton), chain_(make_chain(skeleton, root, effector)) {
  if (chain_.joint_count() != 2)
    throw Error::in_file("<ik>", "bone " + std::to_string(effector),
                         "the two-bone solver needs a chain of exactly two joints, '" + skeleton.key(root) + "' has " +
                             std::to_string(chain_.joint_count()) + " above '" + skeleton.key(effector) + "'");
}

bool TwoBoneSolver::solve(Pose& pose, glm::vec3 target, glm::vec3 pole, float tolerance, IkResult& result) const {
  if (!detail::pose_fits(*skeleton_, pose) || !detail::finite(target) || !detail::finite(pole) ||
      !std::isfinite(tolerance) || tolerance < 0.0f)
    return false;
  const auto upper = static_cast<std::size_t>(chain_.bones[0]);
  const auto lower = static_cast<std::size_t>(chain_.bones[1]);
  detail::clamp_joint(*skeleton_, pose, chain_.bones[0]);
  detail::clamp_joint(*skeleton_, pose, chain_.bones[1]);
  const detail::Frame base = detail::base_frame(chain_, pose);
  glm::quat frames[3];
  glm::vec3 heads[3];
  detail::chain_fk(chain_, pose, base, frames, heads);

  const glm::vec3 root = heads[0];
  const glm::vec3 to_target = target - root;
  const float a = glm::length(heads[1] - heads[0]);
  const float b = glm::length(heads[2] - heads[1]);
  const float target_distance = glm::length(to_target);

  // 1. The middle joint opens or closes about the limb's bend axis until |effector - root| is the reachable
  //    distance nearest the target's: c in [|a - b|, a + b], interior angle from the law of cosines.
  if (a > tiny && b > tiny) {
    const glm::vec3 u = heads[1] - heads[0], v = heads[2] - heads[1];
    glm::vec3 axis = glm::cross(u, v);
    if (glm::length(axis) < 1e-7f * a * b) {  // a straight limb: bend toward the pole, or any way
      axis = glm::cross(u, pole - u * (glm::dot(pole, u) / (a * a)));
      if (glm::length(axis) < 1e-7f * a * glm::length(pole) || glm::length(pole) <= tiny) axis = perpendicular(u);
    }
    axis = glm::normalize(axis);
    const double c = std::clamp(static_cast<double>(target_distance), std::abs(double(a) - double(b)),
                                double(a) + double(b));
    const double cosine = (double(a) * a + double(b) * b - c * c) / (2.0 * double(a) * b);
    const double wanted = std::acos(std::clamp(cosine, -1.0, 1.0));
    const double current = angle_between(-u, v);
    const glm::quat turn = glm::angleAxis(static_cast<float>(current - wanted), axis);
    pose.rotations[lower] = glm::conjugate(frames[0]) * turn * frames[1];
    detail::clamp_joint(*skeleton_, pose, chain_.bones[1]);
    detail::chain_fk(chain_, pose, base, frames, heads);
  }
  // 2. The root turns the effector onto the line to the target, 3. then twists about that line so the middle joint
  //    lies on the pole's side. A target on the root leaves the direction as it is; a pole on the line, the plane.
  if (target_distance > tiny) {
    glm::quat turn = detail::rotation_between(heads[2] - root, to_target);
    const glm::vec3 d = to_target / target_distance;
    const glm::vec3 mid = turn * (heads[1] - root);
    const glm::vec3 mid_across = mid - d * glm::dot(mid, d);
    const glm::vec3 pole_across = pole - d * glm::dot(pole, d);
    if (glm::length(mid_across) > 1e-6f * a && glm::length(pole_across) > 1e-6f * glm::length(pole)) {
      const float twist = std::atan2(glm::dot(glm::cross(mid_across, pole_across), d), glm::dot(mid_across, pole_across));
      turn = glm::angleAxis(twist, d) * turn;
    }
    pose.rotations[upper] = glm::conjugate(base.rotation) * turn * frames[0];
    detail::clamp_joint(*skeleton_, pose, chain_.bones[0]);
    detail::chain_fk(chain_, pose, base, frames, heads);
  }
  const float distance = glm::length(heads[2] - target);
  result = IkResult{distance <= tolerance, distance, 1};
  return true;
}

}  // namespace deform
