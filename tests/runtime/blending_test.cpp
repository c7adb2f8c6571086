// Blending, masks, additive layers and root motion (blending.hpp): a plain double-precision reference of the blend,
// seeded random properties over thousands of cases, and the jobs' refusals.
#include "deform/runtime/blending.hpp"
#include "deform/runtime/parallel.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <vector>

#include "deform/runtime/animation.hpp"
#include "deform/runtime/skeleton.hpp"

using deform::Animation;
using deform::BlendingJob;
using deform::BlendLayer;
using deform::Channel;
using deform::Interpolation;
using deform::Pose;
using deform::RootMotion;
using deform::RootMotionJob;

namespace {

constexpr double pi = 3.14159265358979323846;

// Same rotation (q and -q are one rotation).
float rotation_distance(glm::quat a, glm::quat b) {
  return std::min(glm::length(glm::vec4(a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w)),
                  glm::length(glm::vec4(a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w)));
}

struct Random {
  std::mt19937 engine;
  explicit Random(unsigned seed) : engine(seed) {}
  float uniform(float a, float b) { return std::uniform_real_distribution<float>(a, b)(engine); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(engine); }
  glm::vec3 axis() {
    for (;;) {
      const glm::vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const float l = glm::length(v);
      if (l > 0.1f && l <= 1.0f) return v / l;
    }
  }
  // A rotation of up to `max_degrees` about a random axis, with a random sign (q and -q alike).
  glm::quat rotation(float max_degrees = 180.0f) {
    const glm::quat q = glm::angleAxis(glm::radians(uniform(0.0f, max_degrees)), axis());
    return integer(0, 1) ? q : -q;
  }
  glm::vec3 vec(float r = 2.0f) { return {uniform(-r, r), uniform(-r, r), uniform(-r, r)}; }
  Pose pose(std::size_t bones) {
    Pose p;
    for (std::size_t b = 0; b < bones; ++b) {
      p.rotations.push_back(rotation());
      p.translations.push_back(vec());
    }
    return p;
  }
};

BlendLayer layer_of(const Pose& pose, float weight, std::span<const float> mask = {}) {
  return {pose.rotations, pose.translations, weight, mask};
}

// --- the plain reference: the documented rule in double precision ---
struct DQuat {
  double w = 0, x = 0, y = 0, z = 0;
};
DQuat to_d(glm::quat q) { return {q.w, q.x, q.y, q.z}; }
DQuat mul(DQuat a, DQuat b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
DQuat normalized(DQuat q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
DQuat dpower(DQuat q, double w) {
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  const double s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  if (s == 0) return {1, 0, 0, 0};
  const double half = std::atan2(s, q.w) * w, k = std::sin(half) / s;
  return {std::cos(half), k * q.x, k * q.y, k * q.z};
}

// Returns false where a hemisphere choice is too close to call (the running sum nearly perpendicular to a layer's
// rotation in 4D): float and double may then pick different signs, both valid.
bool reference_blend(const std::vector<BlendLayer>& layers, const std::vector<BlendLayer>& additive, const Pose& rest,
                     float threshold, std::size_t b, glm::quat& out_q, glm::vec3& out_t) {
  DQuat sum;
  double t[3] = {0, 0, 0}, total = 0;
  bool clear = true;
  auto add = [&](glm::quat q, glm::vec3 p, double w) {
    const DQuat d = to_d(q);
    const double dot = sum.w * d.w + sum.x * d.x + sum.y * d.y + sum.z * d.z;
    const double norm = std::sqrt(sum.w * sum.w + sum.x * sum.x + sum.y * sum.y + sum.z * sum.z);
    if (norm > 0 && std::abs(dot) < 1e-3 * norm) clear = false;
    const double s = dot < 0 ? -w : w;
    sum = {sum.w + s * d.w, sum.x + s * d.x, sum.y + s * d.y, sum.z + s * d.z};
    for (int i = 0; i < 3; ++i) t[i] += w * p[i];
    total += w;
  };
  for (const BlendLayer& l : layers) {
    const double w = double(l.weight) * (l.bone_weights.empty() ? 1.0 : l.bone_weights[b]);
    if (w > 0) add(l.rotations[b], l.translations[b], w);
  }
  if (total < threshold) add(rest.rotations[b], rest.translations[b], threshold - total);
  DQuat q = normalized(sum);
  for (int i = 0; i < 3; ++i) t[i] /= total;
  for (const BlendLayer& l : additive) {
    const double w = double(l.weight) * (l.bone_weights.empty() ? 1.0 : l.bone_weights[b]);
    if (!(w > 0)) continue;
    q = normalized(mul(q, dpower(to_d(l.rotations[b]), w)));
    for (int i = 0; i < 3; ++i) t[i] += w * l.translations[b][i];
  }
  out_q = glm::quat(float(q.w), float(q.x), float(q.y), float(q.z));
  out_t = glm::vec3(float(t[0]), float(t[1]), float(t[2]));
  return clear;
}

Pose blend(const std::vector<BlendLayer>& layers, const std::vector<BlendLayer>& additive, const Pose& rest,
           float threshold = 0.1f) {
  Pose out{std::vector<glm::quat>(rest.rotations.size()), std::vector<glm::vec3>(rest.rotations.size())};
  BlendingJob job;
  job.layers = layers;
  job.additive_layers = additive;
  job.threshold = threshold;
  job.rest_rotations = rest.rotations;
  job.rest_translations = rest.translations;
  job.rotations = out.rotations;
  job.translations = out.translations;
  REQUIRE(job.validate().ok());
  REQUIRE(job.run().ok());
  return out;
}

// A random clip on `bones` bones: each bone a channel (or none), random keys, interpolations, 1 to 6 keys.
Animation random_clip(Random& r, std::size_t bones, float duration) {
  Animation clip;
  clip.name = "random";
  clip.duration = duration;
  for (std::size_t b = 0; b < bones; ++b) {
    if (r.integer(0, 4) == 0) continue;
    Channel c;
    c.bone = static_cast<std::int32_t>(b);
    const auto interpolation = static_cast<Interpolation>(r.integer(0, 2));
    c.rotation.interpolation = c.translation.interpolation = interpolation;
    const int keys = r.integer(1, 6);
    for (int k = 0; k < keys; ++k) {
      const float t = keys == 1 ? 0.0f : duration * float(k) / float(keys - 1);
      c.rotation.times.push_back(t);
      c.translation.times.push_back(t);
      c.rotation.values.push_back(r.rotation());
      c.translation.values.push_back(r.vec());
      if (interpolation == Interpolation::cubic_spline) {
        c.rotation.in_tangents.push_back(
            glm::quat(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1)));
        c.rotation.out_tangents.push_back(
            glm::quat(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1)));
        c.translation.in_tangents.push_back(r.vec());
        c.translation.out_tangents.push_back(r.vec());
      }
    }
    clip.channels.push_back(c);
  }
  clip.require_valid(bones);
  return clip;
}

void sample(const Animation& clip, float t, Pose& pose) {
  deform::SamplingJob job;
  job.animation = &clip;
  job.time = t;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  REQUIRE(job.run().ok());
}

Pose identity_pose(std::size_t bones) {
  return {std::vector<glm::quat>(bones, glm::quat(1, 0, 0, 0)), std::vector<glm::vec3>(bones, glm::vec3(0.0f))};
}

}  // namespace

