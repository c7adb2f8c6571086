// with_driven_weights: a clip's pose-driven morph weights as keyed tracks (deform/character/character.hpp).
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/character/character.hpp"

namespace deform {

Animation with_driven_weights(const Character& character, const Animation& clip, float frames_per_second) {
  if (!std::isfinite(frames_per_second) || !(frames_per_second > 0.0f) || frames_per_second > 1000.0f)
    throw Error::invalid_argument("frames_per_second", "must be finite, > 0 and at most 1000");
  clip.require_valid(character.skeleton().bone_count(), "clip '" + clip.name + "'");
  Animation baked = clip;
  if (character.pose_driver_count() == 0) return baked;
  // Key times: k / rate while before the duration, then the duration itself (a zero-length clip: one key at 0).
  std::vector<float> times;
  for (std::size_t k = 0;; ++k) {
    const float t = static_cast<float>(static_cast<double>(k) / frames_per_second);
    if (!(t < clip.duration)) break;
    times.push_back(t);
  }
  times.push_back(clip.duration);
  // The weights update() sets, from a character of its own that only poses (no deformation is needed for them).
  Character posed = character.instance();
  posed.settings.deform_on_cpu = false;
  Pose pose = character.skeleton().bind_pose();
  std::vector<std::vector<float>> weights(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    pose = character.skeleton().bind_pose();
    // Sample the clip's own time, not a wrapped one: a looping clip's key at its duration is its last pose.
    for (const Channel& channel : clip.channels) {
      const auto b = static_cast<std::size_t>(channel.bone);
      pose.rotations[b] = sample_track(channel.rotation, times[k], pose.rotations[b]);
      pose.translations[b] = sample_track(channel.translation, times[k], pose.translations[b]);
    }
    if (const Status set = posed.set_pose(pose); !set)
      throw Error::invalid_argument("clip '" + clip.name + "'",
                                    "at " + std::to_string(times[k]) + " s: " + set.reason());
    if (const Status updated = posed.update(0.0f); !updated)
      throw Error::invalid_argument("clip '" + clip.name + "'",
                                    "at " + std::to_string(times[k]) + " s: " + updated.reason());
    weights[k].assign(posed.morph_weights().begin(), posed.morph_weights().end());
  }
  for (std::size_t d = 0; d < character.pose_driver_count(); ++d) {
    for (const std::uint32_t target : character.pose_driver_targets(d)) {
      std::erase_if(baked.morph_channels, [&](const MorphChannel& c) { return c.target == std::int32_t(target); });
      MorphChannel channel;
      channel.target = static_cast<std::int32_t>(target);
      channel.weight.interpolation = Interpolation::linear;
      channel.weight.times = times;
      for (std::size_t k = 0; k < times.size(); ++k) channel.weight.values.push_back(weights[k][target]);
      baked.morph_channels.push_back(std::move(channel));
    }
  }
  return baked;
}

}  // namespace deform
