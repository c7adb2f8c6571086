// The pose driver (runtime/pose_driver.hpp, offline/pose_driver.hpp): the swing-twist distance against angles found
// by a plain double-precision decomposition over 3,000 seeded rotation pairs up to half turns, the RBF exact at its
// samples and equal to a plain double evaluation elsewhere, twist ignored on request, hostile input refused, and no
// allocation per frame.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <numbers>
#include <random>
#include <vector>

#include "allocation_counter.hpp"  // counts every allocation of this executable
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/rig.hpp"
#include "deform/offline/pose_driver.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/pose_driver.hpp"

namespace {

using dquat = glm::dquat;

glm::quat random_rotation(std::mt19937& rng, float max_degrees) {
  std::uniform_real_distribution<float> angle(-max_degrees, max_degrees);
  return deform::quat_from_euler({angle(rng), angle(rng), angle(rng)});
}

// The swing and twist angles of b relative to a about `axis`, in double precision by the textbook construction: the
// twist the projection of the rotation onto the axis, the swing what is left, each angle 2·atan2(|v|, |w|).
void swing_twist_angles(glm::quat a, glm::quat b, glm::vec3 axis, double& swing, double& twist) {
  const dquat r = glm::conjugate(dquat(a)) * dquat(b);
  const glm::dvec3 n(axis);
  const double tau = glm::dot(glm::dvec3(r.x, r.y, r.z), n);
  dquat t(r.w, tau * n.x, tau * n.y, tau * n.z);
  const double length = glm::length(t);
  t = length > 0.0 ? t / length : dquat(1.0, 0.0, 0.0, 0.0);
  const dquat s = r * glm::conjugate(t);
  twist = 2.0 * std::atan2(std::abs(tau) / (length > 0.0 ? length : 1.0), std::abs(t.w));
  swing = 2.0 * std::atan2(glm::length(glm::dvec3(s.x, s.y, s.z)), std::abs(s.w));
}

TEST_CASE("swing-twist distance: the chords of the swing and twist angles, on 3,000 seeded pairs") {
  std::mt19937 rng(2019);
  for (int trial = 0; trial < 3000; ++trial) {
    const glm::quat a = random_rotation(rng, 180.0f), b = random_rotation(rng, 180.0f);
    const glm::vec3 axis = glm::normalize(glm::vec3(random_rotation(rng, 180.0f) * glm::vec3(0, 1, 0)));
    const float weight = trial % 3 == 0 ? 0.0f : trial % 3 == 1 ? 1.0f : 0.5f;
    double swing = 0.0, twist = 0.0;
    swing_twist_angles(a, b, axis, swing, twist);
    const double expected =
        4.0 * std::pow(std::sin(swing / 2), 2) + weight * weight * 4.0 * std::pow(std::sin(twist / 2), 2);
    CAPTURE(trial);
    CHECK(deform::swing_twist_distance_squared(a, b, axis, weight) ==
          doctest::Approx(expected).epsilon(1e-4).scale(1.0));
    // Symmetric.
    CHECK(deform::swing_twist_distance_squared(b, a, axis, weight) ==
          doctest::Approx(deform::swing_twist_distance_squared(a, b, axis, weight)).epsilon(1e-4).scale(1.0));
  }
  // A pure twist about the axis has no swing; a pure swing no twist; a half turn's chord is 2.
  const glm::vec3 y(0, 1, 0);
  const glm::quat twist90 = glm::angleAxis(std::numbers::pi_v<float> / 2, y);
  const glm::quat swing90 = glm::angleAxis(std::numbers::pi_v<float> / 2, glm::vec3(1, 0, 0));
  CHECK(deform::swing_twist_distance_squared(glm::quat(1, 0, 0, 0), twist90, y, 0.0f) == doctest::Approx(0.0).scale(1));
  CHECK(deform::swing_twist_distance_squared(glm::quat(1, 0, 0, 0), twist90, y, 1.0f) == doctest::Approx(2.0));
  CHECK(deform::swing_twist_distance_squared(glm::quat(1, 0, 0, 0), swing90, y, 0.0f) == doctest::Approx(2.0));
  const glm::quat half = glm::angleAxis(std::numbers::pi_v<float>, glm::vec3(1, 0, 0));
  CHECK(deform::swing_twist_distance_squared(glm::quat(1, 0, 0, 0), half, y, 1.0f) == doctest::Approx(4.0));
}

// Eight sample poses of the built-in character's left arm (upper arm, forearm, hand, and the right forearm), each
// the pose for one of eight shapes.
struct Driver {
  deform::Model model = deform::builtin_character();
  std::vector<std::int32_t> bones;
  std::vector<deform::Pose> samples;
  std::vector<float> targets;
  static constexpr std::size_t shapes = 8;
};

Driver make_driver(std::uint32_t seed) {
  Driver d;
  const deform::Skeleton& skeleton = d.model.skeleton;
  for (const char* name : {"upperarm_l", "forearm_l", "hand_l", "forearm_r"}) d.bones.push_back(skeleton.find(name));
  std::mt19937 rng(seed);
  for (std::size_t k = 0; k < Driver::shapes; ++k) {
    deform::Pose pose = skeleton.bind_pose();
    for (const std::int32_t bone : d.bones) pose.rotations[std::size_t(bone)] = random_rotation(rng, 90.0f);
    d.samples.push_back(pose);
    for (std::size_t s = 0; s < Driver::shapes; ++s) d.targets.push_back(s == k ? 1.0f : 0.0f);
  }
  return d;
}

std::vector<float> drive(const deform::PoseDriverBinding& binding, const deform::Pose& pose) {
  std::vector<float> weights(binding.shape_count);
  deform::PoseDriverJob job;
  job.binding = &binding;
  job.rotations = pose.rotations;
  job.weights = weights;
  REQUIRE(job.validate());
  REQUIRE(job.run());
  return weights;
}

// Σₖ φ(dₖ) Cₖₛ in double precision, the distances from the double-precision angles.
std::vector<double> plain_drive(const deform::PoseDriverBinding& b, const deform::Pose& pose) {
  std::vector<double> out(b.shape_count, 0.0);
  const std::size_t n = b.bones.size();
  for (std::size_t k = 0; k < b.pose_count(); ++k) {
    double d2 = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      double swing = 0.0, twist = 0.0;
      swing_twist_angles(b.sample_poses[k * n + j], pose.rotations[std::size_t(b.bones[j])], b.twist_axes[j], swing,
                         twist);
      d2 += 4.0 * std::pow(std::sin(swing / 2), 2) +
            b.twist_weight * b.twist_weight * 4.0 * std::pow(std::sin(twist / 2), 2);
    }
    const double x = d2 / (double(b.radius) * b.radius);
    const double phi = b.kernel == deform::RbfKernel::gaussian ? std::exp(-x) : 1.0 / std::sqrt(1.0 + x);
    for (std::size_t s = 0; s < b.shape_count; ++s) out[s] += phi * b.coefficients[k * b.shape_count + s];
  }
  if (b.clamp)
    for (double& w : out) w = std::clamp(w, 0.0, 1.0);
  return out;
}