TEST_CASE("blending matches the double-precision reference over random layers, masks and additive layers") {
  Random r(1301);
  float worst_q = 0, worst_t = 0;
  int compared = 0, skipped = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 12));
    const Pose rest = r.pose(bones);
    std::vector<Pose> poses;
    std::vector<std::vector<float>> masks;
    const int n = r.integer(0, 4), a = r.integer(0, 2);
    for (int i = 0; i < n + a; ++i) {
      poses.push_back(r.pose(bones));
      std::vector<float> mask;
      if (r.integer(0, 1))
        for (std::size_t b = 0; b < bones; ++b) mask.push_back(r.integer(0, 3) == 0 ? 0.0f : r.uniform(0.0f, 1.0f));
      masks.push_back(mask);
    }
    std::vector<BlendLayer> layers, additive;
    for (int i = 0; i < n + a; ++i) {
      const float w = r.integer(0, 5) == 0 ? 0.0f : r.uniform(0.0f, i < n ? 3.0f : 1.5f);
      (i < n ? layers : additive).push_back(layer_of(poses[std::size_t(i)], w, masks[std::size_t(i)]));
    }
    const float threshold = r.uniform(0.01f, 1.0f);
    const Pose out = blend(layers, additive, rest, threshold);
    for (std::size_t b = 0; b < bones; ++b) {
      glm::quat q;
      glm::vec3 t;
      ++compared;
      if (!reference_blend(layers, additive, rest, threshold, b, q, t)) {
        ++skipped;
        continue;
      }
      worst_q = std::max(worst_q, rotation_distance(out.rotations[b], q));
      worst_t = std::max(worst_t, glm::length(out.translations[b] - t));
      CHECK(std::abs(glm::length(out.rotations[b]) - 1.0f) < 1e-5f);
    }
  }
  MESSAGE("worst rotation difference ", worst_q, ", translation ", worst_t, "; ", skipped, " of ", compared,
          " bones too close to call");
  CHECK(skipped * 100 < compared);
  CHECK(worst_t < 1e-5f);
  CHECK(worst_q < 1e-5f);
}

