// The built-in character's walk: a looping clip made by code (see builtin.hpp).
#include <cmath>
#include <string>

#include "deform/extras/builtin.hpp"

namespace deform {

Animation builtin_walk(const Model& model) {
  const Skeleton& skeleton = model.skeleton;
  constexpr int keys = 17;  // one every 1/16 s, the last equal to the first
  constexpr float duration = 1.0f;
  constexpr float pi = 3.14159265358979f;
  Animation clip;
  clip.name = "walk";
  clip.duration = duration;
  clip.loop = true;
  // Euler angles (degrees, X·Y·Z, absolute as Bone::bind_rotation) of a bone at phase φ ∈ [0, 2π): the bind angles
  // plus a swing; within the bones' limits, so set_pose's clamp leaves them.
  struct Swing {
    const char* bone;
    glm::vec3 offset;     // added to the bind angles
    glm::vec3 amplitude;  // times sin(φ + phase)
    float phase;
  };
  const Swing swings[] = {
      {"spine", {0.0f, 0.0f, 0.0f}, {2.0f, 8.0f, 0.0f}, 0.0f},
      {"neck", {0.0f, 0.0f, 0.0f}, {0.0f, -6.0f, 0.0f}, 0.0f},
      {"upperarm_l", {0.0f, 0.0f, -65.0f}, {30.0f, 0.0f, 5.0f}, pi},
      {"upperarm_r", {0.0f, 0.0f, 65.0f}, {30.0f, 0.0f, -5.0f}, 0.0f},
      {"forearm_l", {30.0f, 0.0f, 0.0f}, {15.0f, 0.0f, 0.0f}, pi},
      {"forearm_r", {30.0f, 0.0f, 0.0f}, {15.0f, 0.0f, 0.0f}, 0.0f},
      {"thigh_l", {-5.0f, 0.0f, 0.0f}, {-25.0f, 0.0f, 0.0f}, 0.0f},
      {"thigh_r", {-5.0f, 0.0f, 0.0f}, {-25.0f, 0.0f, 0.0f}, pi},
      {"shin_l", {25.0f, 0.0f, 0.0f}, {20.0f, 0.0f, 0.0f}, 0.5f * pi},
      {"shin_r", {25.0f, 0.0f, 0.0f}, {20.0f, 0.0f, 0.0f}, 1.5f * pi},
  };
  // Cubic-spline keys with the swing's own derivative as tangents, so the motion is smooth (C¹) through the keys:
  // secondary motion feels a walk's accelerations, and linear keys would make them kicks every 1/16 s.
  Pose pose = skeleton.bind_pose();
  const float key_rate = 2.0f * pi / duration;  // dφ/dt
  for (const Swing& swing : swings) {
    const std::int32_t bone = skeleton.find(swing.bone);
    if (bone < 0) throw Error::in_file(model.name, "walk", std::string("no bone '") + swing.bone + "'");
    Channel channel;
    channel.bone = bone;
    channel.rotation.interpolation = Interpolation::cubic_spline;
    const auto rotation_at = [&](float phase) {
      skeleton.set_euler(pose, bone,
                         skeleton.bone(bone).bind_rotation + swing.offset + swing.amplitude * std::sin(phase + swing.phase));
      return pose.rotations[std::size_t(bone)];
    };
    for (int k = 0; k < keys; ++k) {
      const float phase = 2.0f * pi * float(k % (keys - 1)) / float(keys - 1);
      const glm::quat q = rotation_at(phase);
      // dq/dt by a central difference (both sides on q's hemisphere), per second as the tangents are.
      constexpr float step = 1e-3f;
      glm::quat ahead = rotation_at(phase + step), behind = rotation_at(phase - step);
      if (glm::dot(ahead, q) < 0.0f) ahead = -ahead;
      if (glm::dot(behind, q) < 0.0f) behind = -behind;
      const glm::quat tangent = (ahead - behind) * (key_rate / (2.0f * step));
      channel.rotation.times.push_back(duration * float(k) / float(keys - 1));
      channel.rotation.values.push_back(q);
      channel.rotation.in_tangents.push_back(tangent);
      channel.rotation.out_tangents.push_back(tangent);
    }
    clip.channels.push_back(std::move(channel));
  }
  // The hips bob twice per cycle.
  Channel hips;
  hips.bone = 0;
  hips.translation.interpolation = Interpolation::cubic_spline;
  for (int k = 0; k < keys; ++k) {
    const float phase = 2.0f * pi * float(k % (keys - 1)) / float(keys - 1);
    hips.translation.times.push_back(duration * float(k) / float(keys - 1));
    hips.translation.values.push_back(skeleton.bone(0).bind_translation +
                                      glm::vec3(0.0f, 0.02f * std::cos(2.0f * phase), 0.0f));
    const glm::vec3 tangent(0.0f, -0.04f * std::sin(2.0f * phase) * key_rate, 0.0f);
    hips.translation.in_tangents.push_back(tangent);
    hips.translation.out_tangents.push_back(tangent);
  }
  clip.channels.push_back(std::move(hips));
  clip.validate(skeleton.bone_count(), model.name);
  return clip;
}

}  // namespace deform
