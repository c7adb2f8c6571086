// Animation clips: sampling at keys, linear / slerp / step / cubic spline between them, looping, validation.
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <span>
#include <string>
#include <vector>

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

namespace {

// A clip of `channels` channels on bones 0.., each track with 0 to 40 keys at random gaps, of a random interpolation
// (mostly linear), rotations of any angle and either sign; some tracks empty.
Animation random_clip(std::mt19937& random, std::size_t channels, bool loop) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), gap(0.005f, 0.2f);
  std::uniform_int_distribution<int> keys(0, 40), kind(0, 5);
  Animation clip;
  clip.name = "random";
  clip.loop = loop;
  for (std::size_t c = 0; c < channels; ++c) {
    Channel channel;
    channel.bone = static_cast<std::int32_t>(c);
    const int k = kind(random);
    const auto interpolation = k < 4 ? Interpolation::linear : static_cast<Interpolation>(k == 4 ? 0 : 2);
    channel.translation.interpolation = channel.rotation.interpolation = interpolation;
    for (Track<glm::vec3>* track : {&channel.translation}) {
      float t = gap(random) - 0.1f;
      for (int n = keys(random); n > 0; --n) {
        track->times.push_back(t);
        track->values.push_back({unit(random), unit(random), unit(random)});
        if (interpolation == Interpolation::cubic_spline) {
          track->in_tangents.push_back({unit(random), unit(random), unit(random)});
          track->out_tangents.push_back({unit(random), unit(random), unit(random)});
        }
        t += gap(random);
      }
      clip.duration = std::max(clip.duration, t);
    }
    float t = gap(random) - 0.1f;
    for (int n = keys(random); n > 0; --n) {
      channel.rotation.times.push_back(t);
      channel.rotation.values.push_back(
          glm::normalize(glm::quat{unit(random), unit(random), unit(random), unit(random)}));
      if (interpolation == Interpolation::cubic_spline) {
        channel.rotation.in_tangents.push_back({unit(random), unit(random), unit(random), unit(random)});
        channel.rotation.out_tangents.push_back({unit(random), unit(random), unit(random), unit(random)});
      }
      t += gap(random);
    }
    clip.duration = std::max(clip.duration, t);
    clip.channels.push_back(std::move(channel));
  }
  return clip;
}

bool same_bits(const deform::Pose& a, const deform::Pose& b) {
  return std::memcmp(a.rotations.data(), b.rotations.data(), a.rotations.size() * sizeof(glm::quat)) == 0 &&
         std::memcmp(a.translations.data(), b.translations.data(), a.translations.size() * sizeof(glm::vec3)) == 0;
}

}  // namespace

TEST_CASE("a cursor gives the search's result bit for bit: forward, backward, jumps, loops, any starting values") {
  std::mt19937 random(36);
  std::uniform_real_distribution<float> step(0.0f, 1.0f / 30.0f);
  std::size_t samples = 0, moved = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t channels = 1 + static_cast<std::size_t>(trial % 40);
    const Animation clip = random_clip(random, channels, trial % 3 != 0);
    REQUIRE_NOTHROW(clip.require_valid(channels));
    deform::Pose plain = identity_pose(channels), cursored = identity_pose(channels);
    std::vector<std::uint32_t> cursor(2 * channels);
    // Start from zeros, from the largest values or from noise: every start is safe.
    for (std::uint32_t& c : cursor) c = trial % 3 == 0 ? 0u : (trial % 3 == 1 ? 0xffffffffu : random() % 64u);
    deform::SamplingJob with{&clip, 0.0f, cursored.rotations, cursored.translations, cursor};
    deform::SamplingJob without{&clip, 0.0f, plain.rotations, plain.translations};
    REQUIRE(with.cursor_size() == cursor.size());
    REQUIRE(with.validate());
    float t = -0.5f;
    for (int frame = 0; frame < 400; ++frame) {
      // Mostly forward by under a frame; sometimes backward, a jump anywhere (several loops included), or still.
      const int move = static_cast<int>(random() % 20);
      if (move == 0) t -= 4.0f * step(random);
      else if (move == 1) t = (std::uniform_real_distribution<float>(-3.0f, 3.0f)(random)) * (clip.duration + 0.1f);
      else if (move != 2) t += step(random);
      with.time = without.time = t;
      const std::vector<std::uint32_t> before = cursor;
      REQUIRE(with.run());
      REQUIRE(without.run());
      REQUIRE(same_bits(cursored, plain));
      moved += before != cursor;
      ++samples;
    }
  }
  CHECK(samples == 24000);
  CHECK(moved > 1000);  // the cursor is written back, not only read
}