TEST_CASE("a single layer of weight 1 gives the sampled clip, at every bone") {
  Random r(7);
  for (int trial = 0; trial < 1000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 30));
    const Animation clip = random_clip(r, bones, r.uniform(0.1f, 3.0f));
    const Pose rest = r.pose(bones);
    Pose sampled = rest;
    sample(clip, r.uniform(-10.0f, 10.0f), sampled);
    const Pose out = blend({layer_of(sampled, 1.0f)}, {}, rest);
    for (std::size_t b = 0; b < bones; ++b) {
      CHECK(rotation_distance(out.rotations[b], sampled.rotations[b]) < 1e-6f);
      CHECK(glm::length(out.translations[b] - sampled.translations[b]) < 1e-6f);
    }
  }
}

TEST_CASE("weights scaled together give the same pose") {
  Random r(11);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 10));
    const Pose rest = r.pose(bones);
    const int n = r.integer(1, 4);
    std::vector<Pose> poses;
    std::vector<float> weights;
    for (int i = 0; i < n; ++i) {
      poses.push_back(r.pose(bones));
      weights.push_back(r.uniform(0.2f, 1.0f));
    }
    const float scale = r.uniform(0.5f, 20.0f);
    std::vector<BlendLayer> a, b;
    for (int i = 0; i < n; ++i) {
      a.push_back(layer_of(poses[std::size_t(i)], weights[std::size_t(i)]));
      b.push_back(layer_of(poses[std::size_t(i)], weights[std::size_t(i)] * scale));
    }
    const Pose pa = blend(a, {}, rest), pb = blend(b, {}, rest);
    for (std::size_t k = 0; k < bones; ++k) {
      CHECK(rotation_distance(pa.rotations[k], pb.rotations[k]) < 1e-5f);
      CHECK(glm::length(pa.translations[k] - pb.translations[k]) < 1e-5f);
    }
  }
}

TEST_CASE("a bone masked to 0 in one layer keeps the other layer; the mask splits a body in two") {
  Random r(12);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 20));
    const Pose rest = r.pose(bones), upper = r.pose(bones), lower = r.pose(bones);
    std::vector<float> upper_mask(bones), lower_mask(bones);
    for (std::size_t b = 0; b < bones; ++b) {
      upper_mask[b] = float(r.integer(0, 1));
      lower_mask[b] = 1.0f - upper_mask[b];
    }
    const float wu = r.uniform(0.1f, 2.0f), wl = r.uniform(0.1f, 2.0f);
    const Pose out = blend({layer_of(upper, wu, upper_mask), layer_of(lower, wl, lower_mask)}, {}, rest, 0.05f);
    for (std::size_t b = 0; b < bones; ++b) {
      const Pose& expected = upper_mask[b] > 0 ? upper : lower;
      CHECK(rotation_distance(out.rotations[b], expected.rotations[b]) < 1e-6f);
      CHECK(glm::length(out.translations[b] - expected.translations[b]) < 1e-5f);
    }
  }
  // set_subtree_weight: a bone and its descendants.
  std::vector<deform::Bone> chain(4);
  for (int i = 0; i < 4; ++i) {
    chain[std::size_t(i)].parent = i - 1;
    if (i < 3) chain[std::size_t(i)].children = {i + 1};
  }
  const deform::Skeleton skeleton(chain);
  std::vector<float> mask(4, 0.0f);
  deform::set_subtree_weight(skeleton, 2, 0.5f, mask);
  CHECK(mask == std::vector<float>{0.0f, 0.0f, 0.5f, 0.5f});
  CHECK_THROWS_AS(deform::set_subtree_weight(skeleton, 4, 1.0f, mask), deform::Error);
  std::vector<float> short_mask(3);
  CHECK_THROWS_AS(deform::set_subtree_weight(skeleton, 0, 1.0f, short_mask), deform::Error);
}

