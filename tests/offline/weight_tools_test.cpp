// The rigger's weight controls (weight_tools.hpp): glob matching and bone selection, and each weight tool checked for
// the property it promises over seeded random weights on a mesh symmetric about x = 0.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
using deform::Bone;
using deform::Skeleton;
using deform::SkinWeights;

namespace {

Bone bone(const char* name, std::int32_t parent, glm::vec3 translation) {
  Bone b;
  b.name = name;
  b.parent = parent;
  b.bind_translation = translation;
  return b;
}

// spine (root) with a head and two arms (upper + hand) on either side of x = 0.
Skeleton symmetric_skeleton() {
  std::vector<Bone> bones = {bone("spine", -1, {0, 0, 0}),       bone("head", 0, {0, 1, 0}),
                             bone("arm.L", 0, {0.5f, 0.8f, 0}),  bone("hand.L", 2, {0.5f, 0, 0}),
                             bone("arm.R", 0, {-0.5f, 0.8f, 0}), bone("hand.R", 4, {-0.5f, 0, 0})};
  for (std::size_t i = 1; i < bones.size(); ++i)
    bones[static_cast<std::size_t>(bones[i].parent)].children.push_back(static_cast<std::int32_t>(i));
  return Skeleton(std::move(bones));
}

// A grid of (2n + 1) × m points in the plane z = 0, x from -1 to 1 (symmetric about x = 0), two triangles per cell,
// the points' order shuffled by `seed` (so that a point's mirror is not found by its index).
deform::Mesh symmetric_grid(int n, int m, unsigned seed) {
  std::vector<glm::vec3> grid;
  for (int j = 0; j < m; ++j)
    for (int i = -n; i <= n; ++i) grid.emplace_back(float(i) / float(n), float(j) * 0.1f, 0.0f);
  std::vector<std::uint32_t> order(grid.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<std::uint32_t> where(grid.size());
  deform::Mesh mesh;
  mesh.positions.resize(grid.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) {
    mesh.positions[k] = grid[order[k]];
    where[order[k]] = k;
  }
  mesh.vertex_point.resize(grid.size());
  for (std::uint32_t k = 0; k < grid.size(); ++k) mesh.vertex_point[k] = k;
  const int w = 2 * n + 1;
  auto id = [&](int i, int j) { return where[static_cast<std::size_t>(j * w + i)]; };
  for (int j = 0; j + 1 < m; ++j)
    for (int i = 0; i + 1 < w; ++i)
      for (std::uint32_t v : {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)})
        mesh.triangles.push_back(v);
  return mesh;
}

// Random weights: 1 to `most` influences per point on random bones, random positive weights, normalised.
SkinWeights random_weights(std::size_t points, std::uint16_t bones, int most, std::mt19937& rng) {
  SkinWeights w;
  std::uniform_int_distribution<int> count(1, most);
  std::uniform_int_distribution<int> which(0, bones - 1);
  std::uniform_real_distribution<float> value(0.01f, 1.0f);
  for (std::size_t p = 0; p < points; ++p) {
    std::vector<std::uint16_t> b;
    std::vector<float> v;
    const int n = count(rng);
    for (int k = 0; k < n; ++k) {
      b.push_back(static_cast<std::uint16_t>(which(rng)));
      v.push_back(value(rng));
    }
    deform::append_influences(w, b, v);
  }
  return w;
}

// Each point's influences as a map bone -> weight (slots and extras).
std::vector<std::map<int, float>> rows(const SkinWeights& w) {
  std::vector<std::map<int, float>> out(w.size());
  for (std::size_t p = 0; p < w.size(); ++p)
    for (int k = 0; k < deform::max_influences; ++k)
      if (w.weights[p][k] > 0.0f) out[p][w.bones[p][k]] += w.weights[p][k];
  for (std::size_t j = 0; j < w.extra_points.size(); ++j)
    for (std::uint32_t e = w.extra_offsets[j]; e < w.extra_offsets[j + 1]; ++e)
      out[w.extra_points[j]][w.extra_bones[e]] += w.extra_weights[e];
  return out;
}

void check_normalised(const SkinWeights& w) {
  for (const auto& row : rows(w)) {
    double sum = 0.0;
    for (const auto& [bone, value] : row) {
      CHECK(value > 0.0f);
      sum += value;
    }
    CHECK(sum == doctest::Approx(1.0).epsilon(1e-5));
  }
}

bool same_weights(const SkinWeights& a, const SkinWeights& b, float tolerance) {
  const auto ra = rows(a), rb = rows(b);
  if (ra.size() != rb.size()) return false;
  for (std::size_t p = 0; p < ra.size(); ++p) {
    if (ra[p].size() != rb[p].size()) return false;
    for (const auto& [bone, value] : ra[p]) {
      const auto it = rb[p].find(bone);
      if (it == rb[p].end() || std::abs(it->second - value) > tolerance) return false;
    }
  }
  return true;
}

}  // namespace

