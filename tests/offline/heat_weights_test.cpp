// Volumetric weights: bone heat (heat_weights.hpp) and geodesic voxel (voxel_weights.hpp) weights on a two-bone
// cylinder (monotone along the axis, sums of 1), a hand resting against a thigh (where distance weights bind the
// hand to the leg and these do not), a hand bone parented elsewhere at the end of the forearm (the points behind it
// left to the forearm, the two bones' weights shared over a narrow band at the wrist), points equidistant from two
// bones (weighted alike whatever the bones' numbering), islands no bone sees or reaches, bones with no vertex, points
// outside every triangle, the deforming mask, invalid options.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "deform/offline/heat_weights.hpp"
#include "deform/offline/voxel_weights.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
using deform::Bone;
using deform::Mesh;
using deform::Skeleton;
using deform::SkinWeights;

namespace {

Bone bone(std::int32_t parent, glm::vec3 translation, std::string name = {}) {
  Bone b;
  b.name = std::move(name);
  b.parent = parent;
  b.bind_translation = translation;
  return b;
}

Skeleton make_skeleton(std::vector<Bone> bones) {
  for (std::size_t i = 1; i < bones.size(); ++i)
    bones[static_cast<std::size_t>(bones[i].parent)].children.push_back(static_cast<std::int32_t>(i));
  return Skeleton(std::move(bones));
}

// Appends a closed cylinder along +Y (axis through `base`, `rings` rings of `sides` points from base.y to base.y +
// height, a centre point on each cap) as its own island. Render vertex = point.
void add_cylinder(Mesh& mesh, glm::vec3 base, float radius, float height, int rings = 21, int sides = 12) {
  const auto first = static_cast<std::uint32_t>(mesh.positions.size());
  auto index = [&](int ring, int side) { return first + static_cast<std::uint32_t>(ring * sides + (side % sides)); };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < sides; ++s) {
      const float angle = 2.0f * 3.14159265f * static_cast<float>(s) / static_cast<float>(sides);
      const float y = height * static_cast<float>(r) / static_cast<float>(rings - 1);
      mesh.positions.push_back(base + glm::vec3(radius * std::cos(angle), y, radius * std::sin(angle)));
    }
  const auto bottom = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.positions.push_back(base);
  const auto top = bottom + 1;
  mesh.positions.push_back(base + glm::vec3(0.0f, height, 0.0f));
  auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    mesh.triangles.insert(mesh.triangles.end(), {a, b, c});
  };
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < sides; ++s) {
      triangle(index(r, s), index(r + 1, s), index(r + 1, s + 1));
      triangle(index(r, s), index(r + 1, s + 1), index(r, s + 1));
    }
  for (int s = 0; s < sides; ++s) {
    triangle(bottom, index(0, s), index(0, s + 1));
    triangle(top, index(rings - 1, s + 1), index(rings - 1, s));
  }
  while (mesh.vertex_point.size() < mesh.positions.size())
    mesh.vertex_point.push_back(static_cast<std::uint32_t>(mesh.vertex_point.size()));
}

// Appends a closed axis-aligned box (8 points, 12 triangles) as its own island.
void add_box(Mesh& mesh, glm::vec3 min, glm::vec3 max) {
  const auto f = static_cast<std::uint32_t>(mesh.positions.size());
  for (int i = 0; i < 8; ++i)
    mesh.positions.push_back({(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z});
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    mesh.triangles.insert(mesh.triangles.end(), {f + q[0], f + q[1], f + q[2], f + q[0], f + q[2], f + q[3]});
  while (mesh.vertex_point.size() < mesh.positions.size())
    mesh.vertex_point.push_back(static_cast<std::uint32_t>(mesh.vertex_point.size()));
}

float weight_of(const SkinWeights& w, std::size_t point, int bone_id) {
  for (int k = 0; k < 4; ++k)
    if (w.weights[point][k] > 0.0f && w.bones[point][k] == bone_id) return w.weights[point][k];
  return 0.0f;
}

// The .skw contract: normalised, strongest first, at most `most` used, unused slots (bone 0, weight 0).
void check_contract(const SkinWeights& w, std::size_t points, std::size_t bones, int most = 4) {
  REQUIRE(w.size() == points);
  for (std::size_t i = 0; i < points; ++i) {
    float sum = 0.0f;
    int used = 0;
    for (int k = 0; k < 4; ++k) {
      const float x = w.weights[i][k];
      REQUIRE(x >= 0.0f);
      REQUIRE(w.bones[i][k] < bones);
      if (k > 0) REQUIRE(x <= w.weights[i][k - 1]);
      if (x == 0.0f) REQUIRE(w.bones[i][k] == 0);
      used += x > 0.0f ? 1 : 0;
      sum += x;
    }
    REQUIRE(used >= 1);
    REQUIRE(used <= most);
    REQUIRE(std::abs(sum - 1.0f) <= 1e-5f);
  }
}

bool mentions(const std::vector<std::string>& warnings, const std::string& text) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

// Two bones along +Y: "lower" from y = 0 to 1, "upper" from 1 on (a leaf, to y = 2).
Skeleton two_bones() { return make_skeleton({bone(-1, {0, 0, 0}, "lower"), bone(0, {0, 1, 0}, "upper")}); }

}  // namespace