TEST_CASE("rest fallback: no weight gives the rest pose, a weak weight moves continuously towards it") {
  const Pose rest{{glm::quat(1, 0, 0, 0)}, {glm::vec3(0.0f)}};
  const Pose moved{{glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 0, 1))}, {glm::vec3(2, 0, 0)}};
  Pose out = blend({layer_of(moved, 0.0f)}, {}, rest);
  CHECK(rotation_distance(out.rotations[0], rest.rotations[0]) < 1e-7f);
  CHECK(glm::length(out.translations[0]) < 1e-7f);
  out = blend({layer_of(moved, 0.05f)}, {}, rest, 0.1f);  // half the threshold: half way
  CHECK(glm::length(out.translations[0] - glm::vec3(1, 0, 0)) < 1e-6f);
  CHECK(std::abs(glm::degrees(glm::angle(out.rotations[0])) - 45.0f) < 1e-3f);
  out = blend({}, {}, rest);  // no layers at all
  CHECK(glm::length(out.translations[0]) == 0.0f);
}

TEST_CASE("two layers 90° apart blend half way; opposite signs of one rotation do not cancel") {
  const glm::quat a = glm::angleAxis(glm::radians(0.0f), glm::vec3(0, 1, 0));
  const glm::quat b = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  const Pose rest{{a}, {glm::vec3(0.0f)}}, pa{{a}, {glm::vec3(0, 0, 0)}}, pb{{-b}, {glm::vec3(4, 0, 0)}};
  const Pose out = blend({layer_of(pa, 1.0f), layer_of(pb, 1.0f)}, {}, rest);
  CHECK(rotation_distance(out.rotations[0], glm::angleAxis(glm::radians(45.0f), glm::vec3(0, 1, 0))) < 1e-6f);
  CHECK(glm::length(out.translations[0] - glm::vec3(2, 0, 0)) < 1e-6f);
  // 3:1 weights: the nlerp, not the slerp (21.6°, not 22.5°): checked against the normalised sum and the angle.
  const Pose out2 = blend({layer_of(pa, 3.0f), layer_of(pb, 1.0f)}, {}, rest);
  const glm::quat expected = glm::normalize(glm::quat(3.0f * a.w + b.w, 0, 3.0f * a.y + b.y, 0));
  CHECK(rotation_distance(out2.rotations[0], expected) < 1e-6f);
  CHECK(std::abs(glm::degrees(glm::angle(out2.rotations[0])) - 21.598f) < 1e-2f);
}

TEST_CASE("additive: the delta of the reference is the identity; weight 1 restores the pose; w scales the angle") {
  Random r(21);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 12));
    const Pose base = r.pose(bones), reference = r.pose(bones), pose = r.pose(bones);
    Pose delta = identity_pose(bones);
    REQUIRE(deform::additive_delta(reference.rotations, reference.translations, reference.rotations,
                                   reference.translations, delta.rotations, delta.translations)
                .ok());
    const float w = r.uniform(0.0f, 2.0f);
    Pose out = blend({layer_of(base, 1.0f)}, {layer_of(delta, w)}, base);
    for (std::size_t b = 0; b < bones; ++b) {
      CHECK(rotation_distance(out.rotations[b], base.rotations[b]) < 1e-5f);
      CHECK(glm::length(out.translations[b] - base.translations[b]) < 1e-5f);
    }
    REQUIRE(deform::additive_delta(reference.rotations, reference.translations, pose.rotations, pose.translations,
                                   delta.rotations, delta.translations)
                .ok());
    out = blend({layer_of(reference, 1.0f)}, {layer_of(delta, 1.0f)}, base);
    for (std::size_t b = 0; b < bones; ++b) {
      CHECK(rotation_distance(out.rotations[b], pose.rotations[b]) < 1e-5f);
      CHECK(glm::length(out.translations[b] - pose.translations[b]) < 1e-5f);
    }
  }
  // Weight w of a 120° delta about X turns the base by w·120° (shorter arc, either sign of the delta).
  const Pose base{{glm::quat(1, 0, 0, 0)}, {glm::vec3(0.0f)}};
  const glm::quat turn = glm::angleAxis(glm::radians(120.0f), glm::vec3(1, 0, 0));
  for (const float w : {0.0f, 0.25f, 0.5f, 1.0f, 1.25f})
    for (const float sign : {1.0f, -1.0f}) {
      const Pose delta{{sign * turn}, {glm::vec3(1, 2, 3)}};
      const Pose out = blend({layer_of(base, 1.0f)}, {layer_of(delta, w)}, base);
      CHECK(rotation_distance(out.rotations[0], glm::angleAxis(glm::radians(120.0f * w), glm::vec3(1, 0, 0))) < 1e-5f);
      CHECK(glm::length(out.translations[0] - w * glm::vec3(1, 2, 3)) < 1e-6f);
    }
}

