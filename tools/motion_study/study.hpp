#pragma once
// The secondary-motion study (docs/elasticity.md, "Measured"): the spread of a tip's path over frame rates and its
// match across scales, for libdeform's spring chains and inertial lattices and for a naive per-frame spring (VRM's
// update) on the same motion. Header-only so that the tool and its test measure the same way.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/spring_chain.hpp"

namespace motion_study {

constexpr double checkpoint_rate = 15.0;  // every run lands on every 1/15 s, where runs are compared

// Frame times from 0 to `seconds` landing on every checkpoint: round(hz / 15) equal steps between two, or as many
// steps cut at random places (`jitter`, seeded).
inline std::vector<double> frame_times(double hz, double seconds, bool jitter, std::uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::vector<double> times{0.0};
  const int per = std::max(1, int(std::lround(hz / checkpoint_rate)));
  for (int c = 0; c < int(std::lround(seconds * checkpoint_rate)); ++c) {
    std::vector<double> cuts;
    for (int k = 1; k < per; ++k)
      cuts.push_back(jitter ? std::uniform_real_distribution<double>(0.0, 1.0)(rng) : double(k) / per);
    std::sort(cuts.begin(), cuts.end());
    for (const double cut : cuts) times.push_back((c + cut) / checkpoint_rate);
    times.push_back((c + 1) / checkpoint_rate);
  }
  return times;
}

inline bool at_checkpoint(double t) { return std::abs(t * checkpoint_rate - std::round(t * checkpoint_rate)) < 1e-7; }

using Path = std::vector<glm::vec3>;  // a point at every checkpoint after t = 0

// The spread over runs (max - min at a checkpoint, the largest over checkpoints and axes) against the motion's
// amplitude (max - min of the first run over its checkpoints, the largest axis).
struct Spread {
  double spread = 0.0;
  double amplitude = 0.0;
  double percent() const { return amplitude > 0.0 ? 100.0 * spread / amplitude : 0.0; }
};
inline Spread spread_of(const std::vector<Path>& runs) {
  Spread s;
  for (int axis = 0; axis < 3; ++axis) {
    double lo = 1e300, hi = -1e300;
    for (const glm::vec3& p : runs.front()) lo = std::min(lo, double(p[axis])), hi = std::max(hi, double(p[axis]));
    s.amplitude = std::max(s.amplitude, hi - lo);
    for (std::size_t k = 0; k < runs.front().size(); ++k) {
      double a = 1e300, b = -1e300;
      for (const Path& run : runs) a = std::min(a, double(run[k][axis])), b = std::max(b, double(run[k][axis]));
      s.spread = std::max(s.spread, b - a);
    }
  }
  return s;
}

// How far `scaled`, divided by `scale`, is from `unit`, as a percentage of `unit`'s amplitude.
inline double scale_mismatch_percent(const Path& unit, const Path& scaled, double scale) {
  Path back = scaled;
  for (glm::vec3& p : back) p /= float(scale);
  return spread_of({unit, back}).percent();
}

// --- the naive per-frame spring: VRMC_springBone's update (see deform::VrmSpringJoint), tails in world space ------
class VrmChain {
 public:
  VrmChain(std::vector<std::int32_t> bones, glm::vec3 tip, const deform::VrmSpringJoint& joint,
           std::vector<deform::SpringCollider> colliders)
      : bones_(std::move(bones)), tip_(tip), joint_(joint), colliders_(std::move(colliders)) {}
  // One frame: the animated world matrices; the tails follow with VRM's per-frame factors. Its forces are in metres
  // whatever the model's scale, as VRM's are; the radii scale with the bones.
  void run(float dt, std::span<const glm::mat4> world, float scale) {
    std::vector<glm::vec3> animated;  // first head, then each bone's tail
    for (const std::int32_t b : bones_) animated.emplace_back(world[std::size_t(b)][3]);
    animated.emplace_back(world[std::size_t(bones_.back())] * glm::vec4(tip_, 1.0f));
    if (tails_.empty()) {
      tails_.assign(animated.begin() + 1, animated.end());
      previous_ = tails_;
    }
    glm::vec3 head = animated[0];
    glm::quat bend(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t i = 0; i < tails_.size(); ++i) {
      const glm::vec3 bone = bend * (animated[i + 1] - animated[i]);
      const float length = glm::length(bone);
      glm::vec3 next = tails_[i] + (tails_[i] - previous_[i]) * (1.0f - joint_.drag_force) +
                       bone / length * (joint_.stiffness * dt) +
                       glm::normalize(joint_.gravity_dir) * (joint_.gravity_power * dt);
      next = head + glm::normalize(next - head) * length;
      for (const deform::SpringCollider& c : colliders_) {
        const glm::mat4& m = world[std::size_t(c.bone)];
        const glm::vec3 a(m * glm::vec4(c.start, 1.0f)), b(m * glm::vec4(c.end, 1.0f));
        const glm::vec3 ab = b - a;
        const float along =
            glm::dot(ab, ab) > 0.0f ? std::clamp(glm::dot(next - a, ab) / glm::dot(ab, ab), 0.0f, 1.0f) : 0.0f;
        const glm::vec3 nearest = a + ab * along;
        const float reach = (c.radius + joint_.hit_radius) * scale;
        if (glm::length(next - nearest) < reach) {
          next = nearest + glm::normalize(next - nearest) * reach;
          next = head + glm::normalize(next - head) * length;
        }
      }
      previous_[i] = tails_[i];
      tails_[i] = next;
      const glm::vec3 from = bone, to = next - head;
      const glm::vec3 c = glm::cross(from, to);
      bend = glm::normalize(glm::quat(glm::length(from) * glm::length(to) + glm::dot(from, to), c.x, c.y, c.z)) * bend;
      head = next;
    }
  }
  glm::vec3 tip() const { return tails_.back(); }

