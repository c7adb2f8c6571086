// Automatic weights: hand-computed cases, the hierarchy restriction, a plain reference of the documented method over
// seeded random skeletons and points, smoothing, and invalid options.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
using deform::AutoWeightsOptions;
using deform::Bone;
using deform::Skeleton;
using deform::SkinWeights;

namespace {

Bone bone(std::int32_t parent, glm::vec3 translation, glm::vec3 rotation = glm::vec3(0.0f)) {
  Bone b;
  b.parent = parent;
  b.bind_translation = translation;
  b.bind_rotation = rotation;
  return b;
}

// Builds a skeleton from bones whose parents are set; fills the child lists in id order.
Skeleton make_skeleton(std::vector<Bone> bones) {
  for (std::size_t i = 1; i < bones.size(); ++i)
    bones[static_cast<std::size_t>(bones[i].parent)].children.push_back(static_cast<std::int32_t>(i));
  return Skeleton(std::move(bones));
}

// A chain of `n` bones along +Y, one metre apart, heads at y = 0, 1, 2, ...
Skeleton chain(int n) {
  std::vector<Bone> bones{bone(-1, {0, 0, 0})};
  for (int i = 1; i < n; ++i) bones.push_back(bone(i - 1, {0, 1, 0}));
  return make_skeleton(bones);
}

// Checks the .skw contract on every point and returns the bones with positive weight per point.
void check_normalised(const SkinWeights& w, std::size_t points, std::size_t bones, int max_influences = 4) {
  REQUIRE(w.size() == points);
  REQUIRE(w.weights.size() == points);
  for (std::size_t i = 0; i < points; ++i) {
    float sum = 0.0f;
    int used = 0;
    for (int k = 0; k < 4; ++k) {
      const float x = w.weights[i][k];
      REQUIRE(x >= 0.0f);
      REQUIRE(w.bones[i][k] < bones);
      if (x > 0.0f) ++used;
      if (k > 0) REQUIRE(x <= w.weights[i][k - 1]);  // strongest first
      if (x == 0.0f) REQUIRE(w.bones[i][k] == 0);    // unused slots: bone 0, weight 0
      sum += x;
    }
    REQUIRE(used >= 1);
    REQUIRE(used <= max_influences);
    REQUIRE(std::abs(sum - 1.0f) <= 1e-6f);
  }
}

float weight_of(const SkinWeights& w, std::size_t point, int bone_id) {
  for (int k = 0; k < 4; ++k)
    if (w.weights[point][k] > 0.0f && w.bones[point][k] == bone_id) return w.weights[point][k];
  return 0.0f;
}

// --- a plain reference of the method in weights.hpp (doubles, dense, no smoothing) ---

double reference_distance(glm::dvec3 p, glm::dvec3 head, glm::dvec3 tail, double behind_scale) {
  const glm::dvec3 axis = tail - head, v = p - head;
  const double length2 = glm::dot(axis, axis);
  if (length2 == 0.0) return glm::length(v);
  const double t = glm::dot(v, axis) / length2;
  if (t < 0.0) {
    const double behind = -t * std::sqrt(length2);
    const double perp2 = std::max(glm::dot(v, v) - behind * behind, 0.0);
    return std::sqrt(perp2 + behind_scale * behind_scale * behind * behind);
  }
  return glm::length(p - (head + std::min(t, 1.0) * axis));
}

// Dense weights per bone for one point.
// `ambiguous` (when given) is set when float rounding may choose otherwise: two bones within 1e-5 (relative) of the
// nearest distance, or the max_influences-th and the next weight within 1e-4 of each other.
std::vector<double> reference_weights(glm::vec3 point, const Skeleton& s, const AutoWeightsOptions& o,
                                      bool* ambiguous = nullptr) {
  const auto segments = deform::bone_segments(s, o.leaf_length);
  std::vector<double> d(s.bone_count());
  std::size_t nearest = 0;
  for (std::size_t b = 0; b < d.size(); ++b) {
    d[b] = reference_distance(point, segments[b].head, segments[b].tail,
                              s.bones()[b].parent >= 0 ? o.behind_head_penalty : 1.0);
    if (d[b] < d[nearest]) nearest = b;
  }
  std::vector<std::size_t> competitors{nearest};
  if (s.bones()[nearest].parent >= 0) competitors.push_back(static_cast<std::size_t>(s.bones()[nearest].parent));
  for (auto c : s.bones()[nearest].children) competitors.push_back(static_cast<std::size_t>(c));
  std::vector<double> w(s.bone_count(), 0.0);
  for (std::size_t b : competitors) w[b] = std::pow(d[nearest] / std::max(d[b], 1e-30), o.falloff_power);
  if (d[nearest] == 0.0) w[nearest] = 1.0;
  // The strongest max_influences, then drop those under 0.1% and normalise.
  std::vector<std::size_t> order(w.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return w[a] > w[b]; });
  const std::size_t keep = std::min(static_cast<std::size_t>(o.max_influences), w.size());
  if (ambiguous != nullptr) {
    *ambiguous = false;
    for (std::size_t b = 0; b < d.size(); ++b)
      if (b != nearest && d[b] <= d[nearest] * (1.0 + 1e-5)) *ambiguous = true;
    if (keep < w.size() && w[order[keep]] > 0.0 && w[order[keep - 1]] - w[order[keep]] <= 1e-4 * w[order[keep - 1]])
      *ambiguous = true;
  }
  double kept = 0.0;
  for (std::size_t k = 0; k < keep; ++k) kept += w[order[k]];
  std::vector<double> out(w.size(), 0.0);
  double total = 0.0;
  for (std::size_t k = 0; k < keep; ++k) {
    const std::size_t b = order[k];
    if (k == 0 || w[b] >= 1e-3 * kept) out[b] = w[b], total += w[b];
  }
  for (double& x : out) x /= total;
  return out;
}

}  // namespace