TEST_CASE("glob_match: *, ?, classes, escapes, anchored") {
  using deform::glob_match;
  CHECK(glob_match("*", ""));
  CHECK(glob_match("hand*", "hand_l"));
  CHECK_FALSE(glob_match("hand*", "Hand_l"));  // case-sensitive
  CHECK(glob_match("*_l", "thumb1_l"));
  CHECK_FALSE(glob_match("*_l", "thumb1_r"));
  CHECK(glob_match("thumb?_l", "thumb2_l"));
  CHECK_FALSE(glob_match("thumb?_l", "thumb12_l"));
  CHECK(glob_match("?", "\xc3\xa9"));  // é: one character, two bytes
  CHECK(glob_match("finger[12]_*", "finger2_l"));
  CHECK_FALSE(glob_match("finger[12]_*", "finger3_l"));
  CHECK(glob_match("finger[1-3]", "finger3"));
  CHECK(glob_match("finger[!1-3]", "finger4"));
  CHECK(glob_match("finger[^1-3]", "finger4"));
  CHECK_FALSE(glob_match("finger[!1-3]", "finger2"));
  CHECK(glob_match("[]]", "]"));
  CHECK(glob_match("a\\*b", "a*b"));
  CHECK_FALSE(glob_match("a\\*b", "axb"));
  CHECK(glob_match("*a*b*c*", "xxaxxbxxcxx"));
  CHECK_FALSE(glob_match("*a*b*c*", "xxcxxbxxaxx"));
  CHECK_FALSE(glob_match("hand", "hand_l"));  // anchored at both ends
  CHECK_THROWS_WITH_AS(glob_match("hand[12", "hand1"), doctest::Contains("unclosed '['"), deform::Error);
  CHECK_THROWS_WITH_AS(glob_match("hand\\", "x"), doctest::Contains("ends with '\\'"), deform::Error);
}

