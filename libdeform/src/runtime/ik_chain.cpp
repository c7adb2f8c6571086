// IK chains: finding the bones from root to effector, and the helpers every solver shares (ik_chain.hpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <string>
#include <string_view>

#include "deform/runtime/error.hpp"
#include "ik_chain.hpp"
#include "finite.hpp"

namespace deform {

namespace {

using deform::finite;  // the overloads below would hide it

bool finite(const RigidTransform& t) noexcept { return finite(t.rotation) && finite(t.translation); }

// True when the spans hold every bone of the chain and its ancestors.
bool spans_fit(const IkChain& chain, std::size_t rotations, std::size_t translations) noexcept {
  const auto needed = static_cast<std::size_t>(chain.max_bone) + 1;
  return chain.max_bone >= 0 && rotations >= needed && translations >= needed;
}

// The sum of the chain's segment lengths; the spans hold every chain bone.
float segment_sum(const IkChain& chain, std::span<const glm::vec3> translations) noexcept {
  float length = 0.0f;
  for (std::size_t k = 1; k < chain.bones.size(); ++k)
    length += glm::length(translations[static_cast<std::size_t>(chain.bones[k])]);
  return length;
}

// The checks every solve shares: the chain's pose entries finite, its length (returned) finite. Spans already fit.
Status check_chain_pose(const IkChain& chain, std::span<const glm::quat> rotations,
                        std::span<const glm::vec3> translations, float& length) noexcept {
  for (const std::int32_t id : chain.bones) {
    const auto b = static_cast<std::size_t>(id);
    if (!finite(rotations[b]) || !finite(translations[b])) return Status::failure("chain pose is not finite");
  }
  length = segment_sum(chain, translations);
  if (!std::isfinite(length)) return Status::failure("chain length overflows");
  return {};
}

// `count` objects of type T at `bytes`, which then moves past them.
template <class T>
std::span<T> carve(std::byte*& bytes, std::size_t count) noexcept {
  T* first = reinterpret_cast<T*>(bytes);
  std::uninitialized_default_construct_n(first, count);
  bytes += count * sizeof(T);
  return std::span<T>(first, count);
}

}  // namespace

Status assign_chain(IkChain& chain, const Skeleton& skeleton, std::int32_t root, std::int32_t effector) {
  chain.bones.clear();
  chain.ancestors.clear();
  chain.limits.clear();
  chain.max_bone = -1;
  const auto count = static_cast<std::int32_t>(skeleton.bone_count());
  if (root < 0 || root >= count) return Status::failure("root bone out of range");
  if (effector < 0 || effector >= count) return Status::failure("effector out of range");
  if (root == effector || !skeleton.is_ancestor(root, effector))
    return Status::failure("root is not an ancestor of the effector");
  std::size_t length = 1;
  for (std::int32_t id = effector; id != root; id = skeleton.bone(id).parent)
    if (++length > max_chain_bones) return Status::failure("chain longer than 256 bones");
  chain.bones.resize(length);
  std::int32_t id = effector;
  for (std::size_t k = length; k-- > 0; id = skeleton.bone(id).parent) chain.bones[k] = id;
  std::size_t depth = 0;
  for (id = skeleton.bone(root).parent; id >= 0; id = skeleton.bone(id).parent) ++depth;
  chain.ancestors.resize(depth);
  id = skeleton.bone(root).parent;
  for (std::size_t k = depth; k-- > 0; id = skeleton.bone(id).parent) chain.ancestors[k] = id;
  chain.limits.resize(length - 1);
  for (std::size_t k = 0; k + 1 < length; ++k) chain.limits[k] = prepare_limits(skeleton.bone(chain.bones[k]).limits);
  for (const std::int32_t bone : chain.bones) chain.max_bone = std::max(chain.max_bone, bone);
  for (const std::int32_t bone : chain.ancestors) chain.max_bone = std::max(chain.max_bone, bone);
  return {};
}

IkChain make_chain(const Skeleton& skeleton, std::int32_t root, std::int32_t effector) {
  const auto count = static_cast<std::int32_t>(skeleton.bone_count());
  auto bone_name = [&](std::int32_t id) { return "bone " + std::to_string(id); };
  if (root < 0 || root >= count) throw Error::invalid_argument(bone_name(root), "root bone out of range");
  if (effector < 0 || effector >= count) throw Error::invalid_argument(bone_name(effector), "effector out of range");
  if (root == effector || !skeleton.is_ancestor(root, effector))
    throw Error::invalid_argument(
        bone_name(effector),
        "root '" + skeleton.key(root) + "' is not an ancestor of effector '" + skeleton.key(effector) + "'");
  IkChain chain;
  if (const Status status = assign_chain(chain, skeleton, root, effector); !status)
    throw Error::invalid_argument(bone_name(effector), status.reason());
  return chain;
}

float chain_length(const IkChain& chain, std::span<const glm::vec3> translations) noexcept {
  return spans_fit(chain, translations.size(), translations.size()) ? segment_sum(chain, translations) : 0.0f;
}

RigidTransform RigidTransform::from_matrix(const glm::mat4& matrix) noexcept {
  return {glm::normalize(glm::quat_cast(glm::mat3(matrix))), glm::vec3(matrix[3])};
}

glm::mat4 RigidTransform::matrix() const noexcept { return local_matrix(rotation, translation); }

Status chain_base(const IkChain& chain, std::span<const glm::quat> rotations, std::span<const glm::vec3> translations,
                  RigidTransform& base) noexcept {
  if (!spans_fit(chain, rotations.size(), translations.size()))
    return Status::failure("pose spans do not hold every chain bone");
  // The first ancestor's transform is its local one (bone 0 has no parent): the products start from it rather than
  // from the identity.
  RigidTransform frame;
  if (!chain.ancestors.empty()) {
    const auto first = static_cast<std::size_t>(chain.ancestors.front());
    frame = {rotations[first], translations[first]};
    for (std::size_t k = 1; k < chain.ancestors.size(); ++k) {
      const auto b = static_cast<std::size_t>(chain.ancestors[k]);
      frame.translation += frame.rotation * translations[b];
      frame.rotation = frame.rotation * rotations[b];
    }
  }
  base = frame;
  return {};
}

Status effector_position(const IkChain& chain, std::span<const glm::quat> rotations,
                         std::span<const glm::vec3> translations, glm::vec3& position) noexcept {
  if (chain.bones.empty()) return Status::failure("the chain has no bones");
  if (!spans_fit(chain, rotations.size(), translations.size()))
    return Status::failure("pose spans do not hold every chain bone");
  detail::Frame frame;
  for (const std::int32_t id : chain.ancestors) {
    const auto b = static_cast<std::size_t>(id);
    frame.translation += frame.rotation * translations[b];
    frame.rotation = frame.rotation * rotations[b];
  }
  for (const std::int32_t id : chain.bones) {
    const auto b = static_cast<std::size_t>(id);
    frame.translation += frame.rotation * translations[b];
    frame.rotation = frame.rotation * rotations[b];
  }
  position = frame.translation;
  return {};
}

std::size_t IkJob::scratch_size() const noexcept { return chain == nullptr ? 0 : scratch_size(chain->joint_count()); }

namespace {

// IkJob::validate, returning the chain's length as well.
Status check(const IkJob& job, float& length) noexcept {
  const IkChain* chain = job.chain;
  const IkSettings& settings = job.settings;
  if (chain == nullptr || chain->joint_count() == 0) return Status::failure("no chain");
  if (!spans_fit(*chain, job.rotations.size(), job.translations.size()))
    return Status::failure("pose spans do not hold every chain bone");
  if (settings.max_iterations < 1) return Status::failure("max_iterations below 1");
  if (!std::isfinite(settings.tolerance) || settings.tolerance < 0.0f)
    return Status::failure("tolerance not finite and >= 0");
  if (!std::isfinite(settings.max_step_degrees) || settings.max_step_degrees < 0.0f)
    return Status::failure("max_step_degrees not finite and >= 0");
  if (job.scratch.size() < job.scratch_size()) return Status::failure("scratch smaller than scratch_size()");
  if (reinterpret_cast<std::uintptr_t>(job.scratch.data()) % IkJob::scratch_alignment != 0)
    return Status::failure("scratch misaligned");
  if (!finite(job.target)) return Status::failure("target is not finite");
  if (!finite(job.base)) return Status::failure("base is not finite");
  if (job.use_pole && !finite(job.pole)) return Status::failure("pole is not finite");
  if (!chain->swing_twist.empty() && chain->swing_twist.size() != chain->joint_count())
    return Status::failure("swing_twist has neither 0 nor one entry per joint");
  if (!(job.weight >= 0.0f && job.weight <= 1.0f)) return Status::failure("weight not within [0, 1]");
  return check_chain_pose(*chain, job.rotations, job.translations, length);
}

}  // namespace

Status IkJob::validate() const noexcept {
  float length = 0.0f;
  return check(*this, length);
}

Status IkJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (begin > end || end > count()) return Status::failure("range out of bounds");
  return begin == end ? Status() : run();
}

