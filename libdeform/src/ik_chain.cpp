// IK chains: finding the bones from root to effector, and the helpers every solver shares (ik_chain.hpp).
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/error.hpp"
#include "ik_chain.hpp"

namespace deform {

namespace {

constexpr std::size_t max_chain_bones = 256;

}  // namespace

IkChain make_chain(const Skeleton& skeleton, std::int32_t root, std::int32_t effector) {
  const auto count = static_cast<std::int32_t>(skeleton.bone_count());
  auto bone_name = [&](std::int32_t id) { return "bone " + std::to_string(id); };
  if (root < 0 || root >= count) throw Error::in_file("<ik>", bone_name(root), "root bone out of range");
  if (effector < 0 || effector >= count) throw Error::in_file("<ik>", bone_name(effector), "effector out of range");
  if (root == effector || !skeleton.is_ancestor(root, effector))
    throw Error::in_file("<ik>", bone_name(effector),
                         "root '" + skeleton.key(root) + "' is not an ancestor of effector '" + skeleton.key(effector) + "'");
  IkChain chain;
  for (std::int32_t id = effector; id != root; id = skeleton.bone(id).parent) {
    chain.bones.push_back(id);
    if (chain.bones.size() >= max_chain_bones)
      throw Error::in_file("<ik>", bone_name(effector), "chain longer than 256 bones");
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

bool pose_fits(const Skeleton& skeleton, const Pose& pose) noexcept {
  return pose.rotations.size() == skeleton.bone_count() && pose.translations.size() == skeleton.bone_count();
}

Frame base_frame(const IkChain& chain, const Pose& pose) noexcept {
  Frame frame;
  for (const std::int32_t id : chain.ancestors) {
    const auto b = static_cast<std::size_t>(id);
    frame.translation += frame.rotation * pose.translations[b];
    frame.rotation = frame.rotation * pose.rotations[b];
  }
  return frame;
}

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

glm::quat rotation_between(glm::vec3 from, glm::vec3 to, float max_radians) noexcept {
  const float from_length = glm::length(from), to_length = glm::length(to);
  if (!(from_length > 1e-12f) || !(to_length > 1e-12f)) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const glm::vec3 a = from / from_length, b = to / to_length;
  const float cosine = glm::dot(a, b);
  glm::vec3 axis = glm::cross(a, b);
  const float sine = glm::length(axis);
  if (sine < 1e-7f) {
    if (cosine > 0.0f) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    // Opposite: any axis perpendicular to `a` does; take the one from the coordinate axis least aligned with it.
    const glm::vec3 helper = std::abs(a.x) < 0.6f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    axis = glm::normalize(glm::cross(a, helper));
    if (max_radians > 0.0f && max_radians < 3.14159265f) return glm::angleAxis(max_radians, axis);
    return glm::quat(0.0f, axis.x, axis.y, axis.z);
  }
  if (max_radians > 0.0f) {
    const float angle = std::atan2(sine, cosine);
    if (angle > max_radians) return glm::angleAxis(max_radians, axis / sine);
  }
  // q = (1 + cos θ, sin θ · n) normalised is the rotation by θ about n: no trigonometry needed.
  return glm::normalize(glm::quat(1.0f + cosine, axis.x, axis.y, axis.z));
}

bool clamp_joint(const Skeleton& skeleton, Pose& pose, std::int32_t bone) noexcept {
  const DofLimits& limits = skeleton.bones()[static_cast<std::size_t>(bone)].limits;
  const bool free = glm::all(glm::lessThanEqual(limits.min, glm::vec3(-180.0f))) &&
                    glm::all(glm::greaterThanEqual(limits.max, glm::vec3(180.0f)));
  glm::quat& rotation = pose.rotations[static_cast<std::size_t>(bone)];
  rotation = glm::normalize(rotation);
  if (free) return false;
  const glm::quat before = rotation;
  skeleton.clamp_to_limits(pose, bone);
  return rotation != before;
}

namespace {

float wrap_degrees(float a) { return a > 180.0f ? a - 360.0f : (a <= -180.0f ? a + 360.0f : a); }

// The joint's Euler triple that its limits mean: of the two triples of the rotation, the one nearer the limits,
// clamped (the rotation is in the limits already, so this only removes rounding).
glm::vec3 limited_euler(glm::quat rotation, const DofLimits& limits) {
  const glm::vec3 first = euler_from_quat(rotation);
  const glm::vec3 second(wrap_degrees(first.x + 180.0f), wrap_degrees(180.0f - first.y), wrap_degrees(first.z + 180.0f));
  auto miss = [&](glm::vec3 e) {
    const glm::vec3 d = e - clamp_euler(e, limits);
    return std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  };
  return clamp_euler(miss(second) < miss(first) ? second : first, limits);
}

// The angle in [min, max] (degrees) nearest, around the circle, to `best` (degrees): where the 1-D objective
// -cos(angle - best) is smallest.
float nearest_in_range(float best, float min, float max) {
  if (max - min >= 360.0f) return wrap_degrees(best);
  for (float shift : {-360.0f, 0.0f, 360.0f})
    if (best + shift >= min && best + shift <= max) return best + shift;
  const float to_min = std::abs(wrap_degrees(best - min)), to_max = std::abs(wrap_degrees(best - max));
  return to_min <= to_max ? min : max;
}

}  // namespace

void reaim_joint(const Skeleton& skeleton, Pose& pose, std::int32_t bone, glm::quat parent, glm::vec3 head,
                      glm::vec3 point, glm::vec3 goal) noexcept {
  const DofLimits& limits = skeleton.bones()[static_cast<std::size_t>(bone)].limits;
  glm::quat& rotation = pose.rotations[static_cast<std::size_t>(bone)];
  glm::vec3 euler = limited_euler(rotation, limits);
  // In the parent's frame, the point is R(euler) · carried and should be at wanted.
  const glm::vec3 carried = glm::conjugate(parent * rotation) * (point - head);
  const glm::vec3 wanted = glm::conjugate(parent) * (goal - head);
  static const glm::vec3 axes[3] = {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1)};
  for (int axis = 0; axis < 3; ++axis) {
    if (limits.min[axis] == limits.max[axis]) continue;
    // R = Rx · Ry · Rz: axis k turns v = (the rotations after k) · carried; compare with (those before k)⁻¹ · wanted.
    glm::quat before(1.0f, 0.0f, 0.0f, 0.0f), after(1.0f, 0.0f, 0.0f, 0.0f);
    for (int other = 0; other < 3; ++other) {
      const glm::quat q = glm::angleAxis(glm::radians(euler[other]), axes[other]);
      if (other < axis) before = before * q;
      if (other > axis) after = after * q;
    }
    const glm::vec3 v = after * carried, u = glm::conjugate(before) * wanted;
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;  // the plane the axis turns
    if (v[i] * v[i] + v[j] * v[j] < 1e-20f || u[i] * u[i] + u[j] * u[j] < 1e-20f) continue;
    const float best = glm::degrees(std::atan2(u[j], u[i]) - std::atan2(v[j], v[i]));
    euler[axis] = nearest_in_range(wrap_degrees(best), limits.min[axis], limits.max[axis]);
  }
  rotation = quat_from_euler(euler);
}

void point_segments_at(const Skeleton& skeleton, const IkChain& chain, Pose& pose, glm::quat base,
                       std::span<glm::quat> frames, std::span<glm::vec3> heads, glm::vec3 target) noexcept {
  for (std::size_t k = 0; k < chain.joint_count(); ++k) {
    const glm::quat parent = k == 0 ? base : frames[k - 1];
    const std::int32_t bone = chain.bones[k];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(bone)];
    const glm::vec3 offset = pose.translations[static_cast<std::size_t>(chain.bones[k + 1])];
    local = glm::conjugate(parent) * rotation_between((parent * local) * offset, target - heads[k]) * parent * local;
    if (clamp_joint(skeleton, pose, bone))
      reaim_joint(skeleton, pose, bone, parent, heads[k], heads[k] + (parent * local) * offset, target);
    frames[k] = parent * local;
    heads[k + 1] = heads[k] + frames[k] * offset;
  }
  frames[chain.joint_count()] = frames[chain.joint_count() - 1] *
                                pose.rotations[static_cast<std::size_t>(chain.bones.back())];
}

void damped_least_squares_step(const Skeleton& skeleton, const IkChain& chain, Pose& pose, glm::quat base,
                               std::span<const glm::quat> frames, std::span<const glm::vec3> heads, glm::vec3 target,
                               float lambda, std::span<glm::vec3> angles, std::span<glm::vec3> columns) noexcept {
  static const glm::vec3 axes[3] = {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1)};
  const std::size_t joints = chain.joint_count();
  const glm::vec3 effector = heads[joints];
  glm::dmat3 jjt(lambda * lambda);
  for (std::size_t k = 0; k < joints; ++k) {
    const DofLimits& limits = skeleton.bones()[static_cast<std::size_t>(chain.bones[k])].limits;
    const glm::vec3 euler = limited_euler(pose.rotations[static_cast<std::size_t>(chain.bones[k])], limits);
    angles[k] = euler;
    glm::quat frame = k == 0 ? base : frames[k - 1];
    for (int axis = 0; axis < 3; ++axis) {
      // Column of Euler axis `axis`: its world direction (after the axes before it) × (effector − head).
      // Axes locked, or at a limit with the error pulling outward, take no part (an active set).
      glm::vec3 column = glm::cross(frame * axes[axis], effector - heads[k]);
      const float pull = glm::dot(column, target - effector);
      const bool bounded = limits.max[axis] - limits.min[axis] < 360.0f;
      if (limits.min[axis] == limits.max[axis] ||
          (bounded && ((euler[axis] >= limits.max[axis] && pull > 0.0f) || (euler[axis] <= limits.min[axis] && pull < 0.0f))))
        column = glm::vec3(0.0f);
      columns[3 * k + static_cast<std::size_t>(axis)] = column;
      jjt += glm::outerProduct(glm::dvec3(column), glm::dvec3(column));
      frame = frame * glm::angleAxis(glm::radians(euler[axis]), axes[axis]);
    }
  }
  const glm::vec3 y(glm::inverse(jjt) * glm::dvec3(target - effector));
  for (std::size_t k = 0; k < joints; ++k) {
    const std::int32_t bone = chain.bones[k];
    const DofLimits& limits = skeleton.bones()[static_cast<std::size_t>(bone)].limits;
    glm::vec3 euler = angles[k];
    for (int axis = 0; axis < 3; ++axis)
      euler[axis] += glm::degrees(glm::dot(columns[3 * k + static_cast<std::size_t>(axis)], y));
    for (int axis = 0; axis < 3; ++axis)
      euler[axis] = limits.max[axis] - limits.min[axis] >= 360.0f
                        ? wrap_degrees(euler[axis])
                        : std::clamp(euler[axis], limits.min[axis], limits.max[axis]);
    pose.rotations[static_cast<std::size_t>(bone)] = quat_from_euler(euler);
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

void perturb_joints(const Skeleton& skeleton, const IkChain& chain, Pose& pose, std::uint32_t& state,
                    float degrees) noexcept {
  auto uniform = [&state]() {  // xorshift32, in [-1, 1)
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return static_cast<float>(state >> 8) * (2.0f / 16777216.0f) - 1.0f;
  };
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k) {
    const std::int32_t bone = chain.bones[k];
    const glm::vec3 delta(uniform() * degrees, uniform() * degrees, uniform() * degrees);
    glm::quat& rotation = pose.rotations[static_cast<std::size_t>(bone)];
    rotation = rotation * quat_from_euler(delta);
    clamp_joint(skeleton, pose, bone);
  }
}

bool settings_valid(glm::vec3 target, const IkSettings& settings) noexcept {
  return detail::finite(target) && settings.max_iterations >= 1 && std::isfinite(settings.tolerance) &&
         settings.tolerance >= 0.0f && std::isfinite(settings.max_step_degrees) && settings.max_step_degrees >= 0.0f;
}

}  // namespace detail
}  // namespace deform