TEST_CASE("select_bones: include, exclude, a pattern that matches nothing, nothing left") {
  const Skeleton s = symmetric_skeleton();
  const std::vector<std::string> none;
  CHECK(deform::select_bones(s, none) == std::vector<std::uint8_t>{1, 1, 1, 1, 1, 1});
  const std::vector<std::string> arms = {"arm.*", "spine"};
  CHECK(deform::select_bones(s, arms) == std::vector<std::uint8_t>{1, 0, 1, 0, 1, 0});
  const std::vector<std::string> hands = {"hand.?"};
  CHECK(deform::select_bones(s, none, hands) == std::vector<std::uint8_t>{1, 1, 1, 0, 1, 0});
  CHECK(deform::select_bones(s, arms, std::vector<std::string>{"*.R"}) == std::vector<std::uint8_t>{1, 0, 1, 0, 0, 0});
  CHECK_THROWS_WITH_AS(deform::select_bones(s, std::vector<std::string>{"arm*", "Hand*"}),
                       doctest::Contains("pattern 'Hand*': matches no bone"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::select_bones(s, none, std::vector<std::string>{"leg*"}),
                       doctest::Contains("pattern 'leg*': matches no bone"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::select_bones(s, hands, hands), doctest::Contains("no bone deforms"), deform::Error);
}

TEST_CASE("weighted_bones: the bones some point uses, extras included") {
  SkinWeights w;
  const std::vector<std::uint16_t> b = {0, 2, 3, 4, 5};
  const std::vector<float> v = {5, 4, 3, 2, 1};  // bone 5 lands past the fourth, in the extras
  deform::append_influences(w, b, v);
  REQUIRE(w.has_extra());
  CHECK(deform::weighted_bones(w, 7) == std::vector<std::uint8_t>{1, 0, 1, 1, 1, 1, 0});
}

TEST_CASE("normalize, prune, limit: sums stay 1 and each promise holds over random weights") {
  std::mt19937 rng(34);
  for (int trial = 0; trial < 20; ++trial) {
    const SkinWeights start = random_weights(200, 12, 8, rng);
    // normalise: an unnormalised copy comes back as the normalised start.
    SkinWeights scaled = start;
    for (auto& w4 : scaled.weights) w4 *= 3.0f;
    for (float& e : scaled.extra_weights) e *= 3.0f;
    deform::normalize_weights(scaled);
    check_normalised(scaled);
    CHECK(same_weights(scaled, start, 1e-6f));

    const float threshold = std::uniform_real_distribution<float>(0.0f, 0.6f)(rng);
    SkinWeights pruned = start;
    const std::size_t removed = deform::prune_weights(pruned, threshold);
    check_normalised(pruned);
    std::size_t before = 0, after = 0;
    for (const auto& row : rows(start)) before += row.size();
    const auto pruned_rows = rows(pruned);
    for (const auto& row : pruned_rows) {
      after += row.size();
      CHECK(!row.empty());
      for (const auto& [bone, value] : row) CHECK(value >= threshold * (1.0f - 1e-6f));
    }
    CHECK(before - after == removed);
    // The strongest bone of each point survives.
    const auto start_rows = rows(start);
    for (std::size_t p = 0; p < start.size(); ++p) CHECK(pruned_rows[p].count(start.bones[p][0]) == 1);

    const int limit = std::uniform_int_distribution<int>(1, 6)(rng);
    SkinWeights limited = start;
    deform::limit_influences(limited, limit);
    check_normalised(limited);
    for (std::size_t p = 0; p < limited.size(); ++p) {
      CHECK(deform::influence_count(limited, p) <= static_cast<std::size_t>(limit));
      CHECK(limited.bones[p][0] == start.bones[p][0]);
    }
  }
  SkinWeights w = random_weights(3, 4, 2, rng);
  CHECK_THROWS_AS(deform::prune_weights(w, -0.1f), deform::Error);
  CHECK_THROWS_AS(deform::prune_weights(w, 1.5f), deform::Error);
  CHECK_THROWS_AS(deform::limit_influences(w, 0), deform::Error);
  CHECK_THROWS_AS(deform::limit_influences(w, 17), deform::Error);
}

TEST_CASE("prune: a point whose weights all lie below the threshold keeps its strongest alone") {
  SkinWeights w;
  const std::vector<std::uint16_t> b = {3, 1, 2};
  const std::vector<float> v = {1, 1, 1};
  deform::append_influences(w, b, v);
  CHECK(deform::prune_weights(w, 0.5f) == 2);
  CHECK(w.bones[0][0] == 1);  // ties: the lower bone
  CHECK(w.weights[0][0] == 1.0f);
  CHECK(deform::influence_count(w, 0) == 1);
}

TEST_CASE("smooth: sums stay 1, the gradient energy shrinks, a seam stays closed") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    const deform::Mesh mesh = symmetric_grid(6, 8, static_cast<unsigned>(trial));
    const SkinWeights start = random_weights(mesh.point_count(), 6, 4, rng);
    const double e0 = deform::weight_gradient_energy(start, mesh);
    // Without the cut (every influence kept) no pass raises the energy.
    double previous = e0;
    SkinWeights w = start;
    for (int pass = 0; pass < 5; ++pass) {
      deform::SmoothWeightsOptions o;
      o.iterations = 1;
      o.max_influences = 6;
      deform::smooth_weights(w, mesh, o);
      check_normalised(w);
      const double e = deform::weight_gradient_energy(w, mesh);
      CHECK(e <= previous * (1.0 + 1e-6));
      previous = e;
    }
    CHECK(previous < 0.5 * e0);
    // With the default cut to four, a few passes still shrink it.
    SkinWeights cut = start;
    deform::SmoothWeightsOptions o;
    o.iterations = 3;
    deform::smooth_weights(cut, mesh, o);
    check_normalised(cut);
    for (std::size_t p = 0; p < cut.size(); ++p) CHECK(deform::influence_count(cut, p) <= 4);
    CHECK(deform::weight_gradient_energy(cut, mesh) < e0);
  }
  // A seam: point 4 duplicates point 1's position (as a UV seam splits a vertex) with other weights; after smoothing
  // both have the same weights.
  deform::Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
  mesh.vertex_point = {0, 1, 2, 3, 4};
  mesh.triangles = {0, 1, 2, 4, 3, 2};
  SkinWeights w;
  for (int b : {0, 1, 2, 3, 1}) {
    const std::vector<std::uint16_t> bones = {static_cast<std::uint16_t>(b)};
    const std::vector<float> one = {1.0f};
    deform::append_influences(w, bones, one);
  }
  w.bones[4][0] = 4;  // the seam's second point on another bone
  deform::smooth_weights(w, mesh, {});
  CHECK(rows(w)[1] == rows(w)[4]);
  check_normalised(w);
  // Invalid options and weights that do not fit.
  deform::SmoothWeightsOptions bad;
  bad.factor = 0.0f;
  CHECK_THROWS_AS(deform::smooth_weights(w, mesh, bad), deform::Error);
  bad = {};
  bad.iterations = -1;
  CHECK_THROWS_AS(deform::smooth_weights(w, mesh, bad), deform::Error);
  SkinWeights short_weights = w;
  short_weights.bones.pop_back();
  short_weights.weights.pop_back();
  CHECK_THROWS_WITH_AS(deform::smooth_weights(short_weights, mesh, {}), doctest::Contains("hold 4 points, the mesh 5"),
                       deform::Error);
}