TEST_CASE("heat weights on a two-bone cylinder: sums of 1, monotone along the axis, each end on its bone") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = two_bones();
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton);
  check_contract(r.weights, mesh.point_count(), 2);
  CHECK(r.warnings.empty());
  // Along the axis the upper bone's weight never falls (per side, ring by ring), and the ends are rigid.
  const int rings = 21, sides = 12;
  for (int s = 0; s < sides; ++s) {
    float previous = -1.0f;
    for (int ring = 0; ring < rings; ++ring) {
      const float w = weight_of(r.weights, static_cast<std::size_t>(ring * sides + s), 1);
      CHECK(w >= previous - 1e-5f);
      previous = w;
    }
  }
  CHECK(weight_of(r.weights, 0, 0) > 0.95f);                                              // y = 0
  CHECK(weight_of(r.weights, static_cast<std::size_t>((rings - 1) * sides), 1) > 0.95f);  // y = 2
  // Symmetric about the joint: the ring at y = 1 is shared about half and half.
  const float middle = weight_of(r.weights, static_cast<std::size_t>(10 * sides), 1);
  CHECK(middle > 0.3f);
  CHECK(middle < 0.7f);
}

TEST_CASE("heat weights: a hand resting against a thigh keeps its arm's weights (distance weights do not)") {
  // Pelvis at (0, 1.5, 0); a thin leg (thigh, shin) at x = 0.3; an arm hanging at x = 0.51 whose fat hand (radius
  // 0.12) rests 3 cm from the thigh (radius 0.06): the hand's inner side is nearer the thigh's bone than its own.
  const Skeleton skeleton = make_skeleton({bone(-1, {0, 1.5f, 0}, "pelvis"), bone(0, {0.3f, -0.5f, 0}, "thigh"),
                                           bone(1, {0, -0.5f, 0}, "shin"), bone(0, {0.51f, -0.05f, 0}, "forearm"),
                                           bone(3, {0, -0.5f, 0}, "hand")});
  Mesh mesh;
  add_cylinder(mesh, {0.3f, 0.0f, 0}, 0.06f, 1.0f);    // leg
  add_cylinder(mesh, {0.51f, 0.95f, 0}, 0.04f, 0.5f);  // forearm
  const std::size_t hand_first = mesh.point_count();
  add_cylinder(mesh, {0.51f, 0.65f, 0}, 0.12f, 0.3f);  // hand
  const std::size_t hand_end = mesh.point_count();

  auto leg_weight = [&](const SkinWeights& w) {
    float most = 0.0f;
    for (std::size_t i = hand_first; i < hand_end; ++i) most = std::max(most, weight_of(w, i, 1) + weight_of(w, i, 2));
    return most;
  };
  const SkinWeights distance = deform::compute_automatic_weights(mesh, skeleton);
  CHECK(leg_weight(distance) > 0.4f);  // the failure heat weights fix: about half the hand's weight on the leg
  const deform::WeightsResult heat = deform::compute_heat_weights(mesh, skeleton);
  check_contract(heat.weights, mesh.point_count(), 5);
  CHECK(leg_weight(heat.weights) == 0.0f);
  // And the leg keeps its own weights.
  for (std::size_t i = 0; i < hand_first / 2; ++i)
    CHECK(weight_of(heat.weights, i, 1) + weight_of(heat.weights, i, 2) + weight_of(heat.weights, i, 0) > 0.99f);
  // Geodesic voxel weights: the path from the thigh into the hand goes through the pelvis and down the arm.
  const deform::WeightsResult voxel = deform::compute_voxel_weights(mesh, skeleton);
  check_contract(voxel.weights, mesh.point_count(), 5);
  CHECK(leg_weight(voxel.weights) == 0.0f);
}

