// Cyclic coordinate descent with quaternions and Euler DOF limits (thesis §7.4.3–7.4.4), with a stall escape.
#include <algorithm>

#include "ik_chain.hpp"

namespace deform {

CcdSolver::CcdSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector)
    : skeleton_(&skeleton), chain_(make_chain(skeleton, root, effector)),
      limits_(detail::prepare_chain_limits(skeleton, chain_)) {
  frames_.resize(chain_.bones.size());
  heads_.resize(chain_.bones.size());
  best_.resize(chain_.joint_count());
  angles_.resize(chain_.joint_count());
  columns_.resize(3 * chain_.joint_count());
}

void CcdSolver::sweep(Pose& pose, glm::vec3 target, glm::quat base, float max_step_radians, bool reaim) {
  // Effector side first. Joints nearer the root keep their frames while the ones below them turn, so only the
  // effector position needs updating between joints; the caller ends the sweep with a full chain FK.
  const detail::StepCap cap = detail::cap_for(max_step_radians);
  glm::vec3 effector = heads_.back();
  for (std::size_t k = chain_.joint_count(); k-- > 0;) {
    const glm::vec3 head = heads_[k];
    const glm::quat parent = k == 0 ? base : frames_[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain_.bones[k])];
    // Relative to the joint's head: effector and target in the parent's frame, the effector in the joint's own
    // frame (which the joint's rotation does not change).
    const glm::vec3 reach = glm::conjugate(parent) * (effector - head);
    const glm::vec3 wanted = glm::conjugate(parent) * (target - head);
    const glm::vec3 carried = glm::conjugate(local) * reach;
    local = detail::rotation_between(reach, wanted, cap) * local;
    detail::clamp_joint(limits_[k], local, reaim, carried, wanted);
    frames_[k] = parent * local;
    effector = head + frames_[k] * carried;
  }
}

bool CcdSolver::solve(Pose& pose, glm::vec3 target, const IkSettings& settings, IkResult& result) {
  if (!detail::pose_fits(*skeleton_, pose) || !detail::settings_valid(target, settings)) return false;
  const std::size_t joints = chain_.joint_count();
  for (std::size_t k = 0; k < joints; ++k)
    clamp_rotation(limits_[k], pose.rotations[static_cast<std::size_t>(chain_.bones[k])]);
  const detail::Frame base = detail::base_frame(chain_, pose);
  const float max_step = glm::radians(settings.max_step_degrees);

  const float length = chain_length(chain_, pose);
  detail::chain_fk(chain_, pose, base, frames_, heads_);
  float distance = glm::length(heads_.back() - target);
  // No pose gets nearer than this; progress is measured on the distance above it.
  const float floor = std::max(0.0f, glm::length(target - heads_[0]) - length);
  float best_distance = distance;
  detail::save_joints(chain_, pose, best_);
  int iterations = 0;
  // The stall escape's stages: 0 CCD sweeps while each gains enough; then 1 one straightening pass
  // (out-of-reach targets only), 2 damped least-squares steps while they gain; on their stall, a random kick and
  // back to 0.
  int stage = 0;
  bool angles_current = false;  // angles_ hold the joints' Euler angles: the last step was a least-squares step
  // Within tolerance of the floor nothing better exists: an out-of-reach target stops there too.
  while (distance > floor + settings.tolerance && iterations < settings.max_iterations) {
    ++iterations;
    if (stage == 1) {
      detail::point_segments_at(chain_, limits_, pose, base.rotation, frames_, heads_, target);
    } else if (stage == 2) {
      detail::damped_least_squares_step(chain_, limits_, pose, base.rotation, frames_, heads_, target,
                                        detail::damping_fraction * length, angles_current, angles_, columns_);
    } else {
      sweep(pose, target, base.rotation, max_step, settings.escape_stalls);
    }
    angles_current = stage == 2;
    detail::chain_fk(chain_, pose, base, frames_, heads_);
    const float previous = distance;
    distance = glm::length(heads_.back() - target);
    if (distance < best_distance) {
      best_distance = distance;
      detail::save_joints(chain_, pose, best_);
    }
    const float gain = previous - distance;
    if (!settings.escape_stalls || distance <= settings.tolerance) continue;
    // Clamped CCD crawls near the target (each joint moves the effector only across its own lever arm), creeps
    // toward the straight chain for a target out of reach, or sits in a local minimum with joints pinned at their
    // limits. Straightening, then least-squares steps that move all joints together, then a kick into another basin.
    if (stage == 0 && gain < detail::handover_gain * (previous - floor)) {
      stage = floor > 0.0f ? 1 : 2;
    } else if (stage == 1) {
      stage = 2;
    } else if (stage == 2 && gain < detail::stall_gain * (previous - floor)) {
      detail::load_joints(chain_, best_, pose);
      detail::perturb_joints(chain_, limits_, pose, random_state_, detail::escape_degrees);
      detail::chain_fk(chain_, pose, base, frames_, heads_);
      distance = glm::length(heads_.back() - target);
      stage = 0;
      angles_current = false;
    }
  }
  if (best_distance < distance) {
    detail::load_joints(chain_, best_, pose);
    distance = best_distance;
  }
  result = IkResult{distance <= settings.tolerance, distance, iterations};
  return true;
}

}  // namespace deform