Status IkJob::run() const noexcept {
  float length = 0.0f;
  if (const Status status = check(*this, length); !status) return status;
  const std::size_t joints = chain->joint_count(), bones = joints + 1;
  // The scratch's parts, doubles first (scratch_alignment), then floats.
  std::byte* bytes = scratch.data();
  detail::Scratch parts;
  parts.angles = carve<glm::dvec3>(bytes, joints);
  parts.frames = carve<glm::quat>(bytes, bones);
  parts.best = carve<glm::quat>(bytes, joints);
  parts.heads = carve<glm::vec3>(bytes, bones);
  parts.columns = carve<glm::vec3>(bytes, 3 * joints);
  parts.goals = carve<glm::vec3>(bytes, bones);
  parts.lengths = carve<float>(bytes, joints);
  parts.input = carve<glm::quat>(bytes, joints);
  parts.first = carve<glm::quat>(bytes, joints);
  parts.axis_dirs = carve<glm::vec4>(bytes, joints);
  const detail::PoseView pose{rotations, translations};
  if (weight == 0.0f) {  // nothing to apply: the input pose as it is, measured
    detail::chain_fk(*chain, pose, base, parts.frames, parts.heads);
    const float distance = glm::length(parts.heads[joints] - target);
    if (result != nullptr) *result = IkResult{distance <= settings.tolerance, distance, 0};
    return {};
  }
  if (weight < 1.0f) detail::save_joints(*chain, pose, parts.input);
  std::uint32_t state = random_state != nullptr ? *random_state : ik_random_seed;
  IkResult solved = method == IkMethod::fabrik
                        ? detail::solve_fabrik(*chain, pose, base, target, settings, parts, state)
                        : detail::solve_ccd(*chain, pose, base, target, settings, length, parts, state);
  if (use_pole || weight < 1.0f) {
    detail::chain_fk(*chain, pose, base, parts.frames, parts.heads);
    if (use_pole) {
      solved.distance = detail::swivel_toward_pole(*chain, pose, base, target, pole, solved.distance,
                                                   settings.tolerance, parts.frames, parts.heads);
      if (!detail::faces_pole(*chain, parts.heads, pole)) {
        // The limits kept the middle off the pole's side: seed a second solve bent toward the pole.
        detail::save_joints(*chain, pose, parts.first);
        const float first_distance = solved.distance;
        detail::swivel_toward_pole(*chain, pose, base, target, pole, first_distance, settings.tolerance, parts.frames,
                                   parts.heads, true);
        IkResult again = method == IkMethod::fabrik
                             ? detail::solve_fabrik(*chain, pose, base, target, settings, parts, state)
                             : detail::solve_ccd(*chain, pose, base, target, settings, length, parts, state);
        detail::chain_fk(*chain, pose, base, parts.frames, parts.heads);
        again.distance = detail::swivel_toward_pole(*chain, pose, base, target, pole, again.distance,
                                                    settings.tolerance, parts.frames, parts.heads);
        const float good_enough = std::max(first_distance, settings.tolerance);
        if (detail::faces_pole(*chain, parts.heads, pole) && again.distance <= good_enough) {
          again.iterations += solved.iterations;
          solved = again;
        } else {
          detail::load_joints(*chain, parts.first, pose);
          detail::chain_fk(*chain, pose, base, parts.frames, parts.heads);
          solved.distance = first_distance;
        }
      }
    }
    if (weight < 1.0f) {
      for (std::size_t k = 0; k < joints; ++k) {
        glm::quat& rotation = rotations[static_cast<std::size_t>(chain->bones[k])];
        const glm::quat from = parts.input[k];
        rotation = glm::slerp(from, glm::dot(from, rotation) < 0.0f ? -rotation : rotation, weight);
        detail::clamp_chain_joint(*chain, k, rotation);
      }
      detail::chain_fk(*chain, pose, base, parts.frames, parts.heads);
      solved.distance = glm::length(parts.heads[joints] - target);
    }
    solved.reached = solved.distance <= settings.tolerance;
  }
  if (random_state != nullptr) *random_state = state;
  if (result != nullptr) *result = solved;
  return {};
}