TEST_CASE("a cursor holds each track's segment; a cursor of the wrong size is refused, nothing written") {
  // Keys at 0, 1, 2, 3: at 1.5 the rotation's segment is 1, the translation (keys at 0, 2) is in segment 0.
  Animation clip;
  clip.duration = 3.0f;
  Channel channel;
  channel.bone = 0;
  channel.translation = {Interpolation::linear, {0.0f, 2.0f}, {glm::vec3(0.0f), glm::vec3(2.0f)}, {}, {}};
  channel.rotation = {
      Interpolation::linear,
      {0.0f, 1.0f, 2.0f, 3.0f},
      {axis_angle(0, {0, 0, 1}), axis_angle(30, {0, 0, 1}), axis_angle(60, {0, 0, 1}), axis_angle(90, {0, 0, 1})},
      {},
      {}};
  clip.channels.push_back(channel);
  deform::Pose pose = identity_pose(1);
  std::vector<std::uint32_t> cursor{7, 7};
  deform::SamplingJob job{&clip, 1.5f, pose.rotations, pose.translations, cursor};
  REQUIRE(job.run());
  CHECK(cursor == std::vector<std::uint32_t>{0, 1});
  CHECK(near(pose.rotations[0], axis_angle(45, {0, 0, 1})));
  job.time = 2.5f;
  REQUIRE(job.run());
  CHECK(cursor == std::vector<std::uint32_t>{1, 2});
  job.time = 0.5f;  // backwards
  REQUIRE(job.run());
  CHECK(cursor == std::vector<std::uint32_t>{0, 0});

  std::vector<std::uint32_t> short_cursor(1), long_cursor(3);
  const deform::Pose before = pose;
  for (std::span<std::uint32_t> bad : {std::span<std::uint32_t>(short_cursor), std::span<std::uint32_t>(long_cursor)}) {
    job.cursor = bad;
    job.time = 1.25f;
    const deform::Status validated = job.validate(), ran = job.run();
    CHECK_FALSE(validated);
    CHECK(std::string(ran.reason()) == "cursor is neither empty nor two entries per channel");
    CHECK(same_bits(pose, before));
  }
}

TEST_CASE("linear rotations: within 1e-6 of the exact slerp, angles near 0 and near 180° included") {
  // The reference: the shortest-path slerp of the same float keys in double precision. Where the keys are half a turn
  // apart (dot product 0) both arcs are equally short; the reference takes the side the float dot product picks.
  auto float_dot = [](glm::quat a, glm::quat b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; };
  auto exact = [&](glm::quat a, glm::quat b, float u) {
    glm::dquat x(a), y(b);
    x = glm::normalize(x);
    y = glm::normalize(y);
    if (float_dot(a, b) < 0.0f) y = -y;
    const double theta = std::acos(std::clamp(glm::dot(x, y), -1.0, 1.0));
    if (theta < 1e-12) return glm::normalize(x * (1.0 - u) + y * double(u));
    return glm::normalize(x * (std::sin((1.0 - u) * theta) / std::sin(theta)) +
                          y * (std::sin(double(u) * theta) / std::sin(theta)));
  };
  std::mt19937 random(180);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), fraction(0.0f, 1.0f);
  double worst = 0.0, worst_glm = 0.0;
  int near_zero = 0, near_half_turn = 0;
  for (int i = 0; i < 200000; ++i) {
    const glm::quat a = glm::normalize(glm::quat{unit(random), unit(random), unit(random), unit(random)});
    glm::quat b;
    const int kind = i % 4;
    if (kind == 0) {
      b = glm::normalize(glm::quat{unit(random), unit(random), unit(random), unit(random)});
    } else {
      // Rotations apart by an angle near 0 (down to 1e-7 rad) or near 180° (the keys' dot product near 0),
      // either sign.
      const float small = std::pow(10.0f, -7.0f * fraction(random));
      const float angle = kind == 1 ? small : glm::radians(180.0f) - small;
      b = a * glm::angleAxis(angle, glm::normalize(glm::vec3{unit(random), unit(random), unit(random)}));
      if (kind == 3) b = -b;
      (kind == 1 ? near_zero : near_half_turn)++;
    }
    const float u = i % 50 == 0 ? float(i % 100 == 0) : fraction(random);
    const Track<glm::quat> track{Interpolation::linear, {0.0f, 1.0f}, {a, b}, {}, {}};
    // At u = 1 the track holds its last key, b itself, which is -b' when the arc went to -b: one rotation.
    glm::quat got = deform::sample_track(track, u, glm::quat(1, 0, 0, 0));
    if (u == 1.0f && float_dot(a, b) < 0.0f) got = -got;
    const glm::dquat want = exact(a, b, u);
    // glm decides the side by its own dot product: compared where the two cannot disagree.
    const glm::quat plain_glm = glm::normalize(glm::slerp(a, b, u));
    for (int k = 0; k < 4; ++k) {
      worst = std::max(worst, std::abs(double(got[k]) - want[k]));
      if (std::abs(float_dot(a, b)) > 1e-5f)
        worst_glm = std::max(worst_glm, std::abs(double(got[k]) - double(plain_glm[k])));
    }
  }
  CHECK(near_zero == 50000);
  CHECK(near_half_turn == 100000);
  MESSAGE("largest difference per component: " << worst << " from the exact slerp, " << worst_glm << " from glm's");
  CHECK(worst <= 1e-6);
  CHECK(worst_glm <= 2e-6);
}

TEST_CASE("SamplingJob's blocks of slerps give sample_track's bits, every interpolation, beyond one block") {
  std::mt19937 random(37);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t channels = 10 + static_cast<std::size_t>(trial) * 3;  // 10 to 67: several blocks of 16
    const Animation clip = random_clip(random, channels, true);
    for (int frame = 0; frame < 50; ++frame) {
      const float t = std::uniform_real_distribution<float>(-1.0f, clip.duration + 1.0f)(random);
      deform::Pose pose = identity_pose(channels), reference = identity_pose(channels);
      deform::SamplingJob job{&clip, t, pose.rotations, pose.translations};
      REQUIRE(job.run());
      const float local = clip.local_time(t);
      for (std::size_t c = 0; c < channels; ++c) {
        reference.translations[c] =
            deform::sample_track(clip.channels[c].translation, local, reference.translations[c]);
        reference.rotations[c] = deform::sample_track(clip.channels[c].rotation, local, reference.rotations[c]);
      }
      REQUIRE(same_bits(pose, reference));
    }
  }
}