TEST_CASE("pose driver: exact at its samples, equal to a plain evaluation between them, both kernels") {
  for (const deform::RbfKernel kernel : {deform::RbfKernel::gaussian, deform::RbfKernel::inverse_multiquadric}) {
    for (std::uint32_t seed = 1; seed <= 10; ++seed) {
      const Driver d = make_driver(seed);
      deform::PoseDriverSettings settings;
      settings.kernel = kernel;
      settings.clamp = false;
      const deform::PoseDriverBinding binding =
          deform::bind_pose_driver(d.model.skeleton, d.bones, d.samples, d.targets, Driver::shapes, settings);
      CHECK(binding.radius > 0.0f);
      CAPTURE(seed);
      for (std::size_t k = 0; k < Driver::shapes; ++k) {
        const std::vector<float> w = drive(binding, d.samples[k]);
        for (std::size_t s = 0; s < Driver::shapes; ++s)
          CHECK(w[s] == doctest::Approx(s == k ? 1.0 : 0.0).scale(1).epsilon(2e-3));
      }
      std::mt19937 rng(seed + 100);
      for (int trial = 0; trial < 50; ++trial) {
        deform::Pose pose = d.model.skeleton.bind_pose();
        for (const std::int32_t bone : d.bones) pose.rotations[std::size_t(bone)] = random_rotation(rng, 120.0f);
        const std::vector<float> w = drive(binding, pose);
        const std::vector<double> reference = plain_drive(binding, pose);
        for (std::size_t s = 0; s < Driver::shapes; ++s)
          CHECK(w[s] == doctest::Approx(reference[s]).scale(1).epsilon(1e-3));
      }
    }
  }
}