TEST_CASE("heat weights: more than four influences on request, in SkinWeights' extras") {
  // A cylinder on a chain of eight short bones: a point sees several, and with max_influences 8 keeps them all.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.3f, 2.0f, 41);
  std::vector<Bone> bones = {bone(-1, {0, 0, 0}, "b0")};
  for (int b = 1; b < 8; ++b) bones.push_back(bone(b - 1, {0, 0.25f, 0}, "b" + std::to_string(b)));
  const Skeleton skeleton = make_skeleton(bones);
  deform::HeatWeightsOptions o;
  const deform::WeightsResult four = deform::compute_heat_weights(mesh, skeleton, o);
  CHECK_FALSE(four.weights.has_extra());
  o.max_influences = 8;
  const deform::WeightsResult eight = deform::compute_heat_weights(mesh, skeleton, o);
  REQUIRE(eight.weights.has_extra());
  REQUIRE(eight.weights.extra_offsets.size() == eight.weights.extra_points.size() + 1);
  std::size_t most = 0;
  for (std::size_t p = 0; p < mesh.point_count(); ++p) {
    CAPTURE(p);
    const std::size_t count = deform::influence_count(eight.weights, p);
    most = std::max(most, count);
    CHECK(count <= 8);
    float sum = 0.0f, weakest_slot = 1.0f;
    for (int k = 0; k < 4; ++k) {
      sum += eight.weights.weights[p][k];
      if (eight.weights.weights[p][k] > 0.0f) weakest_slot = std::min(weakest_slot, eight.weights.weights[p][k]);
    }
    for (std::size_t j = 0; j < eight.weights.extra_points.size(); ++j) {
      if (eight.weights.extra_points[j] != p) continue;
      for (std::uint32_t e = eight.weights.extra_offsets[j]; e < eight.weights.extra_offsets[j + 1]; ++e) {
        sum += eight.weights.extra_weights[e];
        CHECK(eight.weights.extra_weights[e] <= weakest_slot);  // the slots hold the strongest four
      }
    }
    CHECK(sum == doctest::Approx(1.0f).epsilon(1e-5));
    CHECK(eight.weights.bones[p][0] == four.weights.bones[p][0]);  // the same strongest bone either way
  }
  CHECK(most > 4);
  o.max_influences = deform::max_requested_influences + 1;
  CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
}

TEST_CASE("heat weights: a bone beside the surface does not heat it, whichever way the triangles wind") {
  // A body (cylinder of radius 0.2 on lower -> upper) and a bone 'outside' of another part, running 0.1 beside the
  // body's surface: nearer to the body's points there than the body's own bones, and nothing between. Only bones
  // behind the surface heat it, so 'outside' gets (almost) nothing; before that rule it took the body's side.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = make_skeleton({bone(-1, {0, 0, 0}, "lower"), bone(0, {0, 1, 0}, "upper"),
                                           bone(1, {0.3f, -0.2f, 0}, "outside"), bone(2, {0, 0.4f, 0}, "end")});
  deform::HeatWeightsOptions o;
  o.deforming = {1, 1, 1, 0};
  for (const bool flipped : {false, true}) {
    CAPTURE(flipped);
    Mesh m = mesh;
    if (flipped)
      for (std::size_t t = 0; t < m.triangles.size(); t += 3) std::swap(m.triangles[t + 1], m.triangles[t + 2]);
    const deform::WeightsResult r = deform::compute_heat_weights(m, skeleton, o);
    check_contract(r.weights, m.point_count(), 4);
    std::size_t beside = 0;
    float most = 0.0f;
    for (std::size_t i = 0; i < m.point_count(); ++i) {
      const glm::vec3 p = m.positions[i];
      if (p.x < 0.15f || std::abs(p.y - 1.0f) > 0.15f) continue;
      ++beside;
      CHECK(weight_of(r.weights, i, 2) < 0.01f);  // what diffuses from points that see it at a grazing angle
      most = std::max(most, weight_of(r.weights, i, 2));
    }
    CHECK(beside >= 6);
    MESSAGE("flipped " << flipped << ": most weight of 'outside' beside it " << most);
  }
}