TEST_CASE("bone_segments: first child, leaf continuation, lone root") {
  // root at origin -> child A at (0,1,0) (first) and child B at (1,0,0); A is a leaf.
  const Skeleton s = make_skeleton({bone(-1, {0, 0, 0}), bone(0, {0, 1, 0}), bone(0, {1, 0, 0})});
  auto segments = deform::bone_segments(s);
  REQUIRE(segments.size() == 3);
  CHECK(segments[0].tail == glm::vec3(0, 1, 0));  // the first child's head
  CHECK(segments[1].head == glm::vec3(0, 1, 0));
  CHECK(segments[1].tail == glm::vec3(0, 2, 0));  // parent -> head, once more
  CHECK(segments[2].tail == glm::vec3(2, 0, 0));
  segments = deform::bone_segments(s, 0.5f);
  CHECK(segments[1].tail == glm::vec3(0, 1.5f, 0));
  const auto lone = deform::bone_segments(make_skeleton({bone(-1, {3, 4, 5})}));
  CHECK(lone[0].head == glm::vec3(3, 4, 5));
  CHECK(lone[0].tail == glm::vec3(3, 4, 5));
  CHECK_THROWS_AS(deform::bone_segments(s, -1.0f), deform::Error);
}

TEST_CASE("hand-computed weights of a two-bone chain") {
  const Skeleton s = chain(2);  // segments (0,0,0)-(0,1,0) and (0,1,0)-(0,2,0)
  const std::vector<glm::vec3> points = {{1.0f, 0.5f, 0.0f}, {0.0f, 1.5f, 0.0f}, {0.0f, 1.0f, 0.3f}};
  const SkinWeights w = deform::compute_automatic_weights(points, s);
  check_normalised(w, points.size(), 2);
  // Point 0: root at distance 1; child: 0.5 behind its head, 1 aside -> d² = 1 + (2·0.5)² = 2;
  // weights 1 and (1/√2)^4 = 1/4 -> 0.8 and 0.2.
  CHECK(w.bones[0][0] == 0);
  CHECK(w.weights[0][0] == doctest::Approx(0.8).epsilon(1e-6));
  CHECK(weight_of(w, 0, 1) == doctest::Approx(0.2).epsilon(1e-6));
  // Point 1 lies on the child's segment: the child alone.
  CHECK(w.bones[1][0] == 1);
  CHECK(w.weights[1][0] == 1.0f);
  CHECK(w.weights[1][1] == 0.0f);
  // Point 2 is level with the joint: the root (0.3 beyond its tail) and the child (0.3 aside, nothing behind) tie,
  // and equal distances give equal weights.
  CHECK(w.weights[2][0] == doctest::Approx(0.5).epsilon(1e-5));
  CHECK(w.weights[2][1] == doctest::Approx(0.5).epsilon(1e-5));
  CHECK(w.bones[2][0] == 0);  // a tie lists the lower id first
  // A penalty of 1 is the plain segment distance: point 0 is then at √1.25 from the child.
  AutoWeightsOptions plain;
  plain.behind_head_penalty = 1.0f;
  const SkinWeights p = deform::compute_automatic_weights(points, s, plain);
  const double child = std::pow(1.0 / 1.25, 2.0);
  CHECK(weight_of(p, 0, 1) == doctest::Approx(child / (1.0 + child)).epsilon(1e-6));
}