TEST_CASE("pose driver: clamped weights, no twist on request, far poses fade under the gaussian") {
  const Driver d = make_driver(7);
  const deform::PoseDriverBinding clamped =
      deform::bind_pose_driver(d.model.skeleton, d.bones, d.samples, d.targets, Driver::shapes);
  std::mt19937 rng(77);
  for (int trial = 0; trial < 200; ++trial) {
    deform::Pose pose = d.model.skeleton.bind_pose();
    for (const std::int32_t bone : d.bones) pose.rotations[std::size_t(bone)] = random_rotation(rng, 180.0f);
    for (const float w : drive(clamped, pose)) CHECK((w >= 0.0f && w <= 1.0f));
  }
  // Twist weight 0: turning every driver bone about its own axis changes nothing.
  deform::PoseDriverSettings no_twist;
  no_twist.twist_weight = 0.0f;
  const deform::PoseDriverBinding swing_only =
      deform::bind_pose_driver(d.model.skeleton, d.bones, d.samples, d.targets, Driver::shapes, no_twist);
  deform::Pose pose = d.samples[3], twisted = d.samples[3];
  for (std::size_t j = 0; j < d.bones.size(); ++j) {
    glm::quat& q = twisted.rotations[std::size_t(d.bones[j])];
    q = q * glm::angleAxis(1.0f, swing_only.twist_axes[j]);
  }
  const std::vector<float> straight = drive(swing_only, pose), turned = drive(swing_only, twisted);
  for (std::size_t s = 0; s < Driver::shapes; ++s)
    CHECK(turned[s] == doctest::Approx(straight[s]).scale(1).epsilon(1e-4));
  // With twist counted, the same turn moves the weights.
  const std::vector<float> counted = drive(clamped, twisted);
  CHECK(counted[3] < 0.9f);
}

TEST_CASE("pose driver: hostile input refused, nothing written, no allocation per frame") {
  const Driver d = make_driver(3);
  const deform::Skeleton& skeleton = d.model.skeleton;
  const auto refuses = [&](const std::vector<std::int32_t>& bones, const std::vector<deform::Pose>& samples,
                           const std::vector<float>& targets, std::size_t shapes, const char* field,
                           const deform::PoseDriverSettings& settings = {}) {
    try {
      (void)deform::bind_pose_driver(skeleton, bones, samples, targets, shapes, settings);
      FAIL("accepted: " << field);
    } catch (const deform::Error& e) {
      CHECK(std::string(e.what()).find(field) != std::string::npos);
    }
  };
  refuses({}, d.samples, d.targets, Driver::shapes, "bones");
  refuses({d.bones[0], d.bones[0]}, d.samples, d.targets, Driver::shapes, "listed twice");
  refuses({9999}, d.samples, d.targets, Driver::shapes, "not in the skeleton");
  refuses(d.bones, {}, {}, Driver::shapes, "samples");
  refuses(d.bones, d.samples, std::vector<float>(3), Driver::shapes, "targets");
  std::vector<deform::Pose> twice = d.samples;
  twice[5] = twice[2];
  refuses(d.bones, twice, d.targets, Driver::shapes, "samples 2 and 5");
  std::vector<deform::Pose> broken = d.samples;
  broken[1].rotations[std::size_t(d.bones[0])].x = std::numeric_limits<float>::quiet_NaN();
  refuses(d.bones, broken, d.targets, Driver::shapes, "sample 1");
  deform::PoseDriverSettings bad;
  bad.radius = -1.0f;
  refuses(d.bones, d.samples, d.targets, Driver::shapes, "radius", bad);

  deform::PoseDriverBinding binding = deform::bind_pose_driver(skeleton, d.bones, d.samples, d.targets, Driver::shapes);
  std::vector<float> weights(Driver::shapes, -7.0f);
  const deform::Pose pose = skeleton.bind_pose();
  deform::PoseDriverJob job;
  job.binding = &binding;
  job.rotations = std::span(pose.rotations).first(3);  // the driver bones are beyond
  job.weights = weights;
  CHECK_FALSE(job.validate());
  CHECK_FALSE(job.run());
  CHECK(weights[0] == -7.0f);
  job.rotations = pose.rotations;
  job.weights = std::span(weights).first(2);
  CHECK_FALSE(job.run());
  job.weights = weights;
  binding.radius = 0.0f;
  CHECK_FALSE(job.validate());
  binding.radius = 1.0f;
  REQUIRE(job.validate());
  const long before = allocations.load();
  for (int frame = 0; frame < 100; ++frame) REQUIRE(job.run());
  CHECK(allocations.load() == before);
  // Ranges of shapes give the same bits as the whole.
  std::vector<float> whole = weights, parts(Driver::shapes, -1.0f);
  job.weights = parts;
  CHECK(job.count() == Driver::shapes);
  REQUIRE(job.run(0, 3));
  CHECK(parts[3] == -1.0f);
  REQUIRE(job.run(3, Driver::shapes));
  CHECK(parts == whole);
  CHECK_FALSE(job.run(4, 2));
  CHECK_FALSE(job.run(0, Driver::shapes + 1));
}