TEST_CASE("heat weights: a bone straight behind the surface counts as nearer than one seen obliquely") {
  // A body (cylinder of radius 0.2 along +Y) with a bone on its axis and a second bone inside it, off the axis: from
  // the points on the +X side the second is 6% nearer but 58° off their inward normal (as a chest's points see a
  // leg's top bone beside the spine). With the paper's plain distance (oblique_penalty 0) the side bone heats them
  // and takes 0.7 of their weight; with the default penalty the axis heats them, and the side bone's weight there is
  // only what diffuses from its own side of the body.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = make_skeleton({bone(-1, {0, 0.2f, 0}, "axis"), bone(0, {0, 1.6f, 0}, "axis_end"),
                                           bone(0, {0.1f, 0.0f, 0.16f}, "side"), bone(2, {0, 1.6f, 0}, "side_end")});
  deform::HeatWeightsOptions o;
  o.deforming = {1, 0, 1, 0};
  CHECK(o.oblique_penalty == 0.3f);
  const deform::WeightsResult with = deform::compute_heat_weights(mesh, skeleton, o);
  o.oblique_penalty = 0.0f;
  const deform::WeightsResult without = deform::compute_heat_weights(mesh, skeleton, o);
  check_contract(with.weights, mesh.point_count(), 4);
  check_contract(without.weights, mesh.point_count(), 4);
  std::size_t facing_x = 0;
  for (std::size_t i = 0; i < mesh.point_count(); ++i) {
    const glm::vec3 p = mesh.positions[i];
    if (p.x < 0.19f || p.y < 0.6f || p.y > 1.4f) continue;
    ++facing_x;
    CAPTURE(i);
    CHECK(weight_of(without.weights, i, 2) > 0.65f);
    CHECK(weight_of(with.weights, i, 0) > weight_of(without.weights, i, 0) + 0.15f);
  }
  CHECK(facing_x >= 8);
}

TEST_CASE("heat weights: a bone's segment toward a child placed outside the body stops where it leaves the body") {
  // A body (lower -> upper) and an arm (upper -> arm -> hand) along +X at height 1.5, and an IK goal parented to
  // the root and placed at the hand, as rigs do (mrfixit.iqm's HandGoal under Spine1). The root's segment toward
  // the goal runs out of the body and into the arm's far end; ended where it leaves the body, it claims none of
  // the arm.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const std::size_t arm = mesh.point_count();
  add_cylinder(mesh, {0, 0, 0}, 0.15f, 1.8f);
  for (std::size_t i = arm; i < mesh.point_count(); ++i) {  // laid along +X from the body's side
    const glm::vec3 p = mesh.positions[i];
    mesh.positions[i] = {0.2f + p.y, 1.5f + p.x, p.z};
  }
  const Skeleton skeleton =
      make_skeleton({bone(-1, {0, 0, 0}, "lower"), bone(0, {0, 1, 0}, "upper"), bone(1, {0, 0.5f, 0}, "arm"),
                     bone(2, {2.0f, 0, 0}, "hand"), bone(0, {2.0f, 1.5f, 0}, "goal")});
  deform::HeatWeightsOptions o;
  o.deforming = {1, 1, 1, 1, 0};
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
  check_contract(r.weights, mesh.point_count(), 5);
  std::size_t far = 0;
  for (std::size_t i = arm; i < mesh.point_count(); ++i) {
    if (mesh.positions[i].x < 1.0f) continue;
    ++far;
    CAPTURE(i);
    CHECK(weight_of(r.weights, i, 0) == 0.0f);
    CHECK(weight_of(r.weights, i, 2) + weight_of(r.weights, i, 3) > 0.99f);
  }
  CHECK(far >= 40);
}