TEST_CASE("mirrored_bone_name: the built-in side rules and custom pairs") {
  using deform::mirrored_bone_name;
  CHECK(mirrored_bone_name("Hand.L") == "Hand.R");
  CHECK(mirrored_bone_name("hand_l") == "hand_r");
  CHECK(mirrored_bone_name("hand_r") == "hand_l");
  CHECK(mirrored_bone_name("L_Hand") == "R_Hand");
  CHECK(mirrored_bone_name("Arm.L.001") == "Arm.R.001");
  CHECK(mirrored_bone_name("arm-l") == "arm-r");
  CHECK(mirrored_bone_name("LeftArm") == "RightArm");
  CHECK(mirrored_bone_name("mixamorig:RightHand") == "mixamorig:LeftHand");
  CHECK(mirrored_bone_name("B_Finger3_Left") == "B_Finger3_Right");
  CHECK(mirrored_bone_name("upperArmLeft") == "upperArmRight");
  CHECK(mirrored_bone_name("ARM_LEFT") == "ARM_RIGHT");
  CHECK(mirrored_bone_name("left_arm") == "right_arm");
  CHECK(mirrored_bone_name("Spine") == std::nullopt);
  CHECK(mirrored_bone_name("Bright") == std::nullopt);
  CHECK(mirrored_bone_name("Leftover") == std::nullopt);
  CHECK(mirrored_bone_name("L") == std::nullopt);
  CHECK(mirrored_bone_name("Roll") == std::nullopt);
  // Its own inverse.
  for (const char* name : {"Hand.L", "LeftArm", "B_Finger3_Left", "ARM_LEFT", "L_arm_left", "RightLeft"}) {
    const auto once = mirrored_bone_name(name);
    REQUIRE(once);
    CHECK(mirrored_bone_name(*once) == name);
  }
  const std::vector<std::pair<std::string, std::string>> pairs = {{"Links", "Rechts"}};
  CHECK(mirrored_bone_name("ArmLinks", pairs) == "ArmRechts");
  CHECK(mirrored_bone_name("ArmRechts", pairs) == "ArmLinks");
  CHECK(mirrored_bone_name("Hand.L", pairs) == std::nullopt);  // custom pairs replace the built-in rules
  const std::vector<std::pair<std::string, std::string>> bad = {{"X", "X"}};
  CHECK_THROWS_AS(mirrored_bone_name("X", bad), deform::Error);
}