namespace detail {

void chain_fk(const IkChain& chain, PoseView pose, const Frame& base, std::span<glm::quat> rotations,
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

namespace {

// Whether the middle (mean of the heads after `pivot`) lies on the pole's side of the line pivot → effector, and
// the turn about that line that would put it there.
struct PoleAim {
  bool valid = false;
  double angle = 0.0;
  glm::dvec3 axis{0.0};
};

PoleAim aim_at_pole(std::size_t joints, std::span<const glm::vec3> heads, glm::vec3 pole, std::size_t pivot) noexcept {
  PoleAim a;
  const glm::dvec3 root(heads[pivot]);
  const glm::dvec3 line = glm::dvec3(heads[joints]) - root;
  const double line_length = glm::length(line);
  if (!(line_length > 1e-12)) return a;
  a.axis = line / line_length;
  glm::dvec3 middle(0.0);
  for (std::size_t k = pivot + 1; k < joints; ++k) middle += glm::dvec3(heads[k]) - root;
  middle /= static_cast<double>(joints - 1 - pivot);
  // The parts of the middle and of the pole across the line: the swivel turns the one onto the other.
  const glm::dvec3 from = middle - glm::dot(middle, a.axis) * a.axis;
  const glm::dvec3 to = (glm::dvec3(pole) - root) - glm::dot(glm::dvec3(pole) - root, a.axis) * a.axis;
  const double scale = line_length * line_length;
  if (glm::dot(from, from) < 1e-12 * scale || glm::dot(to, to) < 1e-12 * scale) return a;
  a.valid = true;
  a.angle = std::atan2(glm::dot(a.axis, glm::cross(from, to)), glm::dot(from, to));
  return a;
}

}  // namespace

bool faces_pole(const IkChain& chain, std::span<const glm::vec3> heads, glm::vec3 pole) noexcept {
  if (chain.joint_count() < 2) return true;
  const PoleAim a = aim_at_pole(chain.joint_count(), heads, pole, 0);
  return !a.valid || std::abs(a.angle) < 0.5 * std::numbers::pi;
}

float swivel_toward_pole(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target, glm::vec3 pole,
                         float distance, float tolerance, std::span<glm::quat> frames, std::span<glm::vec3> heads,
                         bool whole) noexcept {
  const std::size_t joints = chain.joint_count();
  if (joints < 2) return distance;
  // Acceptable: reached stays reached; otherwise no farther than the solve (float rounding of the turn allowed).
  const float allowed = distance <= tolerance ? tolerance : distance + 1e-6f * glm::length(heads[joints] - heads[0]);
  // The root turns first; when its limits keep the middle off the pole's side (a clavicle turns little), the next
  // joint turns the rest of the chain about its own line to the effector, and so on down to the last joint with a
  // middle after it.
  for (std::size_t pivot = 0; pivot + 1 < joints; ++pivot) {
    const PoleAim a = aim_at_pole(joints, heads, pole, pivot);
    if (!a.valid) continue;
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain.bones[pivot])];
    const glm::quat solved = local;
    const glm::quat parent = pivot == 0 ? base.rotation : frames[pivot - 1];
    bool turned = false;
    for (double fraction = 1.0; fraction >= 0.125; fraction *= 0.5) {
      const glm::quat turn(glm::angleAxis(static_cast<float>(a.angle * fraction), glm::vec3(a.axis)));
      local = glm::normalize(glm::conjugate(parent) * turn * parent * solved);
      clamp_chain_joint(chain, pivot, local);
      chain_fk(chain, pose, base, frames, heads);
      const float swivelled = glm::length(heads[joints] - target);
      if (whole || swivelled <= allowed) {
        distance = swivelled;
        turned = true;
        break;
      }
    }
    if (!turned) {
      local = solved;
      chain_fk(chain, pose, base, frames, heads);
    }
    if (faces_pole(chain, heads, pole)) break;
  }
  return distance;
}