TEST_CASE("only the nearest bone, its parent and its children compete") {
  // A long chain: a point beside bone 3 is never pulled by bones 0 or 1, however the falloff is set.
  const Skeleton s = chain(6);
  AutoWeightsOptions soft;
  soft.falloff_power = 0.5f;  // nearly flat falloff: without the restriction every bone would get weight
  const std::vector<glm::vec3> points = {{0.4f, 3.5f, 0.0f}, {2.0f, 3.1f, 0.0f}};
  const SkinWeights w = deform::compute_automatic_weights(points, s, soft);
  check_normalised(w, points.size(), 6);
  for (std::size_t i = 0; i < points.size(); ++i) {
    CHECK(weight_of(w, i, 0) == 0.0f);
    CHECK(weight_of(w, i, 1) == 0.0f);
    CHECK(weight_of(w, i, 5) == 0.0f);
    CHECK(weight_of(w, i, 3) > 0.0f);
    CHECK(weight_of(w, i, 2) > 0.0f);
    CHECK(weight_of(w, i, 4) > 0.0f);
  }
  // Siblings do not compete: a point on the left arm of a Y-shaped skeleton gets nothing from the right arm.
  const Skeleton y =
      make_skeleton({bone(-1, {0, 0, 0}), bone(0, {0, 1, 0}), bone(1, {0.3f, 0.3f, 0}), bone(1, {-0.3f, 0.3f, 0})});
  const std::vector<glm::vec3> left = {{0.35f, 1.4f, 0.0f}, {0.45f, 1.45f, 0.05f}};
  const SkinWeights wy = deform::compute_automatic_weights(left, y, soft);
  CHECK(weight_of(wy, 0, 2) > 0.5f);
  CHECK(weight_of(wy, 0, 3) == 0.0f);
  CHECK(weight_of(wy, 1, 3) == 0.0f);
}

TEST_CASE("max_influences caps the count and keeps the strongest") {
  const Skeleton s = chain(4);
  const std::vector<glm::vec3> points = {{0.5f, 1.5f, 0.0f}, {0.2f, 2.0f, 0.1f}, {0.0f, -0.5f, 0.0f}};
  for (int k = 1; k <= 4; ++k) {
    AutoWeightsOptions o;
    o.max_influences = k;
    o.falloff_power = 1.0f;
    const SkinWeights w = deform::compute_automatic_weights(points, s, o);
    check_normalised(w, points.size(), 4, k);
    if (k == 1)
      for (std::size_t i = 0; i < points.size(); ++i) CHECK(w.weights[i][0] == 1.0f);
  }
  AutoWeightsOptions one;
  one.max_influences = 1;
  const SkinWeights w = deform::compute_automatic_weights(points, s, one);
  CHECK(w.bones[0][0] == 1);  // beside bone 1's segment
  CHECK(w.bones[2][0] == 0);  // below the root
}

TEST_CASE("random skeletons and points agree with the reference method") {
  std::mt19937 rng(20261121);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_real_distribution<float> angle(-180.0f, 180.0f);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int count = 1 + static_cast<int>(rng() % 12);
    std::vector<Bone> bones;
    for (int i = 0; i < count; ++i) {
      const std::int32_t parent = i == 0 ? -1 : static_cast<std::int32_t>(rng() % static_cast<unsigned>(i));
      const glm::vec3 translation{unit(rng), unit(rng), unit(rng)};
      bones.push_back(bone(parent, translation, {angle(rng), angle(rng), angle(rng)}));
    }
    const Skeleton s = make_skeleton(bones);
    AutoWeightsOptions o;
    o.falloff_power = 1.0f + 0.1f * static_cast<float>(rng() % 60);
    o.behind_head_penalty = 1.0f + 0.1f * static_cast<float>(rng() % 30);
    o.leaf_length = 0.1f * static_cast<float>(rng() % 20);
    o.max_influences = 1 + static_cast<int>(rng() % 4);
    std::vector<glm::vec3> points(100);
    for (glm::vec3& p : points) p = 2.0f * glm::vec3{unit(rng), unit(rng), unit(rng)};
    const SkinWeights w = deform::compute_automatic_weights(points, s, o);
    check_normalised(w, points.size(), s.bone_count(), o.max_influences);
    for (std::size_t i = 0; i < points.size(); ++i) {
      bool ambiguous = false;
      const std::vector<double> expected = reference_weights(points[i], s, o, &ambiguous);
      if (ambiguous) continue;  // a near tie: float and double may rightly choose differently
      for (std::size_t b = 0; b < expected.size(); ++b) {
        // Near the 0.1% cut-off or a tie of the k-th place the float and double versions may keep different
        // sets; the difference is then below 0.2%.
        INFO("trial " << trial << " point " << i << " bone " << b << " of " << s.bone_count() << " k "
                      << o.max_influences << " leaf " << o.leaf_length << " got " << w.bones[i][0] << ":"
                      << w.weights[i][0] << " " << w.bones[i][1] << ":" << w.weights[i][1]);
        REQUIRE(std::abs(weight_of(w, i, static_cast<int>(b)) - expected[b]) <= 2e-3);
        ++checked;
      }
    }
  }
  CHECK(checked > 10000);
}