 private:
  std::vector<std::int32_t> bones_;
  glm::vec3 tip_;
  deform::VrmSpringJoint joint_;
  std::vector<deform::SpringCollider> colliders_;
  std::vector<glm::vec3> tails_, previous_;
};

// --- the whip: six links of 0.15 m on a root that swings about Z and sways along Y ------------------------------

struct Whip {
  int links = 6;
  float link = 0.15f;
  double swing = 0.6;  // rad
  double sway = 0.15;  // m
  deform::Skeleton skeleton() const {
    std::vector<deform::Bone> bones(std::size_t(links) + 1);
    bones[0] = {"root", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
    for (int i = 1; i <= links; ++i)
      bones[std::size_t(i)] = {"link" + std::to_string(i),
                               i - 1,
                               i < links ? std::vector<std::int32_t>{i + 1} : std::vector<std::int32_t>{},
                               glm::vec3(i == 1 ? 0.1f : link, 0.0f, 0.0f),
                               glm::vec3(0.0f),
                               {}};
    return deform::Skeleton(bones);
  }
  glm::dmat4 root(double t, double scale) const {
    const double ramp = 1.0 - std::exp(-3.0 * t), pi = 3.14159265358979;
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, sway * std::sin(2 * pi * 1.1 * t) * ramp, 0.0));
    m = glm::rotate(m, swing * std::sin(2 * pi * 0.8 * t) * ramp, glm::dvec3(0, 0, 1));
    return glm::scale(glm::dmat4(1.0), glm::dvec3(scale)) * m;
  }
};

// VRM parameters whose 60 Hz motion matches a 4 Hz, ζ = 0.4 chain with 9.81 m/s² gravity on 0.15 m links.
inline deform::VrmSpringJoint whip_joint() {
  deform::VrmSpringJoint joint;
  joint.stiffness = 1.5791f;
  joint.drag_force = 0.2848f;
  joint.gravity_power = 0.1635f;
  joint.hit_radius = 0.02f;
  return joint;
}

inline deform::SpringCollider whip_collider() {
  return {0, glm::vec3(0.55f, -0.35f, 0.0f), glm::vec3(0.55f, -0.35f, 0.0f), 0.2f};
}

enum class Method { libdeform, naive };

