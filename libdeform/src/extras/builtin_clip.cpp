// The built-in character's clips: looping clips made by code (see builtin.hpp).
#include <cmath>
#include <span>
#include <string>

#include "deform/extras/builtin.hpp"

namespace deform {
namespace {

constexpr float pi = 3.14159265358979f;

// Euler angles (degrees, X·Y·Z, absolute as Bone::bind_rotation) of a bone at phase φ ∈ [0, 2π) of the cycle: the
// bind angles plus offset plus amplitude · sin(harmonic · φ + phase); within the bones' limits, so set_pose's clamp
// leaves them (builtin_test checks every clip with a margin).
struct Swing {
  const char* bone;
  glm::vec3 offset;     // added to the bind angles
  glm::vec3 amplitude;  // times sin(harmonic · φ + phase)
  float phase;
  float harmonic = 1.0f;  // swings per cycle
};

// A looping clip: every swing a rotation channel, and the hips' translation the bind one plus
// bob · cos(bob_harmonic · φ) (no channel when bob is zero). `intervals` keys per cycle (plus the last, equal to the
// first).
struct Cycle {
  const char* name;
  float duration;
  int intervals;
  std::span<const Swing> swings;
  glm::vec3 bob;
  float bob_harmonic;
};

Animation make_cycle(const Model& model, const Cycle& cycle) {
  const Skeleton& skeleton = model.skeleton;
  const int keys = cycle.intervals + 1;
  const float duration = cycle.duration;
  Animation clip;
  clip.name = cycle.name;
  clip.duration = duration;
  clip.loop = true;
  // Cubic-spline keys with the swing's own derivative as tangents, so the motion is smooth (C¹) through the keys:
  // secondary motion feels a clip's accelerations, and linear keys would make them kicks at every key.
  Pose pose = skeleton.bind_pose();
  const float key_rate = 2.0f * pi / duration;  // dφ/dt
  for (const Swing& swing : cycle.swings) {
    const std::int32_t bone = skeleton.find(swing.bone);
    if (bone < 0) throw Error::in_file(model.name, cycle.name, std::string("no bone '") + swing.bone + "'");
    Channel channel;
    channel.bone = bone;
    channel.rotation.interpolation = Interpolation::cubic_spline;
    const auto rotation_at = [&](float phase) {
      skeleton.set_euler(pose, bone,
                         skeleton.bone(bone).bind_rotation + swing.offset +
                             swing.amplitude * std::sin(swing.harmonic * phase + swing.phase));
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
  if (cycle.bob != glm::vec3(0.0f)) {
    Channel hips;
    hips.bone = 0;
    hips.translation.interpolation = Interpolation::cubic_spline;
    const float h = cycle.bob_harmonic;
    for (int k = 0; k < keys; ++k) {
      const float phase = 2.0f * pi * float(k % (keys - 1)) / float(keys - 1);
      hips.translation.times.push_back(duration * float(k) / float(keys - 1));
      hips.translation.values.push_back(skeleton.bone(0).bind_translation + cycle.bob * std::cos(h * phase));
      const glm::vec3 tangent = -(cycle.bob * h) * std::sin(h * phase) * key_rate;  // analytic
      hips.translation.in_tangents.push_back(tangent);
      hips.translation.out_tangents.push_back(tangent);
    }
    clip.channels.push_back(std::move(hips));
  }
  clip.require_valid(skeleton.bone_count(), model.name);
  return clip;
}

// The walk: one step of each leg per second, the arms swinging against the legs, the hips bobbing twice per cycle.
constexpr Swing walk_swings[] = {
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

// The idle: a 4 s breath — the chest rising, the spine and head drifting, the arms hanging loosely at the sides, the
// hips swaying a centimetre.
constexpr Swing idle_swings[] = {
    {"spine", {0.0f, 0.0f, 0.0f}, {1.0f, 2.0f, 1.0f}, 0.0f},
    {"chest", {0.0f, 0.0f, 0.0f}, {2.0f, 0.0f, 0.0f}, 0.5f * pi},
    {"neck", {0.0f, 0.0f, 0.0f}, {-2.0f, 5.0f, 0.0f}, pi},
    {"head", {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 2.0f}, 0.5f * pi},
    {"upperarm_l", {0.0f, 0.0f, -72.0f}, {2.0f, 0.0f, 2.0f}, 0.5f * pi},
    {"upperarm_r", {0.0f, 0.0f, 72.0f}, {2.0f, 0.0f, -2.0f}, 0.5f * pi},
    {"forearm_l", {15.0f, 0.0f, 0.0f}, {3.0f, 0.0f, 0.0f}, 0.5f * pi},
    {"forearm_r", {15.0f, 0.0f, 0.0f}, {3.0f, 0.0f, 0.0f}, 0.5f * pi},
    {"thigh_l", {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -1.5f}, 0.0f},
    {"thigh_r", {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -1.5f}, 0.0f},
};

// The run: 0.7 s per cycle, the body leaning forward, longer strides, the knees bent high, the arms bent at 85° and
// pumping against the legs, the hips bobbing 4 cm twice per cycle.
constexpr Swing run_swings[] = {
    {"spine", {12.0f, 0.0f, 0.0f}, {2.0f, 10.0f, 0.0f}, 0.0f},
    {"neck", {-8.0f, 0.0f, 0.0f}, {0.0f, -8.0f, 0.0f}, 0.0f},
    {"upperarm_l", {0.0f, 0.0f, -70.0f}, {40.0f, 0.0f, 5.0f}, pi},
    {"upperarm_r", {0.0f, 0.0f, 70.0f}, {40.0f, 0.0f, -5.0f}, 0.0f},
    {"forearm_l", {85.0f, 0.0f, 0.0f}, {20.0f, 0.0f, 0.0f}, pi},
    {"forearm_r", {85.0f, 0.0f, 0.0f}, {20.0f, 0.0f, 0.0f}, 0.0f},
    {"thigh_l", {-25.0f, 0.0f, 0.0f}, {-40.0f, 0.0f, 0.0f}, 0.0f},
    {"thigh_r", {-25.0f, 0.0f, 0.0f}, {-40.0f, 0.0f, 0.0f}, pi},
    {"shin_l", {60.0f, 0.0f, 0.0f}, {50.0f, 0.0f, 0.0f}, 0.5f * pi},
    {"shin_r", {60.0f, 0.0f, 0.0f}, {50.0f, 0.0f, 0.0f}, 1.5f * pi},
    {"foot_l", {0.0f, 0.0f, 0.0f}, {10.0f, 0.0f, 0.0f}, pi},
    {"foot_r", {0.0f, 0.0f, 0.0f}, {10.0f, 0.0f, 0.0f}, 0.0f},
};

// The wave: 2 s, the right arm raised — elbow at shoulder height, forearm upright — and waving three times (1.5 Hz)
// side to side at the elbow, the hand flicking a quarter cycle behind; the left arm hangs, the body sways.
constexpr Swing wave_swings[] = {
    {"spine", {0.0f, 0.0f, 0.0f}, {1.0f, 3.0f, 0.0f}, 0.0f},
    {"neck", {0.0f, 0.0f, 0.0f}, {0.0f, 4.0f, 0.0f}, 0.5f * pi},
    {"upperarm_r", {25.0f, 70.0f, -30.0f}, {0.0f, 0.0f, 2.0f}, 0.0f, 3.0f},
    {"forearm_r", {90.0f, 0.0f, 0.0f}, {25.0f, 0.0f, 0.0f}, 0.0f, 3.0f},
    {"hand_r", {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 15.0f}, -0.5f * pi, 3.0f},
    {"upperarm_l", {0.0f, 0.0f, -70.0f}, {2.0f, 0.0f, 1.0f}, 0.0f},
    {"forearm_l", {15.0f, 0.0f, 0.0f}, {3.0f, 0.0f, 0.0f}, 0.0f},
};

}  // namespace

Animation builtin_walk(const Model& model) {
  return make_cycle(model, {"walk", 1.0f, 16, walk_swings, {0.0f, 0.02f, 0.0f}, 2.0f});
}

std::vector<Animation> builtin_clips(const Model& model) {
  std::vector<Animation> clips;
  clips.push_back(make_cycle(model, {"idle", 4.0f, 32, idle_swings, {0.008f, 0.004f, 0.0f}, 1.0f}));
  clips.push_back(builtin_walk(model));
  clips.push_back(make_cycle(model, {"run", 0.7f, 16, run_swings, {0.0f, 0.04f, 0.0f}, 2.0f}));
  clips.push_back(make_cycle(model, {"wave", 2.0f, 48, wave_swings, {0.005f, 0.0f, 0.0f}, 1.0f}));
  return clips;
}

}  // namespace deform
