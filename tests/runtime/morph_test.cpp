// Morph targets: MorphJob against a double-precision reference over random sparse targets, range independence,
// validate(); morph-weight channels (step, linear, cubic spline) and sample_morph_weights.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "deform/runtime/animation.hpp"
#include "deform/runtime/morph.hpp"
using namespace deform;

namespace {

std::vector<MorphTarget> random_targets(std::mt19937& rng, std::size_t points, std::size_t count) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), density(0.0f, 1.0f);
  std::vector<MorphTarget> targets(count);
  for (MorphTarget& t : targets) {
    const float keep = density(rng);
    const bool normals = rng() % 2 == 0;
    for (std::uint32_t p = 0; p < points; ++p) {
      if (density(rng) > keep) continue;
      t.points.push_back(p);
      t.position_deltas.push_back({u(rng), u(rng), u(rng)});
      if (normals) t.normal_deltas.push_back({u(rng), u(rng), u(rng)});
    }
  }
  return targets;
}

}  // namespace

TEST_CASE("MorphJob equals rest + sum of weighted sparse deltas (double reference), whole and in ranges") {
  std::mt19937 rng(1124);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f), w(-1.5f, 1.5f);
  std::size_t checked = 0;
  for (int round = 0; round < 60; ++round) {
    const std::size_t points = 1 + rng() % 300, target_count = rng() % 9;
    const std::vector<MorphTarget> targets = random_targets(rng, points, target_count);
    std::vector<float> weights(target_count);
    for (float& x : weights) x = rng() % 4 == 0 ? 0.0f : w(rng);
    std::vector<glm::vec3> rest(points), rest_n(points), out(points, glm::vec3(7.0f)), out_n(points);
    for (std::size_t i = 0; i < points; ++i) rest[i] = {u(rng), u(rng), u(rng)}, rest_n[i] = {u(rng), u(rng), u(rng)};
    MorphJob job;
    job.targets = targets;
    job.weights = weights;
    job.rest_positions = rest;
    job.rest_normals = rest_n;
    job.out_positions = out;
    job.out_normals = out_n;
    REQUIRE(job.validate());
    REQUIRE(job.run());
    std::vector<glm::dvec3> ref(rest.begin(), rest.end()), ref_n(rest_n.begin(), rest_n.end());
    for (std::size_t k = 0; k < target_count; ++k)
      for (std::size_t i = 0; i < targets[k].points.size(); ++i) {
        ref[targets[k].points[i]] += double(weights[k]) * glm::dvec3(targets[k].position_deltas[i]);
        if (!targets[k].normal_deltas.empty())
          ref_n[targets[k].points[i]] += double(weights[k]) * glm::dvec3(targets[k].normal_deltas[i]);
      }
    for (std::size_t i = 0; i < points; ++i, ++checked) {
      CHECK(glm::length(ref[i] - glm::dvec3(out[i])) <= 1e-5 * std::max(1.0, glm::length(ref[i])));
      CHECK(glm::length(ref_n[i] - glm::dvec3(out_n[i])) <= 1e-5 * std::max(1.0, glm::length(ref_n[i])));
    }
    // Ranges give the same bits.
    std::vector<glm::vec3> parts(points, glm::vec3(-1.0f)), parts_n(points);
    job.out_positions = parts;
    job.out_normals = parts_n;
    for (std::size_t at = 0; at < points;) {
      const std::size_t next = std::min(points, at + 1 + rng() % 50);
      REQUIRE(job.run(at, next));
      at = next;
    }
    CHECK(parts == out);
    CHECK(parts_n == out_n);
  }
  CHECK(checked > 5000);
}

TEST_CASE("MorphJob::validate and run say what is wrong and write nothing") {
  std::vector<MorphTarget> targets(1);
  targets[0].points = {0, 2};
  targets[0].position_deltas = {glm::vec3(1.0f), glm::vec3(2.0f)};
  std::vector<float> weights = {1.0f};
  std::vector<glm::vec3> rest(3, glm::vec3(0.0f)), out(3, glm::vec3(5.0f));
  MorphJob job;
  job.targets = targets;
  job.weights = weights;
  job.rest_positions = rest;
  job.out_positions = out;
  CHECK(job.validate());
  CHECK(std::string(job.run(2, 4).reason()) == "range outside the job");
  CHECK(out[2] == glm::vec3(5.0f));
  weights[0] = NAN;
  CHECK(std::string(job.run().reason()) == "weight is not finite");
  CHECK(out[0] == glm::vec3(5.0f));
  weights[0] = 1.0f;
  targets[0].points = {2, 0};
  CHECK(std::string(job.validate().reason()) == "target is malformed");
  CHECK_THROWS_WITH_AS(require_valid_morph_targets(targets, 3, "m.gltf"), doctest::Contains("not strictly ascending"),
                       Error);
  targets[0].points = {0, 3};
  CHECK_THROWS_WITH_AS(require_valid_morph_targets(targets, 3, "m.gltf"), doctest::Contains("point out of range"),
                       Error);
  std::vector<float> two = {1.0f, 2.0f};
  job.weights = two;
  CHECK(std::string(job.validate().reason()) == "weights and targets differ in count");
  CHECK(find_morph_target(targets, "") == 0);
  CHECK(find_morph_target(targets, "smile") == -1);
}

TEST_CASE("morph channels: step, linear and cubic spline weights; sample_morph_weights leaves others alone") {
  Animation clip;
  clip.duration = 2.0f;
  clip.loop = false;
  MorphChannel step{1, {Interpolation::step, {0.0f, 1.0f}, {0.2f, 0.8f}, {}, {}}};
  MorphChannel linear{0, {Interpolation::linear, {0.0f, 2.0f}, {0.0f, 1.0f}, {}, {}}};
  MorphChannel cubic{3, {Interpolation::cubic_spline, {0.0f, 1.0f}, {0.0f, 1.0f}, {0.0f, 0.5f}, {2.0f, 0.0f}}};
  clip.morph_channels = {step, linear, cubic};
  clip.require_valid(0, "clip.gltf");
  std::vector<float> weights = {9.0f, 9.0f, 9.0f, 9.0f};
  REQUIRE(sample_morph_weights(clip, 0.5f, weights));
  CHECK(weights[0] == doctest::Approx(0.25f));
  CHECK(weights[1] == doctest::Approx(0.2f));
  CHECK(weights[2] == 9.0f);
  // Hermite at u = 0.5, dt = 1: p0 = 0, m0 = 2 (out of key 0), p1 = 1, m1 = 0.5 (in of key 1).
  const float u = 0.5f;
  const float h = (u * u * u - 2 * u * u + u) * 2.0f + (-2 * u * u * u + 3 * u * u) * 1.0f + (u * u * u - u * u) * 0.5f;
  CHECK(weights[3] == doctest::Approx(h));
  std::vector<float> short_weights(2, 0.0f);
  CHECK(std::string(sample_morph_weights(clip, 0.5f, short_weights).reason()) == "morph channel target out of range");
  CHECK(short_weights == std::vector<float>(2, 0.0f));
  clip.morph_channels.push_back(step);
  CHECK_THROWS_WITH_AS(clip.require_valid(0, "clip.gltf"), doctest::Contains("two morph channels for one target"),
                       Error);
}
