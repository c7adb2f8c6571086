// Cyclic coordinate descent with quaternions and Euler DOF limits (thesis §7.4.3–7.4.4), with a stall escape.
#include <algorithm>

#include "ik_chain.hpp"

namespace deform::detail {
namespace {

// One CCD sweep, effector side first. Joints nearer the root keep their frames while the ones below them turn, so
// only the effector position needs updating between joints; the caller ends the sweep with a full chain FK.
void sweep(const IkChain& chain, PoseView pose, const Scratch& scratch, glm::vec3 target, glm::quat base,
           float max_step_radians, bool reaim) {
  const StepCap cap = cap_for(max_step_radians);
  glm::vec3 effector = scratch.heads.back();
  for (std::size_t k = chain.joint_count(); k-- > 0;) {
    const glm::vec3 head = scratch.heads[k];
    const glm::quat parent = k == 0 ? base : scratch.frames[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    // Relative to the joint's head: effector and target in the parent's frame, the effector in the joint's own
    // frame (which the joint's rotation does not change).
    const glm::vec3 reach = glm::conjugate(parent) * (effector - head);
    const glm::vec3 wanted = glm::conjugate(parent) * (target - head);
    const glm::vec3 carried = glm::conjugate(local) * reach;
    local = rotation_between(reach, wanted, cap) * local;
    clamp_chain_joint(chain, k, local, reaim, carried, wanted);
    scratch.frames[k] = parent * local;
    effector = head + scratch.frames[k] * carried;
  }
}

}  // namespace

IkResult solve_ccd(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target, const IkSettings& settings,
                   float length, const Scratch& scratch, std::uint32_t& random_state) noexcept {
  const std::size_t joints = chain.joint_count();
  const std::span<const EulerLimits> limits = chain.limits;
  const std::span<glm::quat> frames = scratch.frames;
  const std::span<glm::vec3> heads = scratch.heads;
  for (std::size_t k = 0; k < joints; ++k)
    clamp_chain_joint(chain, k, pose.rotations[static_cast<std::size_t>(chain.bones[k])]);
  const float max_step = glm::radians(settings.max_step_degrees);

  chain_fk(chain, pose, base, frames, heads);
  float distance = glm::length(heads.back() - target);
  // No pose gets nearer than this; progress is measured on the distance above it.
  const float floor = std::max(0.0f, glm::length(target - heads[0]) - length);
  float best_distance = distance;
  save_joints(chain, pose, scratch.best);
  int iterations = 0;
  // The stall escape's stages: 0 CCD sweeps while each gains enough; then 1 one straightening pass
  // (out-of-reach targets only), 2 damped least-squares steps while they gain; on their stall, a random kick and
  // back to 0.
  int stage = 0;
  float handover = ccd_handover_gain;  // after a kick, ccd_kicked_handover_gain
  bool angles_current = false;  // scratch.angles hold the joints' Euler angles: the last step was a least-squares step
  // Within tolerance of the floor nothing better exists: an out-of-reach target stops there too.
  while (distance > floor + settings.tolerance && iterations < settings.max_iterations) {
    ++iterations;
    if (stage == 1) {
      point_segments_at(chain, pose, base.rotation, frames, heads, target);
    } else if (stage == 2) {
      damped_least_squares_step(chain, limits, pose, base.rotation, frames, heads, target, damping_fraction * length,
                                angles_current, scratch.angles, scratch.axis_dirs, scratch.columns);
    } else {
      sweep(chain, pose, scratch, target, base.rotation, max_step, settings.escape_stalls);
    }
    angles_current = stage == 2;
    chain_fk(chain, pose, base, frames, heads);
    const float previous = distance;
    distance = glm::length(heads.back() - target);
    if (distance < best_distance) {
      best_distance = distance;
      save_joints(chain, pose, scratch.best);
    }
    const float gain = previous - distance;
    if (!settings.escape_stalls || distance <= settings.tolerance) continue;
    // Clamped CCD crawls near the target (each joint moves the effector only across its own lever arm), creeps
    // toward the straight chain for a target out of reach, or sits in a local minimum with joints pinned at their
    // limits. Straightening, then least-squares steps that move all joints together, then a kick into another basin.
    if (stage == 0 && gain < handover * (previous - floor)) {
      stage = floor > 0.0f ? 1 : 2;
    } else if (stage == 1) {
      stage = 2;
    } else if (stage == 2 && gain < stall_gain * (previous - floor)) {
      load_joints(chain, scratch.best, pose);
      perturb_joints(chain, pose, random_state, escape_degrees);
      chain_fk(chain, pose, base, frames, heads);
      distance = glm::length(heads.back() - target);
      stage = 0;
      handover = ccd_kicked_handover_gain;
      angles_current = false;
    }
  }
  if (best_distance < distance) {
    load_joints(chain, scratch.best, pose);
    distance = best_distance;
  }
  return IkResult{distance <= settings.tolerance, distance, iterations};
}

}  // namespace deform::detail