TEST_CASE("an additive clip samples to the delta of the clip from its first frame or a given pose") {
  Random r(22);
  for (int trial = 0; trial < 1000; ++trial) {
    const std::size_t bones = std::size_t(r.integer(1, 10));
    const Animation clip = random_clip(r, bones, r.uniform(0.2f, 2.0f));
    const bool first_frame = trial % 2 == 0;
    Pose reference = identity_pose(bones);
    if (first_frame) {
      sample(clip, 0.0f, reference);
    } else {
      reference = r.pose(bones);
    }
    const Animation additive =
        first_frame ? deform::make_additive_clip(clip) : deform::make_additive_clip(clip, reference);
    additive.require_valid(bones);
    const float t = r.uniform(0.0f, clip.duration);
    Pose sampled = identity_pose(bones), delta = identity_pose(bones), expected = identity_pose(bones);
    sample(clip, t, sampled);
    sample(additive, t, delta);
    REQUIRE(deform::additive_delta(reference.rotations, reference.translations, sampled.rotations, sampled.translations,
                                   expected.rotations, expected.translations)
                .ok());
    for (const Channel& c : clip.channels) {
      const auto b = std::size_t(c.bone);
      CHECK(rotation_distance(delta.rotations[b], expected.rotations[b]) < 2e-5f);
      CHECK(glm::length(delta.translations[b] - expected.translations[b]) < 1e-5f);
    }
    if (first_frame) {  // at time 0 the first-frame delta is the identity: the additive of the reference
      Pose at0 = identity_pose(bones);
      sample(additive, 0.0f, at0);
      for (std::size_t b = 0; b < bones; ++b) {
        CHECK(rotation_distance(at0.rotations[b], glm::quat(1, 0, 0, 0)) < 1e-6f);
        CHECK(glm::length(at0.translations[b]) < 1e-6f);
      }
    }
  }
  Animation clip;
  clip.name = "c";
  clip.channels.push_back(Channel{5, {}, {}, {}});
  CHECK_THROWS_AS(deform::make_additive_clip(clip, identity_pose(2)), deform::Error);
}

TEST_CASE("run(begin, end) over disjoint ranges equals run(); outputs may be a layer's input") {
  Random r(31);
  const std::size_t bones = 40;
  const Pose rest = r.pose(bones), a = r.pose(bones), b = r.pose(bones);
  std::vector<float> mask(bones);
  for (float& m : mask) m = r.uniform(0.0f, 1.0f);
  const std::vector<BlendLayer> layers{layer_of(a, 0.7f), layer_of(b, 0.4f, mask)};
  const Pose whole = blend(layers, {}, rest);
  Pose pieces = identity_pose(bones);
  BlendingJob job;
  job.layers = layers;
  job.rest_rotations = rest.rotations;
  job.rest_translations = rest.translations;
  job.rotations = pieces.rotations;
  job.translations = pieces.translations;
  for (std::size_t begin = 0; begin < bones; begin += 7) REQUIRE(job.run(begin, std::min(bones, begin + 7)).ok());
  CHECK(pieces.rotations == whole.rotations);
  CHECK(pieces.translations == whole.translations);
  CHECK(job.run(3, 41).reason() == std::string("range outside the job"));
  // run_parallel over two threads, in chunks of 16 bones: the same bits.
  Pose parallel = identity_pose(bones);
  job.rotations = parallel.rotations;
  job.translations = parallel.translations;
  deform::ThreadPool pool(2);
  REQUIRE(deform::run_parallel(job, pool, 16).ok());
  CHECK(parallel.rotations == whole.rotations);
  CHECK(parallel.translations == whole.translations);
  job.rotations = pieces.rotations;
  job.translations = pieces.translations;
  // In place: the output is layer a's arrays.
  Pose in_place = a;
  const std::vector<BlendLayer> aliased{layer_of(in_place, 0.7f), layer_of(b, 0.4f, mask)};
  job.layers = aliased;
  job.rotations = in_place.rotations;
  job.translations = in_place.translations;
  REQUIRE(job.run().ok());
  CHECK(in_place.rotations == whole.rotations);
  CHECK(in_place.translations == whole.translations);
}