// The whip's tip at every checkpoint over `seconds`, stepped at `times`, the world scaled by `scale`.
inline Path whip_tip(Method method, const std::vector<double>& times, double scale, bool collider,
                     const Whip& whip = {}) {
  const deform::Skeleton skeleton = whip.skeleton();
  std::vector<std::int32_t> bones;
  for (int i = 1; i <= whip.links; ++i) bones.push_back(i);
  const glm::vec3 tip(whip.link, 0.0f, 0.0f);
  const std::vector<deform::SpringCollider> colliders =
      collider ? std::vector{whip_collider()} : std::vector<deform::SpringCollider>{};
  deform::SpringChainSpec spec = deform::vrm_spring_settings(whip_joint(), whip.link);
  spec.name = "whip";
  spec.bones = bones;
  spec.tip = tip;
  if (collider) spec.colliders = {0};
  deform::SpringChains springs(skeleton, {spec}, colliders);
  VrmChain naive(bones, tip, whip_joint(), colliders);
  Path out;
  std::vector<glm::mat4> world(skeleton.bone_count()), rate(world.size());
  for (std::size_t n = 0; n < times.size(); ++n) {
    const glm::dmat4 root = whip.root(times[n], scale);
    const glm::dmat4 root_rate = (whip.root(times[n] + 1e-6, scale) - whip.root(times[n] - 1e-6, scale)) / 2e-6;
    for (std::size_t b = 0; b < world.size(); ++b) {
      world[b] = glm::mat4(root * glm::dmat4(skeleton.bind_world()[b]));
      rate[b] = glm::mat4(root_rate * glm::dmat4(skeleton.bind_world()[b]));
    }
    const float dt = n == 0 ? 0.0f : float(times[n] - times[n - 1]);
    if (method == Method::libdeform) {
      springs.run(dt, world, rate);
    } else {
      naive.run(dt, world, float(scale));
    }
    if (n > 0 && at_checkpoint(times[n]))
      out.push_back(method == Method::libdeform ? springs.points(0).back() : naive.tip());
  }
  return out;
}

// --- the walk: the built-in character's walk, its arm's lattices lagging behind (inertia 1) ---------------------

// The built-in character scaled by `scale` (mesh, bones and the walk's translations), with its walk.
struct ScaledCharacter {
  deform::Model model;
  deform::Animation walk;
};
inline ScaledCharacter scaled_builtin(double scale) {
  ScaledCharacter c{deform::builtin_character(), {}};
  for (glm::vec3& p : c.model.mesh.positions) p *= float(scale);
  std::vector<deform::Bone> bones(c.model.skeleton.bones().begin(), c.model.skeleton.bones().end());
  for (deform::Bone& b : bones) b.bind_translation *= float(scale);
  c.model.skeleton = deform::Skeleton(bones);
  c.walk = deform::builtin_walk(deform::builtin_character());
  for (deform::Channel& channel : c.walk.channels) {
    for (auto* values :
         {&channel.translation.values, &channel.translation.in_tangents, &channel.translation.out_tangents})
      for (glm::vec3& v : *values) v *= float(scale);
  }
  return c;
}

// The left hand's path (carried by the jiggling lattices). libdeform: the exact step with the pose's lead; naive:
// the thesis' per-frame Verlet, its damping matched at 60 Hz, without a lead.
inline Path walk_hand(Method method, const std::vector<double>& times, double scale) {
  ScaledCharacter scaled = scaled_builtin(scale);
  deform::Rig rig = deform::builtin_rig(scaled.model);
  for (deform::LatticeSpec& lattice : rig.lattices) {
    lattice.motion.inertia = 1.0f;
    lattice.motion.far_share = 1.0f;  // the hand lags with the forearm's far face
    if (method == Method::naive) {
      lattice.elastic.integrator = deform::Integrator::verlet;
      lattice.elastic.verlet_kd = float(deform::verlet_kd(lattice.elastic.oscillator, 1.0 / 60.0));
    }
  }
  deform::Character character(std::move(scaled.model), rig);
  const deform::Pose bind = character.skeleton().bind_pose();
  deform::Pose pose = bind, later = bind;
  const auto sample = [&](double t, deform::Pose& into) {
    into = bind;
    deform::SamplingJob job;
    job.animation = &scaled.walk;
    job.time = float(t);
    job.rotations = into.rotations;
    job.translations = into.translations;
    job.run();
  };
  const std::int32_t hand = character.skeleton().find("hand_l");
  Path out;
  for (std::size_t n = 0; n < times.size(); ++n) {
    sample(times[n], pose);
    if (method == Method::libdeform) {
      sample(times[n] + 1e-3, later);
      character.set_pose(pose, later, 1e-3f);
    } else {
      character.set_pose(pose);
    }
    character.update(n == 0 ? 0.0f : float(times[n] - times[n - 1]));
    if (n > 0 && at_checkpoint(times[n])) out.push_back(character.bone_position(hand));
  }
  return out;
}