TEST_CASE("heat weights: a hand bone parented elsewhere and placed at the wrist leaves the forearm to the forearm") {
  // A forearm (cylinder of radius 0.2 along +Y) whose bone ends at a non-deforming wrist node at y = 1.2, and a hand
  // bone parented to the root and placed at the wrist, as an IK goal is (mrfixit.iqm's HandGoal.L/R under the
  // spine), forking to a finger up the axis and to a thumb node beside it. Its segment toward the thumb passes
  // about 0.12 from the forearm's +X points just behind the wrist, which the forearm's bone is 0.2 straight behind: the
  // hand would heat them. It continues the forearm's chain, so the points behind its head go to the forearm.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = make_skeleton({bone(-1, {0, 0, 0}, "root"), bone(0, {0, 0.2f, 0}, "forearm"),
                                           bone(1, {0, 1.0f, 0}, "wrist"), bone(0, {0, 1.2f, 0}, "hand"),
                                           bone(3, {0.17f, 0.02f, 0}, "thumb"), bone(3, {0, 0.6f, 0}, "finger")});
  deform::HeatWeightsOptions o;
  o.deforming = {0, 1, 0, 1, 0, 1};
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
  check_contract(r.weights, mesh.point_count(), 6);
  std::size_t behind = 0, past = 0;
  for (std::size_t i = 0; i < mesh.point_count(); ++i) {
    const glm::vec3 p = mesh.positions[i];
    if (p.x < 0.15f) continue;
    CAPTURE(i);
    if (p.y > 1.05f && p.y < 1.19f) {
      ++behind;
      CHECK(weight_of(r.weights, i, 1) > 0.45f);
    } else if (p.y > 1.35f) {
      ++past;
      CHECK(weight_of(r.weights, i, 1) < 0.5f);
    }
  }
  CHECK(behind >= 2);
  CHECK(past >= 10);
}

TEST_CASE("heat weights: a hand bone parented elsewhere shares the forearm's weight over a narrow band at the wrist") {
  // The forearm (bone 1, from y = 0.2 to the wrist at y = 1.2) and a hand bone parented to the root at the wrist, as
  // an IK goal is: nothing in the hierarchy bends there, so the two share their summed weight by the side of the
  // wrist, all to the forearm up to 12% of its length (0.12) behind it, all to the hand from as far past it, evenly
  // on the ring at the wrist. Heat's diffusion alone spreads the hand over the forearm's end and the forearm over
  // the hand (a tenth and more at a ring's distance).
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton =
      make_skeleton({bone(-1, {0, 0, 0}, "root"), bone(0, {0, 0.2f, 0}, "forearm"), bone(1, {0, 1.0f, 0}, "wrist"),
                     bone(0, {0, 1.2f, 0}, "hand"), bone(3, {0, 0.6f, 0}, "finger")});
  deform::HeatWeightsOptions o;
  o.deforming = {0, 1, 0, 1, 1};
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
  check_contract(r.weights, mesh.point_count(), 5);
  const int sides = 12;
  std::size_t behind = 0, past = 0;
  for (std::size_t i = 0; i < mesh.point_count(); ++i) {
    const float y = mesh.positions[i].y;
    CAPTURE(i);
    if (y > 0.85f && y < 1.09f) {  // the rings at 0.9 and 1.0
      ++behind;
      CHECK(weight_of(r.weights, i, 3) == 0.0f);
      CHECK(weight_of(r.weights, i, 1) > 0.9f);
    } else if (y > 1.31f && y < 1.55f) {  // the rings at 1.4 and 1.5
      ++past;
      CHECK(weight_of(r.weights, i, 1) == 0.0f);
    }
  }
  CHECK(behind == 2 * sides);
  CHECK(past == 2 * sides);
  for (int s = 0; s < sides; ++s) {  // the ring at the wrist, y = 1.2
    const auto i = static_cast<std::size_t>(12 * sides + s);
    CAPTURE(i);
    CHECK(weight_of(r.weights, i, 1) > 0.2f);
    CHECK(weight_of(r.weights, i, 1) == doctest::Approx(weight_of(r.weights, i, 3)).epsilon(0.02));
  }
}

TEST_CASE("heat weights: a hand bone that descends from the forearm through a bone of no length keeps heat's blend") {
  // As above, but the hand hangs from the forearm through a wrist node at the same place (BCN_Epileptic.X's neck sits
  // on two such bones): the chain is the forearm's own, a joint that bends, so the weights blend as heat gives them.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton =
      make_skeleton({bone(-1, {0, 0, 0}, "root"), bone(0, {0, 0.2f, 0}, "forearm"), bone(1, {0, 1.0f, 0}, "wrist"),
                     bone(2, {0, 0, 0}, "hand"), bone(3, {0, 0.6f, 0}, "finger")});
  deform::HeatWeightsOptions o;
  o.deforming = {0, 1, 0, 1, 1};
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
  check_contract(r.weights, mesh.point_count(), 5);
  const int sides = 12;
  for (int s = 0; s < sides; ++s) {
    const auto i = static_cast<std::size_t>(10 * sides + s);  // the ring at y = 1.0, behind the wrist
    const auto j = static_cast<std::size_t>(14 * sides + s);  // the ring at y = 1.4, past it
    CAPTURE(i);
    CHECK(weight_of(r.weights, i, 3) > 0.02f);
    CHECK(weight_of(r.weights, j, 1) > 0.02f);
  }
}