TEST_CASE("a corrective sculpted at a bent elbow comes back exactly there, and fades to the rest at the bind pose") {
  deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  const std::int32_t forearm = skeleton.find("forearm_l"), upperarm = skeleton.find("upperarm_l");
  deform::Pose bent = skeleton.bind_pose();
  skeleton.set_euler(bent, forearm, {120.0f, 0.0f, 0.0f});
  // The skinning at the bent pose, and a sculpt that pads the elbow's inside: every point within 8 cm of the elbow
  // pushed 1 cm along +y.
  deform::Rig no_lattices;
  deform::Character plain(model, no_lattices);
  REQUIRE(plain.set_pose(bent));
  REQUIRE(plain.update(0.0f));
  bent = plain.pose();  // as the character holds it: within the elbow's limits
  const std::vector<glm::mat4> palette(plain.palette().begin(), plain.palette().end());
  const glm::vec3 elbow = plain.bone_position(forearm);
  std::vector<glm::vec3> sculpt(plain.positions().begin(), plain.positions().end());
  std::size_t padded = 0;
  for (glm::vec3& p : sculpt)
    if (glm::length(p - elbow) < 0.08f) p.y += 0.01f, ++padded;
  REQUIRE(padded > 10);
  const deform::MorphTarget corrective = deform::corrective_from_sculpt(model, palette, sculpt, 1e-6f, "elbow_pad");
  CHECK(corrective.points.size() == padded);
  // The driver: the bind pose (weight 0) and the bent one (weight 1) on the upper arm and forearm.
  const std::vector<std::int32_t> bones = {upperarm, forearm};
  const std::vector<deform::Pose> samples = {skeleton.bind_pose(), bent};
  const std::vector<float> targets = {0.0f, 1.0f};
  const deform::PoseDriverBinding driver = deform::bind_pose_driver(skeleton, bones, samples, targets, 1);
  model.morph_targets.push_back(corrective);
  deform::Character c(model, no_lattices);
  const std::uint32_t shape[] = {0};
  REQUIRE(c.add_pose_driver(driver, shape));
  const std::uint32_t beyond[] = {1};
  CHECK_FALSE(c.add_pose_driver(driver, beyond));
  REQUIRE(c.set_pose(bent));
  REQUIRE(c.update(0.0f));
  CHECK(c.morph_weights()[0] == doctest::Approx(1.0f).epsilon(1e-4));
  float worst = 0.0f;
  for (std::size_t i = 0; i < sculpt.size(); ++i) worst = std::max(worst, glm::length(c.positions()[i] - sculpt[i]));
  CHECK(worst < 1e-4f);  // the sculpt given back (the weight is 1 to 1e-4 of the 1 cm pad)
  // At the bind pose the shape is off and the character is its bind mesh.
  REQUIRE(c.set_pose(skeleton.bind_pose()));
  REQUIRE(c.update(0.0f));
  CHECK(c.morph_weights()[0] == doctest::Approx(0.0f).scale(1).epsilon(1e-4));
  worst = 0.0f;
  for (std::size_t i = 0; i < sculpt.size(); ++i)
    worst = std::max(worst, glm::length(c.positions()[i] - model.mesh.positions[i]));
  CHECK(worst < 1e-5f);
  // Halfway the pad is partly on.
  deform::Pose half = skeleton.bind_pose();
  skeleton.set_euler(half, forearm, {60.0f, 0.0f, 0.0f});
  REQUIRE(c.set_pose(half));
  REQUIRE(c.update(0.0f));
  CHECK(c.morph_weights()[0] > 0.05f);
  CHECK(c.morph_weights()[0] < 0.95f);
  // An instance drives the same shape.
  deform::Character copy = c.instance();
  REQUIRE(copy.set_pose(bent));
  REQUIRE(copy.update(0.0f));
  CHECK(copy.morph_weights()[0] == doctest::Approx(1.0f).epsilon(1e-4));
  // A sculpt of the wrong size is refused.
  CHECK_THROWS_AS(deform::corrective_from_sculpt(model, palette, std::span(sculpt).first(10)), deform::Error);
}