TEST_CASE("mirror: flip twice gives the input back; a left-only weight appears on the right") {
  const Skeleton s = symmetric_skeleton();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const deform::Mesh mesh = symmetric_grid(5, 6, 100u + static_cast<unsigned>(trial));
    const SkinWeights start = random_weights(mesh.point_count(), 6, 5, rng);
    const auto once = deform::mirror_weights(start, mesh, s);
    CHECK(once.axis == 0);
    CHECK(once.plane == 0.0f);
    CHECK(once.bone_pairs == 2);
    CHECK(once.points == mesh.point_count());
    check_normalised(once.weights);
    const auto twice = deform::mirror_weights(once.weights, mesh, s);
    CHECK(same_weights(twice.weights, start, 1e-6f));
    // Each point holds its mirror point's weights, sides swapped (bones 2 <-> 4, 3 <-> 5).
    const int swap[] = {0, 1, 4, 5, 2, 3};
    const auto before = rows(start), after = rows(once.weights);
    for (std::size_t p = 0; p < mesh.point_count(); ++p) {
      glm::vec3 image = mesh.positions[p];
      image.x = -image.x;
      std::size_t q = 0;
      while (glm::length(mesh.positions[q] - image) > 1e-6f) ++q;
      for (const auto& [bone, value] : before[q]) CHECK(after[p].at(swap[bone]) == doctest::Approx(value));
    }
  }
  // Copy from the left (+x): weights painted on the left only appear on the right, the left is unchanged.
  const deform::Mesh mesh = symmetric_grid(4, 3, 5);
  SkinWeights painted;
  for (std::size_t p = 0; p < mesh.point_count(); ++p) {
    const float x = mesh.positions[p].x;
    const std::vector<std::uint16_t> bones =
        x > 0.0f ? std::vector<std::uint16_t>{3, 2} : std::vector<std::uint16_t>{0};
    const std::vector<float> values = x > 0.0f ? std::vector<float>{x, 1.0f - x + 0.01f} : std::vector<float>{1.0f};
    deform::append_influences(painted, bones, values);
  }
  deform::MirrorWeightsOptions copy;
  copy.mode = deform::MirrorMode::from_positive;
  const auto copied = deform::mirror_weights(painted, mesh, s, copy);
  const auto before = rows(painted), after = rows(copied.weights);
  for (std::size_t p = 0; p < mesh.point_count(); ++p) {
    const float x = mesh.positions[p].x;
    if (x >= 0.0f) {
      CHECK(after[p] == before[p]);
    } else {
      CHECK(after[p].count(5) == 1);  // hand.R, where hand.L was on the mirror point
      CHECK(after[p].count(3) == 0);
    }
  }
  CHECK(copied.points == 4u * 3u);
}

