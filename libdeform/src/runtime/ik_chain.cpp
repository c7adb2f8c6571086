// IK chains: finding the bones from root to effector, and the helpers every solver shares (ik_chain.hpp).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "deform/runtime/error.hpp"
#include "ik_chain.hpp"

namespace deform {

namespace {

constexpr std::size_t max_chain_bones = 256;

}  // namespace

IkChain make_chain(const Skeleton& skeleton, std::int32_t root, std::int32_t effector) {
  const auto count = static_cast<std::int32_t>(skeleton.bone_count());
  auto bone_name = [&](std::int32_t id) { return "bone " + std::to_string(id); };
  if (root < 0 || root >= count) throw Error::invalid_argument(bone_name(root), "root bone out of range");
  if (effector < 0 || effector >= count) throw Error::invalid_argument(bone_name(effector), "effector out of range");
  if (root == effector || !skeleton.is_ancestor(root, effector))
    throw Error::invalid_argument(bone_name(effector),
                         "root '" + skeleton.key(root) + "' is not an ancestor of effector '" + skeleton.key(effector) + "'");
  IkChain chain;
  for (std::int32_t id = effector; id != root; id = skeleton.bone(id).parent) {
    chain.bones.push_back(id);
    if (chain.bones.size() >= max_chain_bones)
      throw Error::invalid_argument(bone_name(effector), "chain longer than 256 bones");
  }
  chain.bones.push_back(root);
  std::reverse(chain.bones.begin(), chain.bones.end());
  for (std::int32_t id = skeleton.bone(root).parent; id >= 0; id = skeleton.bone(id).parent) chain.ancestors.push_back(id);
  std::reverse(chain.ancestors.begin(), chain.ancestors.end());
  return chain;
}

float chain_length(const IkChain& chain, const Pose& pose) noexcept {
  float length = 0.0f;
  for (std::size_t k = 1; k < chain.bones.size(); ++k)
    length += glm::length(pose.translations[static_cast<std::size_t>(chain.bones[k])]);
  return length;
}

glm::vec3 effector_position(const Skeleton& skeleton, const IkChain& chain, const Pose& pose) noexcept {
  if (!detail::pose_fits(skeleton, pose) || chain.bones.empty()) return glm::vec3(0.0f);
  detail::Frame frame = detail::base_frame(chain, pose);
  for (std::size_t k = 0; k < chain.bones.size(); ++k) {
    const auto b = static_cast<std::size_t>(chain.bones[k]);
    frame.translation += frame.rotation * pose.translations[b];
    frame.rotation = frame.rotation * pose.rotations[b];
  }
  return frame.translation;
}

namespace detail {

void chain_fk(const IkChain& chain, const Pose& pose, const Frame& base, std::span<glm::quat> rotations,
              std::span<glm::vec3> heads) noexcept {
  glm::quat rotation = base.rotation;
  glm::vec3 head = base.translation;
  for (std::size_t k = 0; k < chain.bones.size(); ++k) {
    const auto b = static_cast<std::size_t>(chain.bones[k]);
    head += rotation * pose.translations[b];
    rotation = rotation * pose.rotations[b];
    rotations[k] = rotation;
    heads[k] = head;
  }
}

StepCap cap_for(float max_radians) noexcept {
  if (!(max_radians > 0.0f) || max_radians >= std::numbers::pi_v<float>) return {};
  return {std::cos(max_radians), glm::vec2(std::cos(0.5f * max_radians), std::sin(0.5f * max_radians))};
}

std::vector<EulerLimits> prepare_chain_limits(const Skeleton& skeleton, const IkChain& chain) {
  std::vector<EulerLimits> limits(chain.joint_count());
  for (std::size_t k = 0; k < limits.size(); ++k)
    limits[k] = prepare_limits(skeleton.bones()[static_cast<std::size_t>(chain.bones[k])].limits);
  return limits;
}

void point_segments_at(const IkChain& chain, std::span<const EulerLimits> limits, Pose& pose, glm::quat base,
                       std::span<glm::quat> frames, std::span<glm::vec3> heads, glm::vec3 target) noexcept {
  for (std::size_t k = 0; k < chain.joint_count(); ++k) {
    const glm::quat parent = k == 0 ? base : frames[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    const glm::vec3 offset = pose.translations[static_cast<std::size_t>(chain.bones[k + 1])];
    const glm::vec3 wanted = glm::conjugate(parent) * (target - heads[k]);
    local = rotation_between(local * offset, wanted) * local;
    clamp_joint(limits[k], local, true, offset, wanted);
    frames[k] = parent * local;
    heads[k + 1] = heads[k] + frames[k] * offset;
  }
  frames[chain.joint_count()] = frames[chain.joint_count() - 1] *
                                pose.rotations[static_cast<std::size_t>(chain.bones.back())];
}

namespace {

constexpr double at_limit = 1e-6;  // radians

}  // namespace

void damped_least_squares_step(const IkChain& chain, std::span<const EulerLimits> limits, Pose& pose, glm::quat base,
                               std::span<const glm::quat> frames, std::span<const glm::vec3> heads, glm::vec3 target,
                               float lambda, bool angles_current, std::span<glm::dvec3> angles,
                               std::span<glm::vec3> columns) noexcept {
  const std::size_t joints = chain.joint_count();
  const glm::vec3 effector = heads[joints];
  glm::dmat3 jjt(lambda * lambda);
  for (std::size_t k = 0; k < joints; ++k) {
    EulerAngles euler;
    if (angles_current) {
      euler = euler_at(limits[k], angles[k]);
    } else {
      limit_euler(limits[k], pose.rotations[static_cast<std::size_t>(chain.bones[k])], euler);
      angles[k] = euler.angle;
    }
    // Euler axis k turns about its world direction: the parent's frame times the rotations of the axes before it.
    const glm::mat3 parent = glm::mat3_cast(k == 0 ? base : frames[k - 1]);
    const glm::vec2 x(euler.dir[0]), y(euler.dir[1]);
    const glm::vec3 axes[3] = {parent[0], x.x * parent[1] + x.y * parent[2],
                               y.y * parent[0] + y.x * (x.x * parent[2] - x.y * parent[1])};
    for (int axis = 0; axis < 3; ++axis) {
      // Column of Euler axis `axis`: its world direction × (effector − head). Axes locked, or at a limit (to the
      // float rounding of a clamped rotation, 1e-6 rad) with the error pulling outward, take no part (an active set).
      glm::vec3 column = glm::cross(axes[axis], effector - heads[k]);
      const float pull = glm::dot(column, target - effector);
      const double min = limits[k].min[axis], max = limits[k].max[axis], angle = euler.angle[axis];
      const bool bounded = max - min < 2.0 * std::numbers::pi;
      if (min == max ||
          (bounded && ((angle >= max - at_limit && pull > 0.0f) || (angle <= min + at_limit && pull < 0.0f))))
        column = glm::vec3(0.0f);
      columns[3 * k + static_cast<std::size_t>(axis)] = column;
      jjt += glm::outerProduct(glm::dvec3(column), glm::dvec3(column));
    }
  }
  const glm::vec3 y(glm::inverse(jjt) * glm::dvec3(target - effector));
  for (std::size_t k = 0; k < joints; ++k) {
    const EulerLimits& limit = limits[k];
    for (int axis = 0; axis < 3; ++axis) {
      const double min = limit.min[axis], max = limit.max[axis];
      double& angle = angles[k][axis];
      angle += static_cast<double>(glm::dot(columns[3 * k + static_cast<std::size_t>(axis)], y));
      angle = max - min >= 2.0 * std::numbers::pi ? std::remainder(angle, 2.0 * std::numbers::pi)
                                                  : std::clamp(angle, min, max);
    }
    pose.rotations[static_cast<std::size_t>(chain.bones[k])] = to_quat(euler_at(limit, angles[k]));
  }
}

void save_joints(const IkChain& chain, const Pose& pose, std::span<glm::quat> saved) noexcept {
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k)
    saved[k] = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
}

void load_joints(const IkChain& chain, std::span<const glm::quat> saved, Pose& pose) noexcept {
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k)
    pose.rotations[static_cast<std::size_t>(chain.bones[k])] = saved[k];
}

void perturb_joints(const IkChain& chain, std::span<const EulerLimits> limits, Pose& pose, std::uint32_t& state,
                    float degrees) noexcept {
  auto uniform = [&state]() {  // xorshift32, in [-1, 1)
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return static_cast<float>(state >> 8) * (2.0f / 16777216.0f) - 1.0f;
  };
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k) {
    const glm::vec3 delta(uniform() * degrees, uniform() * degrees, uniform() * degrees);
    glm::quat& rotation = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    rotation = rotation * quat_from_euler(delta);
    clamp_rotation(limits[k], rotation);
  }
}

bool settings_valid(glm::vec3 target, const IkSettings& settings) noexcept {
  return detail::finite(target) && settings.max_iterations >= 1 && std::isfinite(settings.tolerance) &&
         settings.tolerance >= 0.0f && std::isfinite(settings.max_step_degrees) && settings.max_step_degrees >= 0.0f;
}

}  // namespace detail
}  // namespace deform