TEST_CASE("voxel weights on a two-bone cylinder: sums of 1, monotone along the axis, each end on its bone") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const deform::WeightsResult r = deform::compute_voxel_weights(mesh, two_bones());
  check_contract(r.weights, mesh.point_count(), 2);
  CHECK(r.warnings.empty());
  const int rings = 21, sides = 12;
  for (int s = 0; s < sides; ++s) {
    float previous = -1.0f;
    for (int ring = 0; ring < rings; ++ring) {
      const float w = weight_of(r.weights, static_cast<std::size_t>(ring * sides + s), 1);
      CHECK(w >= previous - 1e-5f);
      previous = w;
    }
  }
  CHECK(weight_of(r.weights, 0, 0) > 0.95f);
  CHECK(weight_of(r.weights, static_cast<std::size_t>((rings - 1) * sides), 1) > 0.95f);
}

TEST_CASE("voxel weights: a piece no bone reaches through the volume is bound rigidly and reported") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const std::size_t box = mesh.point_count();
  add_box(mesh, {1.0f, 1.2f, -0.1f}, {1.2f, 1.4f, 0.1f});
  const Skeleton skeleton =
      make_skeleton({bone(-1, {0, 0, 0}, "lower"), bone(0, {0, 1, 0}, "upper"), bone(0, {0, 0, 40}, "far")});
  deform::VoxelWeightsOptions o;
  o.resolution = 64;
  const deform::WeightsResult r = deform::compute_voxel_weights(mesh, skeleton, o);
  check_contract(r.weights, mesh.point_count(), 3);
  REQUIRE(r.warnings.size() == 2);
  CHECK(r.warnings[0] == "8 points (the first: point " + std::to_string(box) +
                             ") reached by no bone through the volume: bound rigidly to the nearest bone");
  CHECK(r.warnings[1] == "bone 'far' (id 2) gets no vertex");
  for (std::size_t i = box; i < box + 8; ++i) CHECK(r.weights.weights[i][0] == 1.0f);
  o.resolution = 4;
  CHECK_THROWS_AS(deform::compute_voxel_weights(mesh, skeleton, o), deform::Error);
}

TEST_CASE("voxel weights refuse a box they cannot divide: no size, or so large that distances overflow") {
  const auto message = [](const Mesh& mesh) {
    try {
      (void)deform::compute_voxel_weights(mesh, two_bones());
    } catch (const deform::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Mesh point;  // every point at one place: a box of no size (it was a grid of 1e-32 cells, a bone 2^31 steps long)
  add_box(point, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f});
  CHECK(message(point).find("no size") != std::string::npos);
  Mesh huge;  // ±3e38: the box's size is infinite (it escaped as std::length_error)
  add_box(huge, {-3e38f, -3e38f, -3e38f}, {3e38f, 3e38f, 3e38f});
  CHECK(message(huge).find("too large") != std::string::npos);
  Mesh far;  // finite, but squared distances overflow
  add_box(far, {1e20f, 0.0f, 0.0f}, {2e20f, 1.0f, 1.0f});
  CHECK(message(far).find("too large") != std::string::npos);
  Mesh small_far_away;  // a millimetre box a kilometre out is still voxelised
  add_box(small_far_away, {1000.0f, 0.0f, 0.0f}, {1000.001f, 0.001f, 0.001f});
  CHECK(message(small_far_away) == "no error");
}

TEST_CASE("heat weights: islands the body hides from every bone are named, and weighted past their own surface") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  // A closed shell around a small box, beside the cylinder: the cylinder hides its bones from both.
  const std::size_t shell = mesh.point_count();
  add_box(mesh, {0.5f, 0.5f, -0.5f}, {1.5f, 1.5f, 0.5f});
  const std::size_t inner = mesh.point_count();
  add_box(mesh, {0.9f, 0.9f, -0.1f}, {1.1f, 1.1f, 0.1f});
  const Skeleton skeleton = two_bones();
  SUBCASE("by default they look again past their own triangles") {
    const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton);
    check_contract(r.weights, mesh.point_count(), 2);
    REQUIRE(r.warnings.size() == 2);
    CHECK(r.warnings[0] == "island of 8 points (from point " + std::to_string(shell) +
                               ", around (1, 1, 0)) sees no bone past the rest of the mesh: weighted by the bones it "
                               "sees past its own triangles");
    CHECK(mentions(r.warnings, "island of 8 points (from point " + std::to_string(inner)));
    // The shell takes weight from both bones (its lower corners more from the lower one).
    CHECK(weight_of(r.weights, shell, 0) > weight_of(r.weights, shell + 2, 0));
  }
  SUBCASE("island_visibility = false: bound rigidly to the nearest bone, and named") {
    deform::HeatWeightsOptions o;
    o.island_visibility = false;
    const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
    check_contract(r.weights, mesh.point_count(), 2);
    REQUIRE(r.warnings.size() == 2);
    CHECK(r.warnings[1] == "island of 8 points (from point " + std::to_string(inner) +
                               ", around (1, 1, 0)) sees no bone: bound rigidly to the nearest, bone 'lower' (id 0)");
    CHECK(mentions(r.warnings, "sees no bone: bound rigidly to the nearest, bone '"));
    for (std::size_t i = shell; i < shell + 16; ++i) CHECK(r.weights.weights[i][0] == 1.0f);
    for (std::size_t i = inner; i < inner + 8; ++i) CHECK(r.weights.bones[i][0] == 0);  // 4 votes each: the lower id
  }
}