TEST_CASE("smoothing keeps the contract and softens the seams of the built-in character") {
  const deform::Model model = deform::builtin_character();
  AutoWeightsOptions raw;
  raw.smoothing_iterations = 0;
  const SkinWeights unsmoothed = deform::compute_automatic_weights(model.mesh, model.skeleton, raw);
  // Without smoothing the mesh version is the points version.
  CHECK(unsmoothed == deform::compute_automatic_weights(model.mesh.positions, model.skeleton, raw));
  const SkinWeights smoothed = deform::compute_automatic_weights(model.mesh, model.skeleton);
  check_normalised(smoothed, model.mesh.point_count(), model.skeleton.bone_count());
  CHECK(smoothed == model.weights);

  // Dirichlet energy over the mesh edges: sum of (w_a(b) - w_b(b))² over edges and bones. Smoothing lowers it.
  auto energy = [&](const SkinWeights& w) {
    double total = 0.0;
    const auto& m = model.mesh;
    for (std::size_t t = 0; t < m.triangles.size(); t += 3)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = m.vertex_point[m.triangles[t + static_cast<std::size_t>(k)]];
        const std::uint32_t b = m.vertex_point[m.triangles[t + static_cast<std::size_t>((k + 1) % 3)]];
        std::map<int, double> diff;
        for (int s = 0; s < 4; ++s) {
          diff[w.bones[a][s]] += w.weights[a][s];
          diff[w.bones[b][s]] -= w.weights[b][s];
        }
        for (const auto& [bone_id, d] : diff) total += d * d;
      }
    return total;
  };
  const double before = energy(unsmoothed), after = energy(smoothed);
  CHECK(after < 0.6 * before);
}

TEST_CASE("invalid options and points are errors, not silent fixes") {
  const Skeleton s = chain(2);
  const std::vector<glm::vec3> points = {{0, 0, 0}};
  auto fails = [&](void (*edit)(AutoWeightsOptions&), const char* element) {
    AutoWeightsOptions o;
    edit(o);
    CHECK_THROWS_WITH_AS(deform::compute_automatic_weights(points, s, o), doctest::Contains(element), deform::Error);
  };
  fails([](AutoWeightsOptions& o) { o.falloff_power = 0.0f; }, "falloff_power");
  fails([](AutoWeightsOptions& o) { o.falloff_power = std::nanf(""); }, "falloff_power");
  fails([](AutoWeightsOptions& o) { o.behind_head_penalty = 0.5f; }, "behind_head_penalty");
  fails([](AutoWeightsOptions& o) { o.leaf_length = -0.1f; }, "leaf_length");
  fails([](AutoWeightsOptions& o) { o.max_influences = 0; }, "max_influences");
  fails([](AutoWeightsOptions& o) { o.max_influences = 5; }, "max_influences");
  fails([](AutoWeightsOptions& o) { o.smoothing_iterations = -1; }, "smoothing_iterations");
  const std::vector<glm::vec3> bad = {{0, 0, 0}, {0, INFINITY, 0}};
  CHECK_THROWS_WITH_AS(deform::compute_automatic_weights(bad, s), doctest::Contains("vertex 1"), deform::Error);
  CHECK(deform::compute_automatic_weights(std::vector<glm::vec3>{}, s).size() == 0);
  // A mesh whose triangles point past its vertices is rejected before smoothing reads them.
  deform::Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.vertex_point = {0, 1, 2};
  mesh.triangles = {0, 1, 7};
  CHECK_THROWS_WITH_AS(deform::compute_automatic_weights(mesh, s), doctest::Contains("triangle 0"), deform::Error);
}