TEST_CASE("a rig's corrective group: written and read back, and the Character built from it gives the sculpt back") {
  const deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  const std::int32_t forearm = skeleton.find("forearm_l"), upperarm = skeleton.find("upperarm_l");
  deform::Pose bent = skeleton.bind_pose();
  skeleton.set_euler(bent, forearm, {110.0f, 20.0f, 0.0f});
  deform::Character plain(model);
  REQUIRE(plain.set_pose(bent));
  REQUIRE(plain.update(0.0f));
  bent = plain.pose();
  std::vector<glm::vec3> sculpt(plain.positions().begin(), plain.positions().end());
  const glm::vec3 elbow = plain.bone_position(forearm);
  for (glm::vec3& p : sculpt)
    if (glm::length(p - elbow) < 0.08f) p.z -= 0.01f;
  const deform::MorphTarget shape = deform::corrective_from_sculpt(
      model, std::vector<glm::mat4>(plain.palette().begin(), plain.palette().end()), sculpt, 1e-6f, "elbow_in");
  deform::Rig rig;
  deform::CorrectiveSpec group;
  group.name = "elbow_l";
  group.bones = {upperarm, forearm};
  group.shapes.push_back({"elbow_in",
                          {deform::euler_from_quat(bent.rotations[std::size_t(upperarm)]),
                           deform::euler_from_quat(bent.rotations[std::size_t(forearm)])},
                          shape.points,
                          shape.position_deltas});
  rig.correctives.push_back(group);
  const std::string text = deform::format_rig_json(rig, skeleton);
  const deform::Rig back = deform::parse_rig_json(text, skeleton, model.mesh.point_count(), "elbow.rig.json");
  CHECK(back.correctives == rig.correctives);
  CHECK(deform::format_rig_json(back, skeleton) == text);
  deform::Character c(model, back);
  REQUIRE(c.pose_driver_count() == 1);
  REQUIRE(c.morph_target_count() == 1);
  CHECK(c.model().morph_targets[0].name == "elbow_in");
  CHECK(c.rig().correctives == rig.correctives);
  REQUIRE(c.set_pose(bent));
  REQUIRE(c.update(0.0f));
  float worst = 0.0f;
  for (std::size_t i = 0; i < sculpt.size(); ++i) worst = std::max(worst, glm::length(c.positions()[i] - sculpt[i]));
  CHECK(worst < 1e-4f);
  REQUIRE(c.set_pose(skeleton.bind_pose()));
  REQUIRE(c.update(0.0f));
  CHECK(c.morph_weights()[0] == doctest::Approx(0.0f).scale(1).epsilon(1e-4));
  // Hostile group entries name their place.
  const auto refuses = [&](const std::string& from, const std::string& to, const char* expected) {
    std::string bad = text;
    const std::size_t at = bad.find(from);
    REQUIRE(at != std::string::npos);
    bad.replace(at, from.size(), to);
    try {
      (void)deform::parse_rig_json(bad, skeleton, model.mesh.point_count(), "bad.rig.json");
      FAIL("accepted: " << expected);
    } catch (const deform::Error& e) {
      CHECK(std::string(e.what()).find(expected) != std::string::npos);
    }
  };
  refuses("\"gaussian\"", "\"cubic\"", "kernel");
  refuses("\"name\": \"elbow_in\"", "\"name\": \"elbow_in\", \"extra\": 1", "extra");
  refuses("\"bones\": [", "\"bones\": [\"no_such_bone\", ", "no_such_bone");
}