StepCap cap_for(float max_radians) noexcept {
  if (!(max_radians > 0.0f) || max_radians >= std::numbers::pi_v<float>) return {};
  return {std::cos(max_radians), glm::vec2(std::cos(0.5f * max_radians), std::sin(0.5f * max_radians))};
}

void point_segments_at(const IkChain& chain, PoseView pose, glm::quat base, std::span<glm::quat> frames,
                       std::span<glm::vec3> heads, glm::vec3 target) noexcept {
  for (std::size_t k = 0; k < chain.joint_count(); ++k) {
    const glm::quat parent = k == 0 ? base : frames[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    const glm::vec3 offset = pose.translations[static_cast<std::size_t>(chain.bones[k + 1])];
    const glm::vec3 wanted = glm::conjugate(parent) * (target - heads[k]);
    local = rotation_between(local * offset, wanted) * local;
    clamp_chain_joint(chain, k, local, true, offset, wanted);
    frames[k] = parent * local;
    heads[k + 1] = heads[k] + frames[k] * offset;
  }
  frames[chain.joint_count()] =
      frames[chain.joint_count() - 1] * pose.rotations[static_cast<std::size_t>(chain.bones.back())];
}

namespace {

constexpr double at_limit = 1e-6;  // radians

}  // namespace

void damped_least_squares_step(const IkChain& chain, std::span<const EulerLimits> limits, PoseView pose, glm::quat base,
                               std::span<const glm::quat> frames, std::span<const glm::vec3> heads, glm::vec3 target,
                               float lambda, bool angles_current, std::span<glm::dvec3> angles,
                               std::span<glm::vec4> axis_dirs, std::span<glm::vec3> columns) noexcept {
  const std::size_t joints = chain.joint_count();
  const glm::vec3 effector = heads[joints];
  glm::dmat3 jjt(lambda * lambda);
  for (std::size_t k = 0; k < joints; ++k) {
    // (The previous step left the angles and their directions, which quat_at evaluated for them.)
    if (!angles_current) {
      EulerAngles euler;
      limit_euler(limits[k], pose.rotations[static_cast<std::size_t>(chain.bones[k])], euler);
      angles[k] = euler.angle;
      axis_dirs[k] = glm::vec4(glm::vec2(euler.dir[0]), glm::vec2(euler.dir[1]));
    }
    // Euler axis k turns about its world direction: the parent's frame times the rotations of the axes before it.
    const glm::mat3 parent = glm::mat3_cast(k == 0 ? base : frames[k - 1]);
    const glm::vec2 x(axis_dirs[k].x, axis_dirs[k].y), y(axis_dirs[k].z, axis_dirs[k].w);
    const glm::vec3 axes[3] = {parent[0], x.x * parent[1] + x.y * parent[2],
                               y.y * parent[0] + y.x * (x.x * parent[2] - x.y * parent[1])};
    for (int axis = 0; axis < 3; ++axis) {
      // Column of Euler axis `axis`: its world direction × (effector − head). Axes locked, or at a limit (to the
      // float rounding of a clamped rotation, 1e-6 rad) with the error pulling outward, take no part (an active set).
      glm::vec3 column = glm::cross(axes[axis], effector - heads[k]);
      const float pull = glm::dot(column, target - effector);
      const double min = limits[k].min[axis], max = limits[k].max[axis], angle = angles[k][axis];
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
      // A free axis wraps into [-π, π]; one already there is what remainder() returns for it (n = 0), without the
      // libm call that most steps' free axes would otherwise pay.
      if (max - min < 2.0 * std::numbers::pi) angle = std::clamp(angle, min, max);
      else if (std::abs(angle) > std::numbers::pi) angle = std::remainder(angle, 2.0 * std::numbers::pi);
    }
    glm::quat& rotation = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    rotation = quat_at(angles[k], axis_dirs[k]);
    // A swing-twist joint (free Euler entry) is projected; its angles follow the projected rotation.
    if (const SwingTwistLimits* cone = swing_twist_of(chain, k);
        cone != nullptr && clamp_swing_twist(*cone, rotation)) {
      EulerAngles euler;
      limit_euler(limit, rotation, euler);
      angles[k] = euler.angle;
      static_cast<void>(quat_at(angles[k], axis_dirs[k]));  // (the directions)
    }
  }
}

void save_joints(const IkChain& chain, PoseView pose, std::span<glm::quat> saved) noexcept {
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k)
    saved[k] = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
}

void load_joints(const IkChain& chain, std::span<const glm::quat> saved, PoseView pose) noexcept {
  for (std::size_t k = 0; k + 1 < chain.bones.size(); ++k)
    pose.rotations[static_cast<std::size_t>(chain.bones[k])] = saved[k];
}

void perturb_joints(const IkChain& chain, PoseView pose, std::uint32_t& state, float degrees) noexcept {
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
    clamp_chain_joint(chain, k, rotation);
  }
}

}  // namespace detail
}  // namespace deform