// --- the whole character: the built-in character with every limb's lattice (builtin_full_rig) and the ponytail ----

// What a whole-character run records at every checkpoint of `checkpoint_hz` (k / checkpoint_hz s): every point of
// the deformed surface and the ponytail's spring points.
struct CharacterPaths {
  std::vector<Path> surface;   // per checkpoint, every mesh point
  std::vector<Path> ponytail;  // per checkpoint, the chain's points (first head, then the tails)
};

// `into` = `animation` at t seconds over `bind` (the clip's channels replace the bind's values).
inline void sample_clip(const deform::Animation& animation, const deform::Pose& bind, double t, deform::Pose& into) {
  into = bind;
  deform::SamplingJob job;
  job.animation = &animation;
  job.time = float(t);
  job.rotations = into.rotations;
  job.translations = into.translations;
  job.run();
}

// The built-in full rig with every lattice's tuned motion (default_lattice_motion of its part, inertia included).
inline deform::Rig tuned_full_rig() {
  deform::Rig rig = deform::builtin_full_rig(deform::builtin_character());
  for (deform::LatticeSpec& lattice : rig.lattices)
    lattice.motion = deform::default_lattice_motion(deform::builtin_body_part(lattice.name));
  return rig;
}

// Plays the built-in clip `clip` on the built-in character with `rig` (its lattices' motion as the rig has it, or
// every lattice's inertia set to `inertia` when it is >= 0), stepped at `hz` for `seconds`, posed with the pose
// `lead` seconds later; records at every 1 / checkpoint_hz s.
inline CharacterPaths play_character(const deform::Rig& rig, const std::string& clip, double hz, double seconds,
                                     double checkpoint_hz = 3.0, float inertia = -1.0f, float lead = 1e-3f) {
  deform::Model model = deform::builtin_character();
  deform::Animation animation;
  for (deform::Animation& a : deform::builtin_clips(model))
    if (a.name == clip) animation = std::move(a);
  deform::Rig tuned = rig;
  if (inertia >= 0.0f)
    for (deform::LatticeSpec& lattice : tuned.lattices) lattice.motion.inertia = inertia;
  deform::Character character(std::move(model), tuned);
  const deform::Pose bind = character.skeleton().bind_pose();
  deform::Pose pose = bind, later = bind;
  const auto sample = [&](double t, deform::Pose& into) { sample_clip(animation, bind, t, into); };
  CharacterPaths out;
  const auto steps = std::size_t(std::llround(seconds * hz));
  const auto per = std::size_t(std::llround(hz / checkpoint_hz));
  for (std::size_t n = 0; n <= steps; ++n) {
    const double t = double(n) / hz;
    sample(t, pose);
    if (lead > 0.0f) {
      sample(t + double(lead), later);
      character.set_pose(pose, later, lead);
    } else {
      character.set_pose(pose);
    }
    character.update(n == 0 ? 0.0f : float(1.0 / hz));
    if (n == 0 || n % per != 0) continue;
    out.surface.emplace_back(character.positions().begin(), character.positions().end());
    if (character.springs().chain_count() > 0) {
      const auto points = character.springs().points(0);
      out.ponytail.emplace_back(points.begin(), points.end());
    }
  }
  return out;
}

