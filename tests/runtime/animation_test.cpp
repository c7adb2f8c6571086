// Animation clips: sampling at keys, linear / slerp / step / cubic spline between them, looping, validation.
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <span>
#include <string>

using deform::Animation;
using deform::Channel;
using deform::Interpolation;
using deform::Track;

namespace {

glm::quat axis_angle(float degrees, glm::vec3 axis) {
  return glm::angleAxis(glm::radians(degrees), glm::normalize(axis));
}

bool near(glm::vec3 a, glm::vec3 b, float tolerance = 1e-5f) { return glm::length(a - b) <= tolerance; }
// Same rotation (q and -q are one rotation).
bool near(glm::quat a, glm::quat b, float tolerance = 1e-5f) {
  return std::min(glm::length(glm::vec4(a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w)),
                  glm::length(glm::vec4(a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w))) <= tolerance;
}

deform::Pose identity_pose(std::size_t bones) {
  return {std::vector<glm::quat>(bones, glm::quat(1, 0, 0, 0)), std::vector<glm::vec3>(bones, glm::vec3(0.0f))};
}

// The clip at `seconds` into `pose`, by the sampling job.
deform::Status sample(const Animation& clip, float seconds, deform::Pose& pose) {
  deform::SamplingJob job;
  job.animation = &clip;
  job.time = seconds;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  return job.run();
}

// A two-key clip on bone 1: translation (0,0,0) -> (2,4,-6), rotation 0° -> 90° about Z, over two seconds.
Animation two_key_clip(Interpolation interpolation) {
  Animation clip;
  clip.name = "move";
  clip.duration = 2.0f;
  Channel channel;
  channel.bone = 1;
  channel.translation = {interpolation, {0.0f, 2.0f}, {glm::vec3(0.0f), glm::vec3(2, 4, -6)}, {}, {}};
  channel.rotation = {interpolation, {0.0f, 2.0f}, {glm::quat(1, 0, 0, 0), axis_angle(90, {0, 0, 1})}, {}, {}};
  clip.channels.push_back(channel);
  return clip;
}

}  // namespace

TEST_CASE("sampling at key times gives the keys, for random tracks of every interpolation") {
  std::mt19937 random(8);
  std::uniform_real_distribution<float> value(-10.0f, 10.0f), gap(0.01f, 1.0f);
  for (int trial = 0; trial < 300; ++trial) {
    const auto interpolation = static_cast<Interpolation>(trial % 3);
    Track<glm::vec3> translation{interpolation, {}, {}, {}, {}};
    Track<glm::quat> rotation{interpolation, {}, {}, {}, {}};
    float t = value(random);
    const int keys = 1 + trial % 9;
    for (int k = 0; k < keys; ++k) {
      t += gap(random);
      translation.times.push_back(t);
      rotation.times.push_back(t);
      translation.values.push_back({value(random), value(random), value(random)});
      rotation.values.push_back(glm::normalize(glm::quat{value(random), value(random), value(random), value(random)}));
      if (interpolation == Interpolation::cubic_spline) {
        translation.in_tangents.push_back({value(random), value(random), value(random)});
        translation.out_tangents.push_back({value(random), value(random), value(random)});
        rotation.in_tangents.push_back({value(random), value(random), value(random), value(random)});
        rotation.out_tangents.push_back({value(random), value(random), value(random), value(random)});
      }
    }
    for (std::size_t k = 0; k < translation.times.size(); ++k) {
      CHECK(near(deform::sample_track(translation, translation.times[k], glm::vec3(99.0f)), translation.values[k],
                 1e-4f));
      CHECK(near(deform::sample_track(rotation, rotation.times[k], glm::quat(1, 0, 0, 0)), rotation.values[k], 1e-5f));
    }
    // Outside the keys a track holds its end values.
    CHECK(near(deform::sample_track(translation, translation.times.front() - 5.0f, {}), translation.values.front()));
    CHECK(near(deform::sample_track(translation, translation.times.back() + 5.0f, {}), translation.values.back()));
  }
}

TEST_CASE("linear translation and slerp rotation between keys, hand-checked") {
  const Animation clip = two_key_clip(Interpolation::linear);
  deform::Pose pose = identity_pose(3);
  REQUIRE(sample(clip, 0.5f, pose));
  CHECK(near(pose.translations[1], {0.5f, 1.0f, -1.5f}));
  CHECK(near(pose.rotations[1], axis_angle(22.5f, {0, 0, 1})));
  REQUIRE(sample(clip, 1.0f, pose));
  CHECK(near(pose.rotations[1], axis_angle(45.0f, {0, 0, 1})));
  // Bones without a channel are untouched.
  CHECK(pose.translations[0] == glm::vec3(0.0f));
  CHECK(pose.translations[2] == glm::vec3(0.0f));

  // Slerp takes the shorter arc: -q is the same key, the midpoint is still 45°.
  Track<glm::quat> flipped{
      Interpolation::linear, {0.0f, 1.0f}, {glm::quat(1, 0, 0, 0), -axis_angle(90, {0, 0, 1})}, {}, {}};
  CHECK(near(deform::sample_track(flipped, 0.5f, {}), axis_angle(45.0f, {0, 0, 1})));
  // 170° -> -170° about X goes through 180°, not through 0°.
  Track<glm::quat> wrap{
      Interpolation::linear, {0.0f, 1.0f}, {axis_angle(170, {1, 0, 0}), axis_angle(-170, {1, 0, 0})}, {}, {}};
  CHECK(near(deform::sample_track(wrap, 0.5f, {}), axis_angle(180.0f, {1, 0, 0})));
}