TEST_CASE("heat weights: a point equidistant from two bones does not depend on their numbering") {
  // A cylinder along +Y and bones that meet at y = 1: the ring through the joint is equally near both (their
  // nearest points are the joint itself), as the points behind an elbow or a heel are. Numbered either way, each
  // bone gets the same weights; taking the first bone in id order at a tie gave the ring to whichever came first.
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  // The weight of the bone named "up" at every point; bone 0 is a non-deforming root at y = 1.
  const auto up_weights = [&](std::vector<Bone> bones) {
    const Skeleton skeleton = make_skeleton(std::move(bones));
    deform::HeatWeightsOptions o;
    o.deforming.assign(skeleton.bone_count(), 1);
    o.deforming[0] = 0;
    for (std::size_t b = 0; b < skeleton.bone_count(); ++b)
      if (skeleton.bones()[b].name.rfind("end", 0) == 0) o.deforming[b] = 0;
    const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
    check_contract(r.weights, mesh.point_count(), skeleton.bone_count());
    int up = -1;
    for (std::size_t b = 0; b < skeleton.bone_count(); ++b)
      if (skeleton.bones()[b].name == "up") up = static_cast<int>(b);
    std::vector<float> w;
    for (std::size_t p = 0; p < mesh.point_count(); ++p) w.push_back(weight_of(r.weights, p, up));
    return w;
  };
  const auto ring = [](const std::vector<float>& w, int side) { return w[static_cast<std::size_t>(10 * 12 + side)]; };
  SUBCASE("two siblings from one joint, down to y = 0 and up to y = 2, share the ring half and half") {
    const std::vector<float> a =
        up_weights({bone(-1, {0, 1, 0}, "joint"), bone(0, {0, 0, 0}, "down"), bone(0, {0, 0, 0}, "up"),
                    bone(1, {0, -1, 0}, "end1"), bone(2, {0, 1, 0}, "end2")});
    const std::vector<float> b =
        up_weights({bone(-1, {0, 1, 0}, "joint"), bone(0, {0, 0, 0}, "up"), bone(0, {0, 0, 0}, "down"),
                    bone(1, {0, 1, 0}, "end1"), bone(2, {0, -1, 0}, "end2")});
    for (std::size_t p = 0; p < a.size(); ++p) CHECK(a[p] == doctest::Approx(b[p]).epsilon(1e-5));
    for (int side = 0; side < 12; ++side) {
      CHECK(ring(a, side) > 0.4f);
      CHECK(ring(a, side) < 0.6f);
    }
  }
  SUBCASE("a parent and its child, the child listed first or last: the ring behind the joint follows the parent") {
    // "down" from y = 0 to its child "up" at y = 1 (a leaf, to the cylinder's top), under a root at the origin.
    const std::vector<float> a =
        up_weights({bone(-1, {0, 0, 0}, "root"), bone(0, {0, 0, 0}, "down"), bone(1, {0, 1, 0}, "up")});
    const std::vector<float> b =
        up_weights({bone(-1, {0, 0, 0}, "root"), bone(2, {0, 1, 0}, "up"), bone(0, {0, 0, 0}, "down")});
    for (std::size_t p = 0; p < a.size(); ++p) CHECK(a[p] == doctest::Approx(b[p]).epsilon(1e-5));
    for (int side = 0; side < 12; ++side) CHECK(ring(a, side) < 0.5f);
  }
}