// The largest distance of any point at any checkpoint from `reference`'s, as a percentage of `amplitude`.
inline double largest_difference(const std::vector<Path>& run, const std::vector<Path>& reference) {
  double largest = 0.0;
  for (std::size_t k = 0; k < std::min(run.size(), reference.size()); ++k)
    for (std::size_t p = 0; p < std::min(run[k].size(), reference[k].size()); ++p)
      largest = std::max(largest, double(glm::length(run[k][p] - reference[k][p])));
  return largest;
}

// The jiggle's amplitude: the largest range of any point along any axis over the checkpoints.
inline double amplitude_of(const std::vector<Path>& run) {
  double largest = 0.0;
  if (run.empty()) return 0.0;
  for (std::size_t p = 0; p < run.front().size(); ++p)
    for (int axis = 0; axis < 3; ++axis) {
      double lo = 1e300, hi = -1e300;
      for (const Path& at : run) lo = std::min(lo, double(at[p][axis])), hi = std::max(hi, double(at[p][axis]));
      largest = std::max(largest, hi - lo);
    }
  return largest;
}

// --- flesh, not a longer limb: the jiggle's shape against the rigid walk -------------------------------------------

// How the jiggle of `rig`'s lattices (their motion as the rig has it) deforms a character over a clip, against the
// same clip with every lattice's inertia 0 (the rigid clip), every 1/30 s:
struct FleshMeasure {
  double limb_percent = 0.0;    // the largest change of a limb's length (from its upper limb's joint to its hand's
                                // or foot's, between the skin points nearest those joints in the bind pose), % of
                                // the rigid one's
  double volume_percent = 0.0;  // the largest change of a lattice's volume (its control grid's cells), %
  double jiggle = 0.0;          // the largest distance of a skin point from the rigid clip's, model units
  double height = 0.0;          // the bind pose's extent along its tallest axis, model units (jiggle's yardstick)
  std::string worst_limb, worst_lattice;
  std::vector<double> times;                      // the samples' times
  std::vector<std::string> limbs;                 // "upper-end" bone keys: upperarm_l-hand_l, thigh_r-foot_r, ...
  std::vector<std::vector<double>> limb_length;   // per limb, its length at every sample
  std::vector<std::vector<double>> rigid_length;  // the same in the rigid clip
  double jiggle_percent() const { return height > 0.0 ? 100.0 * jiggle / height : 0.0; }
};

// The signed volume of a lattice's control grid (i-fastest, `counts` points per axis): its cells, six tetrahedra each.
inline double grid_volume(std::span<const glm::vec3> p, glm::ivec3 counts) {
  const auto at = [&](int i, int j, int k) { return glm::dvec3(p[std::size_t(i + counts.x * (j + counts.y * k))]); };
  double volume = 0.0;
  const auto tet = [](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d) {
    return glm::dot(b - a, glm::cross(c - a, d - a)) / 6.0;
  };
  for (int k = 0; k + 1 < counts.z; ++k)
    for (int j = 0; j + 1 < counts.y; ++j)
      for (int i = 0; i + 1 < counts.x; ++i) {
        const glm::dvec3 c000 = at(i, j, k), c100 = at(i + 1, j, k), c010 = at(i, j + 1, k), c110 = at(i + 1, j + 1, k),
                         c001 = at(i, j, k + 1), c101 = at(i + 1, j, k + 1), c011 = at(i, j + 1, k + 1),
                         c111 = at(i + 1, j + 1, k + 1);
        // The cube's six tetrahedra around its diagonal c000-c111.
        volume += tet(c000, c100, c110, c111) + tet(c000, c110, c010, c111) + tet(c000, c010, c011, c111) +
                  tet(c000, c011, c001, c111) + tet(c000, c001, c101, c111) + tet(c000, c101, c100, c111);
      }
  return volume;
}