TEST_CASE("BlendingJob refuses malformed calls, writing nothing") {
  Pose rest = identity_pose(3), a = identity_pose(3), out = identity_pose(3), small = identity_pose(2);
  out.translations[0] = glm::vec3(9.0f);
  std::vector<float> mask{1.0f, 1.0f}, bad_mask{1.0f, -1.0f, 1.0f};
  auto reason = [&](std::vector<BlendLayer> layers, float threshold = 0.1f, bool validate = false) {
    BlendingJob job;
    job.layers = layers;
    job.threshold = threshold;
    job.rest_rotations = rest.rotations;
    job.rest_translations = rest.translations;
    job.rotations = out.rotations;
    job.translations = out.translations;
    return std::string(validate ? job.validate().reason() : job.run().reason());
  };
  CHECK(reason({layer_of(small, 1.0f)}) == "layer pose size differs");
  CHECK(reason({layer_of(a, -1.0f)}) == "layer weight is not within [0, 1e6]");
  CHECK(reason({layer_of(a, NAN)}) == "layer weight is not within [0, 1e6]");
  CHECK(reason({layer_of(a, 2e6f)}) == "layer weight is not within [0, 1e6]");
  CHECK(reason({layer_of(a, 1.0f, mask)}) == "layer mask size differs");
  CHECK(reason({layer_of(a, 1.0f, bad_mask)}, 0.1f, true) == "layer mask weight is not within [0, 1e6]");
  CHECK(reason({layer_of(a, 1.0f)}, 0.0f) == "threshold is not within [1e-6, 1e6]");
  CHECK(reason({layer_of(a, 1.0f)}, 1e-30f) == "threshold is not within [1e-6, 1e6]");
  CHECK(reason({layer_of(a, 1.0f)}, INFINITY) == "threshold is not within [1e-6, 1e6]");
  CHECK(reason({layer_of(a, 1.0f)}, NAN) == "threshold is not within [1e-6, 1e6]");
  a.rotations[1].x = NAN;
  CHECK(reason({layer_of(a, 1.0f)}, 0.1f, true) == "layer pose is not finite");
  CHECK(out.translations[0] == glm::vec3(9.0f));
  BlendingJob job;
  job.rest_rotations = small.rotations;
  job.rest_translations = small.translations;
  job.rotations = out.rotations;
  job.translations = out.translations;
  CHECK(std::string(job.run().reason()) == "rest pose size differs");
}

// --- root motion ---
namespace {

// A looping root clip on bone 0: translation and rotation keys spread over `duration`.
Animation root_clip(Random& r, float duration, bool turning, Interpolation interpolation = Interpolation::linear) {
  Animation clip;
  clip.name = "root";
  clip.duration = duration;
  Channel c;
  c.bone = 0;
  c.translation.interpolation = c.rotation.interpolation = interpolation;
  const int keys = r.integer(2, 6);
  for (int k = 0; k < keys; ++k) {
    const float t = duration * float(k) / float(keys - 1);
    c.translation.times.push_back(t);
    c.rotation.times.push_back(t);
    c.translation.values.push_back(r.vec(3.0f));
    // Yaw relative to the first frame within ±80°, tilt (swing) up to 40°.
    const float yaw = turning ? glm::radians(r.uniform(-80.0f, 80.0f)) : 0.0f;
    c.rotation.values.push_back(
        glm::angleAxis(yaw, glm::vec3(0, 1, 0)) *
        glm::angleAxis(glm::radians(r.uniform(0.0f, 40.0f)),
                       glm::normalize(glm::vec3(r.uniform(-1, 1), 0.0f, r.uniform(-1, 1)) + glm::vec3(1e-3f, 0, 0))));
  }
  clip.channels.push_back(c);
  clip.require_valid(1);
  return clip;
}

RootMotion root_motion(const Animation& clip, float from, float to, glm::vec3 up = {0, 1, 0}) {
  RootMotion m;
  RootMotionJob job;
  job.animation = &clip;
  job.from = from;
  job.to = to;
  job.up = up;
  job.motion = &m;
  REQUIRE(job.run().ok());
  return m;
}

bool same_motion(const RootMotion& a, const RootMotion& b, float tolerance) {
  const double dy = std::remainder(double(a.yaw) - double(b.yaw), 2 * pi);
  return glm::length(a.translation - b.translation) <= tolerance && std::abs(dy) <= tolerance;
}

// The plain reference: the root's frame at unwrapped time t by explicit loop counting, in double precision.
struct Frame2 {
  double x = 0, z = 0, yaw = 0;  // up = +Y: a point (x, z) in the ground plane, yaw about +Y
};
Frame2 then(Frame2 a, Frame2 b) {  // a · b
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  // Rotation about +Y by θ maps (x, z) to (x cosθ + z sinθ, -x sinθ + z cosθ).
  return {a.x + c * b.x + s * b.z, a.z - s * b.x + c * b.z, a.yaw + b.yaw};
}
Frame2 invert(Frame2 a) {
  const double c = std::cos(-a.yaw), s = std::sin(-a.yaw);
  return {-(c * a.x + s * a.z), -(-s * a.x + c * a.z), -a.yaw};
}
Frame2 clip_frame(const Animation& clip, double s) {  // G(0)⁻¹ G(s), from the tracks
  const Channel& c = clip.channels[0];
  auto yaw = [&](double at) {
    return double(deform::twist_angle(deform::sample_track(c.rotation, float(at), {}), {0, 1, 0}));
  };
  const glm::vec3 p0 = deform::sample_track(c.translation, 0.0f, {}),
                  p = deform::sample_track(c.translation, float(s), {});
  return {double(p.x) - p0.x, double(p.z) - p0.z, std::remainder(yaw(s) - yaw(0), 2 * pi)};
}
Frame2 unwrapped_frame(const Animation& clip, double t) {
  const double d = clip.duration;
  const double k = std::floor(t / d);
  const double s = t - k * d;
  Frame2 loop = clip_frame(clip, d), f;
  for (int i = 0; i < std::abs(int(k)); ++i) f = then(f, k > 0 ? loop : invert(loop));
  return then(f, clip_frame(clip, s));
}

}  // namespace