TEST_CASE("heat weights: a bone with no vertex is named; a point in no triangle gets a weight") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  mesh.positions.push_back({0.0f, 3.0f, 0.0f});  // in no triangle, seeing the upper bone
  mesh.vertex_point.push_back(static_cast<std::uint32_t>(mesh.vertex_point.size()));
  const Skeleton skeleton =
      make_skeleton({bone(-1, {0, 0, 0}, "lower"), bone(0, {0, 1, 0}, "upper"), bone(0, {0, 0, 40}, "far")});
  const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton);
  check_contract(r.weights, mesh.point_count(), 3);
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0] == "bone 'far' (id 2) gets no vertex");
  CHECK(weight_of(r.weights, mesh.point_count() - 1, 1) == 1.0f);
  CHECK(deform::bones_without_vertices(r.weights, skeleton, {1, 1, 0}).empty());
}

TEST_CASE("heat weights: points welded across a seam, the deforming mask, max_influences, invalid options") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = two_bones();
  SUBCASE("a seam of duplicated points is one surface: both copies get the same weights") {
    Mesh split = mesh;
    const std::size_t copy = split.positions.size();
    split.positions.push_back(split.positions[10 * 12]);
    split.vertex_point.push_back(static_cast<std::uint32_t>(copy));
    for (std::size_t t = 0; t < split.triangles.size(); t += 3)  // the first triangle using point 120 uses the copy
      if (split.triangles[t] == 10 * 12) {
        split.triangles[t] = static_cast<std::uint32_t>(copy);
        break;
      }
    const deform::WeightsResult r = deform::compute_heat_weights(split, skeleton);
    CHECK(r.weights.weights[copy] == r.weights.weights[10 * 12]);
    CHECK(r.weights.bones[copy] == r.weights.bones[10 * 12]);
  }
  SUBCASE("a bone that does not deform gets nothing and is not reported") {
    deform::HeatWeightsOptions o;
    o.deforming = {1, 0};
    const deform::WeightsResult r = deform::compute_heat_weights(mesh, skeleton, o);
    for (std::size_t i = 0; i < mesh.point_count(); ++i) CHECK(weight_of(r.weights, i, 0) == 1.0f);
    CHECK(r.warnings.empty());
  }
  SUBCASE("one influence") {
    deform::HeatWeightsOptions o;
    o.max_influences = 1;
    check_contract(deform::compute_heat_weights(mesh, skeleton, o).weights, mesh.point_count(), 2, 1);
  }
  SUBCASE("invalid options and input throw") {
    deform::HeatWeightsOptions o;
    o.max_influences = 0;
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    o = {};
    o.heat = 0.0f;
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    o = {};
    o.oblique_penalty = -0.1f;
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    o.oblique_penalty = NAN;
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    o = {};
    o.deforming = {0, 0};
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    o.deforming = {1};
    CHECK_THROWS_AS(deform::compute_heat_weights(mesh, skeleton, o), deform::Error);
    Mesh bad = mesh;
    bad.positions[3].x = NAN;
    CHECK_THROWS_AS(deform::compute_heat_weights(bad, skeleton), deform::Error);
    bad = mesh;
    bad.triangles[0] = 100000;
    CHECK_THROWS_AS(deform::compute_heat_weights(bad, skeleton), deform::Error);
  }
  SUBCASE("an empty mesh gives no weights") {
    CHECK(deform::compute_heat_weights(Mesh{}, skeleton).weights.size() == 0);
  }
}

TEST_CASE("distance weights honour the deforming mask") {
  Mesh mesh;
  add_cylinder(mesh, {0, 0, 0}, 0.2f, 2.0f);
  const Skeleton skeleton = make_skeleton({bone(-1, {0, 0, 0}), bone(0, {0, 1, 0}), bone(1, {0, 0.5f, 0})});
  deform::AutoWeightsOptions o;
  o.deforming = {1, 0, 1};
  const SkinWeights w = deform::compute_automatic_weights(mesh, skeleton, o);
  for (std::size_t i = 0; i < mesh.point_count(); ++i) CHECK(weight_of(w, i, 1) == 0.0f);
  o.deforming = {0, 0, 0};
  CHECK_THROWS_AS(deform::compute_automatic_weights(mesh, skeleton, o), deform::Error);
}