TEST_CASE("with_driven_weights: a clip's driven morph weights keyed at a rate, as update() gives them at each key") {
  deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  const std::int32_t forearm = skeleton.find("forearm_l");
  deform::Rig rig;
  deform::CorrectiveSpec group;
  group.name = "elbow";
  group.bones = {forearm};
  group.shapes.push_back({"pad", {{100.0f, 0.0f, 0.0f}}, {1, 5}, {{0.0f, 0.0f, 0.01f}, {0.0f, 0.01f, 0.0f}}});
  rig.correctives.push_back(group);
  model.morph_targets.push_back({"blink", "", 0.0f, {7}, {{0.0f, 0.001f, 0.0f}}, {}});  // the model's own target
  const deform::Character c(model, rig);
  REQUIRE(c.pose_driver_count() == 1);
  REQUIRE(c.pose_driver_targets(0).size() == 1);
  CHECK(c.pose_driver_targets(0)[0] == 1);  // after the model's own target
  // A clip bending the elbow from 0 to 140 degrees over 1.05 s, with a channel of its own for each target.
  deform::Animation clip;
  clip.name = "bend";
  clip.duration = 1.05f;
  deform::Channel bend;
  bend.bone = forearm;
  for (float t : {0.0f, 0.5f, 1.05f}) {
    bend.rotation.times.push_back(t);
    bend.rotation.values.push_back(deform::quat_from_euler(glm::vec3(140.0f * t / 1.05f, 0.0f, 0.0f)));
  }
  clip.channels.push_back(bend);
  for (std::int32_t target : {0, 1}) {
    deform::MorphChannel own;
    own.target = target;
    own.weight.times = {0.0f};
    own.weight.values = {0.5f};
    clip.morph_channels.push_back(own);
  }
  const deform::Animation baked = deform::with_driven_weights(c, clip, 10.0f);
  CHECK(baked.channels.size() == 1);
  REQUIRE(baked.morph_channels.size() == 2);
  CHECK(baked.morph_channels[0].target == 0);  // the model's own target keeps the clip's channel
  CHECK(baked.morph_channels[0].weight.values == std::vector<float>{0.5f});
  const deform::MorphChannel& driven = baked.morph_channels[1];  // the driven one replaced
  CHECK(driven.target == 1);
  CHECK(driven.weight.interpolation == deform::Interpolation::linear);
  REQUIRE(driven.weight.times.size() == 12);  // 0, 0.1, ..., 1.0, and the duration
  CHECK(driven.weight.times[10] == doctest::Approx(1.0f));
  CHECK(driven.weight.times[11] == 1.05f);
  // Each key is what a character holding the clip's pose there drives, to the bit.
  deform::Character check = c.instance();
  float highest = 0.0f;
  for (std::size_t k = 0; k < driven.weight.times.size(); ++k) {
    deform::Pose pose = skeleton.bind_pose();
    deform::SamplingJob sample{&clip, driven.weight.times[k], pose.rotations, pose.translations};
    if (k + 1 < driven.weight.times.size()) REQUIRE(sample.run());  // the looping clip wraps its end to 0
    else pose.rotations[std::size_t(forearm)] = bend.rotation.values.back();
    REQUIRE(check.set_pose(pose));
    REQUIRE(check.update(0.0f));
    CHECK(driven.weight.values[k] == check.morph_weights()[1]);
    highest = std::max(highest, driven.weight.values[k]);
  }
  CHECK(driven.weight.values.front() == doctest::Approx(0.0f).scale(1).epsilon(1e-4));
  CHECK(highest > 0.9f);
  // No driver: the clip as it was. Bad rates and clips are refused.
  const deform::Character plain(model);
  CHECK(deform::with_driven_weights(plain, clip, 10.0f).morph_channels.size() == 2);
  CHECK_THROWS_AS(deform::with_driven_weights(c, clip, 0.0f), deform::Error);
  CHECK_THROWS_AS(deform::with_driven_weights(c, clip, std::numeric_limits<float>::infinity()), deform::Error);
  deform::Animation broken = clip;
  broken.channels[0].bone = 999;
  CHECK_THROWS_AS(deform::with_driven_weights(c, broken, 10.0f), deform::Error);
}

}  // namespace