TEST_CASE("mirror: clear errors for a bone without partner and a point without mirror") {
  std::vector<Bone> bones = {bone("spine", -1, {0, 0, 0}), bone("arm.L", 0, {0.5f, 0.8f, 0}),
                             bone("arm.R", 0, {-0.5f, 0.8f, 0}), bone("goal.L", 0, {1, 0, 0})};
  for (std::size_t i = 1; i < bones.size(); ++i) bones[0].children.push_back(static_cast<std::int32_t>(i));
  const Skeleton s(std::move(bones));
  const deform::Mesh mesh = symmetric_grid(2, 2, 1);
  SkinWeights w;
  for (std::size_t p = 0; p < mesh.point_count(); ++p) {
    const std::vector<std::uint16_t> b = {static_cast<std::uint16_t>(p == 3 ? 3 : 1)};
    const std::vector<float> one = {1.0f};
    deform::append_influences(w, b, one);
  }
  CHECK_THROWS_WITH_AS(deform::mirror_weights(w, mesh, s),
                       doctest::Contains("bone 'goal.L' (id 3): has no mirror partner: no bone is named 'goal.R'"),
                       deform::Error);
  // Unused, the same bone is no error.
  w.bones[3][0] = 1;
  CHECK_NOTHROW(deform::mirror_weights(w, mesh, s));
  // A point moved off the symmetry.
  deform::Mesh moved = mesh;
  std::size_t off_plane = 0;
  while (moved.positions[off_plane].x == 0.0f) ++off_plane;
  moved.positions[off_plane].y += 0.05f;
  CHECK_THROWS_WITH_AS(deform::mirror_weights(w, moved, s), doctest::Contains("has no mirror point within"),
                       deform::Error);
  deform::MirrorWeightsOptions loose;
  loose.tolerance = 0.1f;
  CHECK_NOTHROW(deform::mirror_weights(w, moved, s, loose));
  // No pair to find the axis by.
  const std::vector<Bone> lone = {bone("root", -1, {0, 0, 0})};
  const Skeleton single{std::vector<Bone>(lone)};
  SkinWeights zero;
  for (std::size_t p = 0; p < mesh.point_count(); ++p) {
    const std::vector<std::uint16_t> b = {0};
    const std::vector<float> one = {1.0f};
    deform::append_influences(zero, b, one);
  }
  CHECK_THROWS_WITH_AS(deform::mirror_weights(zero, mesh, single), doctest::Contains("no left/right bone pair"),
                       deform::Error);
  deform::MirrorWeightsOptions x_axis;
  x_axis.axis = 0;
  CHECK(deform::mirror_weights(zero, mesh, single, x_axis).weights == zero);
}

TEST_CASE("mirror: the built-in character's shipped weights, flipped twice") {
  const deform::Model model = deform::builtin_character();
  const auto once = deform::mirror_weights(model.weights, model.mesh, model.skeleton);
  CHECK(once.axis == 0);
  CHECK(once.bone_pairs > 5);
  const auto twice = deform::mirror_weights(once.weights, model.mesh, model.skeleton);
  CHECK(same_weights(twice.weights, model.weights, 1e-5f));
}

TEST_CASE("heat weights' smoothing option: sums stay 1, the gradient energy shrinks, out of range refused") {
  const deform::Model model = deform::builtin_character();
  const deform::WeightsResult plain = deform::compute_heat_weights(model.mesh, model.skeleton);
  deform::HeatWeightsOptions o;
  o.smoothing_iterations = 3;
  const deform::WeightsResult smooth = deform::compute_heat_weights(model.mesh, model.skeleton, o);
  check_normalised(smooth.weights);
  for (std::size_t p = 0; p < smooth.weights.size(); ++p) CHECK(deform::influence_count(smooth.weights, p) <= 4);
  CHECK(deform::weight_gradient_energy(smooth.weights, model.mesh) <
        0.9 * deform::weight_gradient_energy(plain.weights, model.mesh));
  o.smoothing_iterations = 101;
  CHECK_THROWS_WITH_AS(deform::compute_heat_weights(model.mesh, model.skeleton, o),
                       doctest::Contains("smoothing_iterations"), deform::Error);
}

TEST_CASE("weight tools refuse weights that are negative, not finite or inconsistent") {
  for (float bad : {-0.5f, NAN, INFINITY}) {
    SkinWeights w;
    const std::vector<std::uint16_t> b = {0, 1};
    const std::vector<float> v = {0.5f, 0.5f};
    deform::append_influences(w, b, v);
    deform::append_influences(w, b, v);
    w.weights[1][1] = bad;
    CHECK_THROWS_WITH_AS(deform::normalize_weights(w), doctest::Contains("point 1: weight"), deform::Error);
    CHECK_THROWS_AS(deform::prune_weights(w, 0.1f), deform::Error);
    CHECK_THROWS_AS(deform::limit_influences(w, 1), deform::Error);
  }
  SkinWeights w;
  const std::vector<std::uint16_t> b = {0};
  const std::vector<float> v = {1.0f};
  deform::append_influences(w, b, v);
  w.weights.push_back(glm::vec4(1, 0, 0, 0));  // a weight slot without its bone slot
  CHECK_THROWS_WITH_AS(deform::normalize_weights(w), doctest::Contains("different number"), deform::Error);
}