TEST_CASE("step holds each key until the next") {
  Track<glm::vec3> track{Interpolation::step, {0.0f, 1.0f, 3.0f}, {glm::vec3(1), glm::vec3(2), glm::vec3(3)}, {}, {}};
  CHECK(deform::sample_track(track, 0.0f, {}) == glm::vec3(1));
  CHECK(deform::sample_track(track, 0.999f, {}) == glm::vec3(1));
  CHECK(deform::sample_track(track, 1.0f, {}) == glm::vec3(2));
  CHECK(deform::sample_track(track, 2.9f, {}) == glm::vec3(2));
  CHECK(deform::sample_track(track, 3.5f, {}) == glm::vec3(3));
  const Animation clip = two_key_clip(Interpolation::step);
  deform::Pose pose = identity_pose(2);
  REQUIRE(sample(clip, 1.9f, pose));
  CHECK(pose.translations[1] == glm::vec3(0.0f));
  CHECK(near(pose.rotations[1], glm::quat(1, 0, 0, 0)));
}

TEST_CASE("cubic spline follows the glTF Hermite form, hand-checked") {
  // p0 = 0, p1 = 1 over dt = 2; tangents per second, scaled by dt.
  Track<glm::vec3> flat{Interpolation::cubic_spline,
                        {0.0f, 2.0f},
                        {glm::vec3(0), glm::vec3(1)},
                        {glm::vec3(0), glm::vec3(0)},
                        {glm::vec3(0), glm::vec3(0)}};
  CHECK(near(deform::sample_track(flat, 0.5f, {}), glm::vec3(0.15625f)));  // 3u² - 2u³ at u = 1/4
  CHECK(near(deform::sample_track(flat, 1.0f, {}), glm::vec3(0.5f)));
  Track<glm::vec3> sloped = flat;
  sloped.out_tangents[0] = glm::vec3(1.0f);  // m0 = 1 per second
  // (u³ - 2u² + u)·dt·m0 + (-2u³ + 3u²)·p1 at u = 1/2: 0.125·2 + 0.5.
  CHECK(near(deform::sample_track(sloped, 1.0f, {}), glm::vec3(0.75f)));
  // The in tangent of the *first* key and the out tangent of the last do not matter inside the track.
  sloped.in_tangents[0] = glm::vec3(50.0f);
  sloped.out_tangents[1] = glm::vec3(-50.0f);
  CHECK(near(deform::sample_track(sloped, 1.0f, {}), glm::vec3(0.75f)));
  // Rotations are normalised.
  Track<glm::quat> rotation{Interpolation::cubic_spline,
                            {0.0f, 1.0f},
                            {glm::quat(1, 0, 0, 0), axis_angle(90, {0, 1, 0})},
                            {glm::quat(0, 0, 0, 0), glm::quat(0, 0, 0, 0)},
                            {glm::quat(0, 0, 0, 0), glm::quat(0, 0, 0, 0)}};
  const glm::quat middle = deform::sample_track(rotation, 0.5f, {});
  CHECK(std::fabs(glm::length(middle) - 1.0f) < 1e-6f);
  CHECK(near(middle, axis_angle(45.0f, {0, 1, 0})));  // zero tangents: the normalised chord midpoint = slerp's
}

TEST_CASE("looping wraps time, a one-shot clip clamps") {
  Animation clip = two_key_clip(Interpolation::linear);
  deform::Pose a = identity_pose(2), b = identity_pose(2);
  for (const float t : {0.25f, 0.5f, 1.75f}) {
    REQUIRE(sample(clip, t, a));
    for (const float shift : {2.0f, 4.0f, -2.0f, 20.0f}) {
      REQUIRE(sample(clip, t + shift, b));
      CHECK(near(a.translations[1], b.translations[1], 1e-4f));
      CHECK(near(a.rotations[1], b.rotations[1], 1e-4f));
    }
  }
  CHECK(clip.local_time(2.0f) == 0.0f);
  CHECK(clip.local_time(-0.5f) == doctest::Approx(1.5f));
  clip.loop = false;
  REQUIRE(sample(clip, 7.0f, a));
  CHECK(near(a.translations[1], {2, 4, -6}));
  REQUIRE(sample(clip, -1.0f, a));
  CHECK(near(a.translations[1], {0, 0, 0}));
  Animation still;  // zero length: always time 0
  CHECK(still.local_time(3.0f) == 0.0f);
}