TEST_CASE("root motion matches an explicit loop-by-loop reference, over wrap-arounds and several loops") {
  Random r(41);
  float worst = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Animation clip =
        root_clip(r, r.uniform(0.5f, 2.0f), trial % 2 == 1, static_cast<Interpolation>(r.integer(0, 2) == 0 ? 0 : 1));
    const float a = r.uniform(-5.0f, 8.0f), b = r.uniform(-5.0f, 8.0f);
    const RootMotion m = root_motion(clip, a, b);
    const Frame2 expected = then(invert(unwrapped_frame(clip, a)), unwrapped_frame(clip, b));
    const RootMotion e{glm::vec3(float(expected.x), 0.0f, float(expected.z)), float(expected.yaw)};
    worst = std::max(worst, glm::length(m.translation - e.translation));
    CHECK(same_motion(m, e, 2e-3f));
    CHECK(std::abs(m.translation.y) < 1e-5f);              // horizontal
    CHECK(std::abs(double(m.yaw) - expected.yaw) < 2e-3);  // the turns add up, unwrapped
  }
  MESSAGE("worst translation difference ", worst);
}

TEST_CASE("root motion over [a, b] then [b, c] is [a, c]; a whole loop is the last frame's motion") {
  Random r(42);
  for (int trial = 0; trial < 3000; ++trial) {
    const glm::vec3 up = trial % 3 == 0 ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    const Animation clip = root_clip(r, r.uniform(0.5f, 2.0f), true);
    const float a = r.uniform(-4.0f, 6.0f), b = r.uniform(-4.0f, 6.0f), c = r.uniform(-4.0f, 6.0f);
    const RootMotion ab = root_motion(clip, a, b, up), bc = root_motion(clip, b, c, up),
                     ac = root_motion(clip, a, c, up);
    const RootMotion composed = deform::compose(ab, bc, up);
    CHECK(same_motion(composed, ac, 2e-3f));
    CHECK(std::abs(composed.yaw - ac.yaw) < 2e-3f);
    CHECK(std::abs(glm::dot(ab.translation, up)) < 1e-5f);
    const RootMotion back = root_motion(clip, b, a, up);
    CHECK(same_motion(deform::compose(ab, back, up), RootMotion{}, 2e-3f));
  }
  // A clip walking +2 along X per loop without turning: [0.25, 3.75] over a 1-second clip moves 3.5 loops' worth where
  // the walk is linear.
  Animation walk;
  walk.name = "walk";
  walk.duration = 1.0f;
  Channel c;
  c.bone = 0;
  c.translation = {Interpolation::linear, {0.0f, 1.0f}, {glm::vec3(0, 1, 0), glm::vec3(2, 1.2f, 0)}, {}, {}};
  walk.channels.push_back(c);
  CHECK(same_motion(root_motion(walk, 0.25f, 3.75f), {glm::vec3(7, 0, 0), 0.0f}, 1e-5f));
  CHECK(same_motion(root_motion(walk, 0.9f, 1.1f), {glm::vec3(0.4f, 0, 0), 0.0f}, 1e-5f));
  CHECK(same_motion(root_motion(walk, -2.0f, 0.0f), {glm::vec3(4, 0, 0), 0.0f}, 1e-5f));
  walk.loop = false;  // clamped: no loops
  CHECK(same_motion(root_motion(walk, 0.25f, 3.75f), {glm::vec3(1.5f, 0, 0), 0.0f}, 1e-5f));
  // A quarter turn per loop: three loops turn 3π/2, and a step forward along the bone's +X each loop walks a square.
  Animation turn;
  turn.name = "turn";
  turn.duration = 1.0f;
  c.translation = {Interpolation::linear, {0.0f, 1.0f}, {glm::vec3(0), glm::vec3(1, 0, 0)}, {}, {}};
  c.rotation = {Interpolation::linear,
                {0.0f, 1.0f},
                {glm::quat(1, 0, 0, 0), glm::angleAxis(float(pi / 2), glm::vec3(0, 1, 0))},
                {},
                {}};
  turn.channels = {c};
  const RootMotion three = root_motion(turn, 0.0f, 3.0f);
  CHECK(std::abs(three.yaw - float(3 * pi / 2)) < 1e-5f);
  // The three loops' steps: (1,0,0), then turned a quarter about +Y (0,0,-1), then a half (-1,0,0): sum (0,0,-1).
  CHECK(glm::length(three.translation - glm::vec3(0, 0, -1)) < 1e-5f);
  CHECK(same_motion(root_motion(turn, 0.0f, 4.0f), {glm::vec3(0.0f), float(2 * pi)}, 1e-5f));
}