// The limbs of a rig, from its lattices' parts: each hand or foot lattice's bone, and each reach effector, with the
// nearest bone above it that has an upper limb lattice (its shoulder's or hip's joint), as (upper, end) bone pairs.
inline std::vector<std::pair<std::int32_t, std::int32_t>> rig_limbs(const deform::Rig& rig,
                                                                    const deform::Skeleton& skeleton) {
  std::vector<std::int32_t> ends;
  for (const deform::LatticeSpec& end : rig.lattices)
    if (end.motion.part == deform::BodyPart::hand || end.motion.part == deform::BodyPart::foot)
      ends.push_back(end.bone);
  if (rig.reach_effector >= 0) ends.push_back(rig.reach_effector);
  for (const deform::Rig::ReachChain& chain : rig.reach_chains) ends.push_back(chain.effector);
  std::vector<std::pair<std::int32_t, std::int32_t>> limbs;
  for (const std::int32_t end : ends) {
    for (std::int32_t b = skeleton.bone(end).parent; b >= 0; b = skeleton.bone(b).parent) {
      const auto upper = std::find_if(rig.lattices.begin(), rig.lattices.end(), [&](const deform::LatticeSpec& l) {
        return l.bone == b && l.motion.part == deform::BodyPart::upper_limb;
      });
      if (upper == rig.lattices.end()) continue;
      if (std::find(limbs.begin(), limbs.end(), std::pair(b, end)) == limbs.end()) limbs.emplace_back(b, end);
      break;
    }
  }
  return limbs;
}

// The flesh measures of `rig` on `model` playing `animation` at `hz` for `seconds`; with `inertia_scale` >= 0 the
// jiggling character's lattices take that scale of their parts' tuned inertia first (set_inertia_scale, as the
// viewer's slider and `deform simulate --inertia` do).
inline FleshMeasure measure_flesh(const deform::Model& model, const deform::Animation& animation,
                                  const deform::Rig& rig, double hz, double seconds, float inertia_scale = -1.0f) {
  deform::Rig rigid_rig = rig;
  for (deform::LatticeSpec& lattice : rigid_rig.lattices) lattice.motion = {};
  deform::Character jiggly(model, rig), rigid(model, rigid_rig);
  if (inertia_scale >= 0.0f) jiggly.deformers().set_inertia_scale(inertia_scale);
  const deform::Skeleton& skeleton = jiggly.skeleton();
  // The limbs: the skin points nearest their end joints in the bind pose.
  const auto nearest = [&](std::int32_t bone) {
    const glm::vec3 joint(skeleton.bind_world()[std::size_t(bone)][3]);
    std::size_t best = 0;
    for (std::size_t p = 0; p < model.mesh.positions.size(); ++p)
      if (glm::length(model.mesh.positions[p] - joint) < glm::length(model.mesh.positions[best] - joint)) best = p;
    return best;
  };
  struct Limb {
    std::string name;
    std::size_t a, b;
  };
  std::vector<Limb> limbs;
  for (const auto& [upper, end] : rig_limbs(rig, skeleton))
    limbs.push_back({skeleton.key(upper) + "-" + skeleton.key(end), nearest(upper), nearest(end)});
  FleshMeasure m;
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : model.mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  m.height = model.mesh.positions.empty() ? 0.0 : double(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}));
  const deform::Pose bind = skeleton.bind_pose();
  deform::Pose pose = bind, later = bind;
  const auto sample = [&](double t, deform::Pose& into) { sample_clip(animation, bind, t, into); };
  std::vector<std::vector<double>> lengths(limbs.size()), rigid_lengths(limbs.size());
  const auto steps = std::size_t(std::llround(seconds * hz));
  const auto per = std::max<std::size_t>(1, std::size_t(std::llround(hz / 30.0)));
  for (std::size_t n = 0; n <= steps; ++n) {
    const double t = double(n) / hz;
    sample(t, pose);
    sample(t + 1e-3, later);
    for (deform::Character* c : {&jiggly, &rigid}) {
      c->set_pose(pose, later, 1e-3f);
      c->update(n == 0 ? 0.0f : float(1.0 / hz));
    }
    if (n == 0 || n % per != 0) continue;
    m.times.push_back(t);
    const auto skin = jiggly.positions(), still = rigid.positions();
    for (std::size_t p = 0; p < skin.size(); ++p)
      m.jiggle = std::max(m.jiggle, double(glm::length(skin[p] - still[p])));
    for (std::size_t l = 0; l < limbs.size(); ++l) {
      const double length = glm::length(skin[limbs[l].a] - skin[limbs[l].b]);
      const double reference = glm::length(still[limbs[l].a] - still[limbs[l].b]);
      lengths[l].push_back(length);
      rigid_lengths[l].push_back(reference);
      const double percent = 100.0 * std::abs(length / reference - 1.0);
      if (percent > m.limb_percent) m.limb_percent = percent, m.worst_limb = limbs[l].name;
    }
    const deform::DeformerHierarchy& lattices = jiggly.deformers();
    for (std::size_t l = 0; l < lattices.lattice_count(); ++l) {
      const glm::ivec3 counts = lattices.rest_lattice(l).point_counts();
      const double volume = grid_volume(lattices.control_points(l), counts);
      const double reference = grid_volume(rigid.deformers().control_points(l), counts);
      const double percent = 100.0 * std::abs(volume / reference - 1.0);
      if (percent > m.volume_percent) m.volume_percent = percent, m.worst_lattice = lattices.spec(l).name;
    }
  }
  for (const Limb& limb : limbs) m.limbs.push_back(limb.name);
  m.limb_length = std::move(lengths);
  m.rigid_length = std::move(rigid_lengths);
  return m;
}

