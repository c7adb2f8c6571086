// FABRIK (Aristidou & Lasenby 2011) on joint positions, turned back into clamped local rotations after every pass.
#include <algorithm>

#include "ik_chain.hpp"

namespace deform {
namespace {

// `to - from` scaled to `length`; when the two points coincide, `fallback` (a direction) scaled instead.
glm::vec3 reach(glm::vec3 from, glm::vec3 to, float length, glm::vec3 fallback) {
  const glm::vec3 v = to - from;
  const float d = glm::length(v);
  if (d > 1e-12f) return from + v * (length / d);
  const float f = glm::length(fallback);
  return f > 1e-12f ? from + fallback * (length / f) : from;
}

}  // namespace

FabrikSolver::FabrikSolver(const Skeleton& skeleton, std::int32_t root, std::int32_t effector)
    : skeleton_(&skeleton), chain_(make_chain(skeleton, root, effector)),
      limits_(detail::prepare_chain_limits(skeleton, chain_)) {
  frames_.resize(chain_.bones.size());
  heads_.resize(chain_.bones.size());
  goals_.resize(chain_.bones.size());
  lengths_.resize(chain_.joint_count());
  best_.resize(chain_.joint_count());
  angles_.resize(chain_.joint_count());
  columns_.resize(3 * chain_.joint_count());
}

bool FabrikSolver::solve(Pose& pose, glm::vec3 target, const IkSettings& settings, IkResult& result) {
  if (!detail::pose_fits(*skeleton_, pose) || !detail::settings_valid(target, settings)) return false;
  const std::size_t joints = chain_.joint_count();
  for (std::size_t k = 0; k < joints; ++k)
    clamp_rotation(limits_[k], pose.rotations[static_cast<std::size_t>(chain_.bones[k])]);
  const detail::Frame base = detail::base_frame(chain_, pose);

  detail::chain_fk(chain_, pose, base, frames_, heads_);
  float reach_length = 0.0f;
  for (std::size_t k = 0; k < joints; ++k) {
    lengths_[k] = glm::length(heads_[k + 1] - heads_[k]);
    reach_length += lengths_[k];
  }
  float distance = glm::length(heads_.back() - target);
  const float floor = std::max(0.0f, glm::length(target - heads_[0]) - reach_length);
  float best_distance = distance;
  detail::save_joints(chain_, pose, best_);
  int iterations = 0;
  bool polishing = false;       // the stall escape's damped least-squares steps are running
  bool angles_current = false;  // angles_ hold the joints' Euler angles: the last step was a least-squares step
  // Within tolerance of the floor nothing better exists: an out-of-reach target stops there too.
  while (distance > floor + settings.tolerance && iterations < settings.max_iterations) {
    ++iterations;
    if (polishing) {
      detail::damped_least_squares_step(chain_, limits_, pose, base.rotation, frames_, heads_, target,
                                        detail::damping_fraction * reach_length, angles_current, angles_, columns_);
      detail::chain_fk(chain_, pose, base, frames_, heads_);
    } else {
      pass(pose, target, base.rotation, reach_length, settings.escape_stalls);
    }
    angles_current = polishing;
    const float previous = distance;
    distance = glm::length(heads_.back() - target);
    if (distance < best_distance) {
      best_distance = distance;
      detail::save_joints(chain_, pose, best_);
    }
    if (settings.escape_stalls && distance > settings.tolerance &&
        previous - distance < (polishing ? detail::stall_gain : detail::handover_gain) * (previous - floor)) {
      // As in CcdSolver::solve: damped least-squares steps, then a random kick from the best pose.
      if (polishing) {
        detail::load_joints(chain_, best_, pose);
        detail::perturb_joints(chain_, limits_, pose, random_state_, detail::escape_degrees);
        detail::chain_fk(chain_, pose, base, frames_, heads_);
        distance = glm::length(heads_.back() - target);
        angles_current = false;
      }
      polishing = !polishing;
    }
  }
  if (best_distance < distance) {
    detail::load_joints(chain_, best_, pose);
    distance = best_distance;
  }
  result = IkResult{distance <= settings.tolerance, distance, iterations};
  return true;
}

void FabrikSolver::pass(Pose& pose, glm::vec3 target, glm::quat base, float reach_length, bool reaim) {
  const std::size_t joints = chain_.joint_count();
  // The positions pass: backward from the target, forward from the fixed root; out of reach, the straight line.
  for (std::size_t k = 0; k <= joints; ++k) goals_[k] = heads_[k];
  if (glm::length(target - heads_[0]) >= reach_length) {
    for (std::size_t k = 0; k < joints; ++k)
      goals_[k + 1] = reach(goals_[k], target, lengths_[k], heads_[k + 1] - heads_[k]);
  } else {
    goals_[joints] = target;
    for (std::size_t k = joints; k-- > 0;)
      goals_[k] = reach(goals_[k + 1], goals_[k], lengths_[k], heads_[k] - heads_[k + 1]);
    goals_[0] = heads_[0];
    for (std::size_t k = 0; k < joints; ++k)
      goals_[k + 1] = reach(goals_[k], goals_[k + 1], lengths_[k], heads_[k + 1] - heads_[k]);
  }
  // Back to rotations from the root down: each joint turns its segment onto its goal from where its head really
  // is (clamps above it may have moved it), then is clamped; FK follows joint by joint.
  for (std::size_t k = 0; k < joints; ++k) {
    const glm::quat parent = k == 0 ? base : frames_[k - 1];
    glm::quat& local = pose.rotations[static_cast<std::size_t>(chain_.bones[k])];
    const glm::vec3 offset = pose.translations[static_cast<std::size_t>(chain_.bones[k + 1])];
    const glm::vec3 wanted = glm::conjugate(parent) * (goals_[k + 1] - heads_[k]);
    local = detail::rotation_between(local * offset, wanted) * local;
    detail::clamp_joint(limits_[k], local, reaim, offset, wanted);
    frames_[k] = parent * local;
    heads_[k + 1] = heads_[k] + frames_[k] * offset;
  }
}

}  // namespace deform