TEST_CASE("root motion in place: the frame times the in-place root gives the clip's root back") {
  Random r(43);
  for (int trial = 0; trial < 2000; ++trial) {
    const Animation clip = root_clip(r, r.uniform(0.5f, 2.0f), true);
    const float t = r.uniform(0.0f, clip.duration);
    Pose pose = identity_pose(3), original = identity_pose(3);
    sample(clip, t, pose);
    original = pose;
    RootMotion m;
    RootMotionJob job;
    job.animation = &clip;
    job.from = 0.0f;
    job.to = t;
    job.motion = &m;
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    REQUIRE(job.run().ok());
    // In place: no horizontal translation, the first frame's yaw.
    CHECK(std::abs(pose.translations[0].x) < 1e-6f);
    CHECK(std::abs(pose.translations[0].z) < 1e-6f);
    CHECK(std::abs(pose.translations[0].y - original.translations[0].y) < 1e-6f);
    const float first_yaw = deform::twist_angle(clip.channels[0].rotation.values[0], {0, 1, 0});
    CHECK(std::abs(std::remainder(deform::twist_angle(pose.rotations[0], {0, 1, 0}) - first_yaw, float(2 * pi))) <
          1e-4f);
    // G(0) · motion(0, t) · in-place = original.
    const glm::vec3 p0 = clip.channels[0].translation.values[0];
    const glm::mat4 frame = glm::translate(glm::mat4(1.0f), glm::vec3(p0.x, 0, p0.z) + m.translation) *
                            glm::mat4_cast(glm::angleAxis(m.yaw, glm::vec3(0, 1, 0)));
    const glm::mat4 rebuilt = frame * deform::local_matrix(pose.rotations[0], pose.translations[0]);
    const glm::mat4 expected = deform::local_matrix(original.rotations[0], original.translations[0]);
    for (int i = 0; i < 4; ++i) CHECK(glm::length(rebuilt[i] - expected[i]) < 1e-4f);
  }
}

TEST_CASE("RootMotionJob refuses malformed calls") {
  Animation clip;
  clip.name = "c";
  clip.duration = 1.0f;
  RootMotion m;
  Pose pose = identity_pose(2);
  RootMotionJob job;
  CHECK(std::string(job.run().reason()) == "no animation");
  job.animation = &clip;
  CHECK(std::string(job.run().reason()) == "no output");
  job.motion = &m;
  job.to = NAN;
  CHECK(std::string(job.run().reason()) == "times are not finite");
  job.to = 1e30f;
  CHECK(std::string(job.run().reason()) == "too many loops");
  job.to = 1.0f;
  job.up = glm::vec3(0, 2, 0);
  CHECK(std::string(job.run().reason()) == "up axis is not a unit vector");
  job.up = glm::vec3(0, 1, 0);
  job.bone = 2;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  CHECK(std::string(job.run().reason()) == "bone is outside the pose");
  job.bone = -1;
  CHECK(std::string(job.run().reason()) == "bone is negative");
  job.bone = 1;
  CHECK(job.run().ok());
  CHECK(std::string(job.run(0, 2).reason()) == "range outside the job");
  // No channel for the bone: the rest values, no motion.
  CHECK(same_motion(m, RootMotion{}, 0.0f));
}
