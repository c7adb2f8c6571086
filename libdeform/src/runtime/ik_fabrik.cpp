// FABRIK (Aristidou & Lasenby 2011) on joint positions, turned back into clamped local rotations after every pass.
#include <algorithm>

#include "ik_chain.hpp"

namespace deform::detail {
namespace {

// `to - from` scaled to `length`; when the two points coincide, `fallback` (a direction) scaled instead.
glm::vec3 reach(glm::vec3 from, glm::vec3 to, float length, glm::vec3 fallback) {
  const glm::vec3 v = to - from;
  const float d = glm::length(v);
  if (d > 1e-12f) return from + v * (length / d);
  const float f = glm::length(fallback);
  return f > 1e-12f ? from + fallback * (length / f) : from;
}

// One FABRIK pass and its conversion back to clamped rotations; leaves scratch.frames and scratch.heads as the new
// pose's FK.
void pass(const IkChain& chain, PoseView pose, const Scratch& scratch, glm::vec3 target, glm::quat base,
          float reach_length, bool reaim) {
  const std::size_t joints = chain.joint_count();
  const std::span<glm::vec3> goals = scratch.goals, heads = scratch.heads;
  const std::span<const float> lengths = scratch.lengths;
  // The positions pass: backward from the target, forward from the fixed root; out of reach, the straight line.
  for (std::size_t k = 0; k <= joints; ++k) goals[k] = heads[k];
  if (glm::length(target - heads[0]) >= reach_length) {
    for (std::size_t k = 0; k < joints; ++k)
      goals[k + 1] = reach(goals[k], target, lengths[k], heads[k + 1] - heads[k]);
  } else {
    goals[joints] = target;
    for (std::size_t k = joints; k-- > 0;)
      goals[k] = reach(goals[k + 1], goals[k], lengths[k], heads[k] - heads[k + 1]);
    goals[0] = heads[0];
    for (std::size_t k = 0; k < joints; ++k)
      goals[k + 1] = reach(goals[k], goals[k + 1], lengths[k], heads[k + 1] - heads[k]);
  }
  // Back to rotations from the root down: each joint turns its segment onto its goal from where its head really
  // is (clamps above it may have moved it), then is clamped; FK follows joint by joint.
  for (std::size_t k = 0; k < joints; ++k) {
    const glm::quat parent = k == 0 ? base : scratch.frames[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
    const glm::vec3 offset = pose.translations[static_cast<std::size_t>(chain.bones[k + 1])];
    const glm::vec3 wanted = glm::conjugate(parent) * (goals[k + 1] - heads[k]);
    local = rotation_between(local * offset, wanted) * local;
    clamp_chain_joint(chain, k, local, reaim, offset, wanted);
    scratch.frames[k] = parent * local;
    heads[k + 1] = heads[k] + scratch.frames[k] * offset;
  }
}

}  // namespace

IkResult solve_fabrik(const IkChain& chain, PoseView pose, const Frame& base, glm::vec3 target,
                      const IkSettings& settings, const Scratch& scratch, std::uint32_t& random_state) noexcept {
  const std::size_t joints = chain.joint_count();
  const std::span<const EulerLimits> limits = chain.limits;
  const std::span<glm::quat> frames = scratch.frames;
  const std::span<glm::vec3> heads = scratch.heads;
  for (std::size_t k = 0; k < joints; ++k)
    clamp_chain_joint(chain, k, pose.rotations[static_cast<std::size_t>(chain.bones[k])]);

  chain_fk(chain, pose, base, frames, heads);
  float reach_length = 0.0f;
  for (std::size_t k = 0; k < joints; ++k) {
    scratch.lengths[k] = glm::length(heads[k + 1] - heads[k]);
    reach_length += scratch.lengths[k];
  }
  float distance = glm::length(heads.back() - target);
  const float floor = std::max(0.0f, glm::length(target - heads[0]) - reach_length);
  float best_distance = distance;
  save_joints(chain, pose, scratch.best);
  int iterations = 0;
  bool polishing = false;       // the stall escape's damped least-squares steps are running
  bool angles_current = false;  // scratch.angles hold the joints' Euler angles: the last step was a least-squares step
  // Within tolerance of the floor nothing better exists: an out-of-reach target stops there too.
  while (distance > floor + settings.tolerance && iterations < settings.max_iterations) {
    ++iterations;
    if (polishing) {
      damped_least_squares_step(chain, limits, pose, base.rotation, frames, heads, target,
                                damping_fraction * reach_length, angles_current, scratch.angles, scratch.axis_dirs,
                                scratch.columns);
      chain_fk(chain, pose, base, frames, heads);
    } else {
      pass(chain, pose, scratch, target, base.rotation, reach_length, settings.escape_stalls);
    }
    angles_current = polishing;
    const float previous = distance;
    distance = glm::length(heads.back() - target);
    if (distance < best_distance) {
      best_distance = distance;
      save_joints(chain, pose, scratch.best);
    }
    if (settings.escape_stalls && distance > settings.tolerance &&
        previous - distance < (polishing ? stall_gain : fabrik_handover_gain) * (previous - floor)) {
      // As in solve_ccd: damped least-squares steps, then a random kick from the best pose.
      if (polishing) {
        load_joints(chain, scratch.best, pose);
        perturb_joints(chain, pose, random_state, escape_degrees);
        chain_fk(chain, pose, base, frames, heads);
        distance = glm::length(heads.back() - target);
        angles_current = false;
      }
      polishing = !polishing;
    }
  }
  if (best_distance < distance) {
    load_joints(chain, scratch.best, pose);
    distance = best_distance;
  }
  return IkResult{distance <= settings.tolerance, distance, iterations};
}

}  // namespace deform::detail