TEST_CASE("SamplingJob refuses a pose too small, a non-finite time or malformed tracks, writing nothing") {
  const Animation clip = two_key_clip(Interpolation::linear);
  deform::Pose pose = identity_pose(1);  // bone 1 is out of range
  deform::SamplingJob job;
  job.animation = &clip;
  job.time = 0.5f;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  CHECK(std::string(job.validate().reason()) == "channel bone out of the pose");
  CHECK(std::string(job.run().reason()) == "channel bone out of the pose");
  CHECK(pose.translations[0] == glm::vec3(0.0f));
  deform::Pose big = identity_pose(2);
  job.rotations = big.rotations;
  job.translations = big.translations;
  CHECK(job.validate());
  for (const float bad : {NAN, INFINITY}) {
    job.time = bad;
    CHECK(std::string(job.validate().reason()) == "time is not finite");
    CHECK(std::string(job.run().reason()) == "time is not finite");
  }
  job.time = 0.5f;
  job.translations = std::span<glm::vec3>(big.translations).first(1);
  CHECK_FALSE(job.run());
  CHECK(big.translations[1] == glm::vec3(0.0f));
  CHECK(big.rotations[1] == glm::quat(1, 0, 0, 0));
  job.translations = big.translations;
  job.animation = nullptr;
  CHECK(std::string(job.run().reason()) == "no animation");
  CHECK(job.count() == 0);
  // Track sizes are validate()'s to check (Animation::validate names them at bind time).
  Animation broken = clip;
  broken.channels[0].rotation.values.pop_back();
  job.animation = &broken;
  CHECK(std::string(job.validate().reason()) == "track values or tangents do not match its times");
  broken = clip;
  broken.channels[0].translation.interpolation = Interpolation::cubic_spline;
  CHECK_FALSE(job.validate());
}

TEST_CASE("SamplingJob: ranges of channels give the whole run") {
  Animation clip = two_key_clip(Interpolation::linear);
  Channel other = clip.channels[0];
  other.bone = 3;
  other.translation.values[1] = glm::vec3(-1, 0, 5);
  clip.channels.push_back(other);
  other.bone = 0;
  clip.channels.push_back(other);
  REQUIRE_NOTHROW(clip.require_valid(4));
  deform::Pose whole = identity_pose(4), split = identity_pose(4);
  deform::SamplingJob job;
  job.animation = &clip;
  job.time = 1.3f;
  job.rotations = whole.rotations;
  job.translations = whole.translations;
  CHECK(job.count() == 3);
  REQUIRE(job.run());
  job.rotations = split.rotations;
  job.translations = split.translations;
  REQUIRE(job.run(2, 3));
  CHECK(split.translations[0] == whole.translations[0]);
  CHECK(split.translations[1] == glm::vec3(0.0f));
  REQUIRE(job.run(0, 2));
  CHECK(split.translations == whole.translations);
  CHECK(split.rotations == whole.rotations);
  CHECK_FALSE(job.run(2, 1));
  CHECK_FALSE(job.run(0, 4));
}

TEST_CASE("validate rejects malformed clips with the clip and the bone named") {
  const Animation good = two_key_clip(Interpolation::linear);
  CHECK_NOTHROW(good.require_valid(2));
  CHECK_THROWS_AS(good.require_valid(1), deform::Error);  // bone 1 out of range

  auto expect = [](const Animation& clip, const char* words) {
    try {
      clip.require_valid(4, "clip.test");
      FAIL("no error for: " << words);
    } catch (const deform::Error& e) {
      CHECK(std::string(e.what()).find(words) != std::string::npos);
      CHECK(std::string(e.what()).find("clip 'move': bone 1") != std::string::npos);
    }
  };
  Animation clip = good;
  clip.channels[0].translation.times = {1.0f, 1.0f};
  expect(clip, "times not increasing");
  clip = good;
  clip.channels[0].rotation.values.pop_back();
  expect(clip, "differ in count");
  clip = good;
  clip.channels[0].translation.values[1].x = NAN;
  expect(clip, "not finite");
  clip = good;
  clip.channels[0].translation.interpolation = Interpolation::cubic_spline;
  expect(clip, "tangent");
  clip = good;
  clip.channels.push_back(clip.channels[0]);
  expect(clip, "two channels");
  clip = good;
  clip.duration = -1.0f;
  CHECK_THROWS_AS(clip.require_valid(4), deform::Error);
}

TEST_CASE("find_clip looks clips up by name") {
  std::vector<Animation> clips(2);
  clips[0].name = "walk";
  clips[1].name = "run";
  CHECK(deform::find_clip(clips, "run") == 1);
  CHECK(deform::find_clip(clips, "jump") == -1);
}