// The imported clips the flesh is measured on (Debian's assimp-testmodels, with default_rig): the tool's table in
// docs/elasticity.md and the test that holds them to 2% and 3%.
struct ImportedClip {
  const char* file;
  const char* clip;
};
// How long a clip is measured: 2 s as the built-in clips, looping; a clip that does not loop, at most its length.
inline double measured_seconds(const deform::Animation& clip) {
  return clip.loop ? 2.0 : std::min(2.0, double(clip.duration));
}
inline std::vector<ImportedClip> imported_clips() {
  return {{"/usr/share/assimp/models/IQM/mrfixit.iqm", "idle"},
          {"/usr/share/assimp/models/X/Testwuson.X", "Wuson_Walk"},
          {"/usr/share/assimp/models/X/Testwuson.X", "Wuson_Run"}};
}

// The same on the built-in character and its clip `clip` ("walk", "run", ...).
inline FleshMeasure measure_flesh(const deform::Rig& rig, const std::string& clip, double hz, double seconds,
                                  float inertia_scale = -1.0f) {
  const deform::Model model = deform::builtin_character();
  deform::Animation animation;
  for (deform::Animation& a : deform::builtin_clips(model))
    if (a.name == clip) animation = std::move(a);
  return measure_flesh(model, animation, rig, hz, seconds, inertia_scale);
}

// One row of the study: a motion measured over 15, 30, 60, 144 and 240 Hz and a jittered frame time (about 60 Hz),
// and at scales 0.01 and 100 against the scaled 60 Hz path.
struct Row {
  std::string motion;
  std::string method;
  double spread_percent = 0.0;
  double spread_without_15_percent = 0.0;
  double scale_percent = 0.0;  // the larger of the two scales' mismatch
};

template <class Run>
Row measure(std::string motion, std::string method, double seconds, Run run) {
  std::vector<Path> runs;
  for (const double hz : {15.0, 30.0, 60.0, 144.0, 240.0}) runs.push_back(run(frame_times(hz, seconds, false), 1.0));
  runs.push_back(run(frame_times(60.0, seconds, true), 1.0));
  Row row{std::move(motion), std::move(method), spread_of(runs).percent(), 0.0, 0.0};
  row.spread_without_15_percent = spread_of(std::vector<Path>(runs.begin() + 1, runs.end())).percent();
  for (const double scale : {0.01, 100.0})
    row.scale_percent = std::max(row.scale_percent,
                                 scale_mismatch_percent(runs[2], run(frame_times(60.0, seconds, false), scale), scale));
  return row;
}

}  // namespace motion_study
