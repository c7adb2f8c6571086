// The deformer hierarchy on a synthetic limb: a stretched mid-chain lattice stretches its part, carries what lies
// below it with no seam, follows the bones, composes with lattices below it, and matches a plain reference.
#include "deform/offline/hierarchy_binding.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/skeleton.hpp"
#include <doctest/doctest.h>

#include <string>

#include <algorithm>
#include <random>
#include <cmath>
#include <numbers>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

using deform::DeformerHierarchy;
using deform::LatticeSpec;

namespace {

// A straight limb along +Y: root (0) at the origin, then bones 1, 2, 3 one unit apart, and bone 4, a sibling of bone 1
// at the same place (a "torso" part overlapping the limb's lattice).
deform::Skeleton limb_skeleton() {
  std::vector<deform::Bone> bones(5);
  bones[0] = {"root", -1, {1, 4}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  bones[1] = {"upper", 0, {2}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  bones[2] = {"fore", 1, {3}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  bones[3] = {"hand", 2, {}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  bones[4] = {"torso", 0, {}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  return deform::Skeleton(bones);
}

constexpr int ring_points = 8;
constexpr int rings = 81;  // y = 0, 0.05, ..., 4

struct Limb {
  deform::Skeleton skeleton = limb_skeleton();
  std::vector<glm::vec3> points;
  deform::SkinWeights weights;
  std::size_t intruder = 0;  // a torso point inside the upper-arm... the "upper" lattice's box
};

// A cylinder of radius 0.2 along the limb, rigidly weighted per unit of height with linear blends ±0.1 around each
// joint, plus one point of the torso bone inside the first lattice's box.
Limb make_limb() {
  Limb limb;
  for (int r = 0; r < rings; ++r) {
    const float y = 0.05f * float(r);
    for (int a = 0; a < ring_points; ++a) {
      const float angle = 2.0f * float(std::numbers::pi) * float(a) / ring_points;
      limb.points.emplace_back(0.2f * std::cos(angle), y, 0.2f * std::sin(angle));
      const int below = std::clamp(int(std::floor(y)), 0, 3);
      float upper_weight = 0.0f;  // weight of bone below+1 near the joint above
      const float to_joint = y - float(below + 1);
      if (below < 3 && to_joint > -0.1f) upper_weight = (to_joint + 0.1f) / 0.2f;
      const float lower_weight_from_joint_below =
          below >= 1 && y - float(below) < 0.1f ? (0.1f - (y - float(below))) / 0.2f : 0.0f;
      glm::u16vec4 ids(std::uint16_t(below), 0, 0, 0);
      glm::vec4 w(1.0f - upper_weight - lower_weight_from_joint_below, 0.0f, 0.0f, 0.0f);
      if (upper_weight > 0.0f) ids[1] = std::uint16_t(below + 1), w[1] = upper_weight;
      if (lower_weight_from_joint_below > 0.0f) ids[2] = std::uint16_t(below - 1), w[2] = lower_weight_from_joint_below;
      limb.weights.bones.push_back(ids);
      limb.weights.weights.push_back(w);
    }
  }
  limb.intruder = limb.points.size();
  limb.points.emplace_back(0.05f, 1.5f, 0.0f);
  limb.weights.bones.emplace_back(4, 0, 0, 0);
  limb.weights.weights.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
  return limb;
}

// Skin weight of point p on the subtree of `bone` (bones 1..3 form a chain, 4 is apart).
float subtree_weight(const Limb& limb, std::size_t p, int bone) {
  float sum = 0.0f;
  for (int s = 0; s < 4; ++s) {
    const int b = limb.weights.bones[p][s];
    if (b >= bone && b <= 3 && bone >= 1) sum += limb.weights.weights[p][s];
  }
  return sum;
}

// The plain stretch (no volume compensation), which the tests below compare with references; the stretch shape has
// its own tests at the end.
LatticeSpec spec_on(const char* name, std::int32_t bone, float zeta = 1.0f) {
  LatticeSpec spec;
  spec.name = name;
  spec.bone = bone;
  spec.elastic.oscillator = {400.0f, zeta, 1.0f};
  spec.shape.volume = 0.0f;
  return spec;
}

// Plain LBS, the reference the hierarchy is applied after.
std::vector<glm::vec3> skin(const Limb& limb, std::span<const glm::mat4> world) {
  std::vector<glm::mat4> palette(world.size());
  for (std::size_t b = 0; b < world.size(); ++b) palette[b] = world[b] * limb.skeleton.inverse_bind_world()[b];
  std::vector<glm::vec3> out(limb.points.size());
  for (std::size_t p = 0; p < out.size(); ++p) {
    glm::vec3 sum(0.0f);
    for (int s = 0; s < 4; ++s) {
      sum +=
          limb.weights.weights[p][s] * glm::vec3(palette[limb.weights.bones[p][s]] * glm::vec4(limb.points[p], 1.0f));
    }
    out[p] = sum;
  }
  return out;
}

std::vector<glm::mat4> world_of(const deform::Skeleton& skeleton, const deform::Pose& pose) {
  std::vector<glm::mat4> world(skeleton.bone_count());
  deform::LocalToWorldJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  REQUIRE(fk.run());
  return world;
}

void settle(DeformerHierarchy& h) {
  for (int i = 0; i < 100; ++i) REQUIRE(h.step(0.1f));
}

// Displacements the hierarchy adds to the skinned points.
std::vector<glm::vec3> displacements(DeformerHierarchy& h, const std::vector<glm::vec3>& skinned,
                                     std::span<const glm::mat4> world) {
  REQUIRE(h.update(world));
  std::vector<glm::vec3> out = skinned;
  REQUIRE(h.apply(out));
  for (std::size_t p = 0; p < out.size(); ++p) out[p] -= skinned[p];
  return out;
}

double bernstein(int n, int i, double t) {
  double c = 1.0;
  for (int k = 1; k <= i; ++k) c = c * double(n - i + k) / double(k);
  return c * std::pow(t, i) * std::pow(1.0 - t, n - i);
}

}  // namespace

TEST_CASE("a stretched mid-chain lattice stretches its part and carries the hand, with no seam") {
  const Limb limb = make_limb();
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("fore", 2)});
  CHECK(h.length(0) == doctest::Approx(1.0f));
  CHECK(h.bound_count(0) > 0);
  CHECK(h.carried_count(0) > 0);
  const float s = 0.6f;
  REQUIRE(h.set_stretch_target(0, s));
  settle(h);
  CHECK(h.stretch(0) == doctest::Approx(s).epsilon(1e-5));
  const auto world = world_of(limb.skeleton, limb.skeleton.bind_pose());
  const auto skinned = skin(limb, world);
  const auto d = displacements(h, skinned, world);
  for (std::size_t p = 0; p < limb.points.size(); ++p) {
    CAPTURE(p);
    const float y = limb.points[p].y;
    const float along = std::clamp(y - 2.0f, 0.0f, 1.0f);  // u of the "fore" lattice, clamped
    const float w = p == limb.intruder ? 0.0f : subtree_weight(limb, p, 2);
    CHECK(glm::length(d[p] - glm::vec3(0.0f, w * s * along, 0.0f)) < 1e-5f);
  }
  // The hand (bone 3) follows: its head moves by the whole stretch.
  CHECK(glm::length(h.point_displacement(3, glm::vec3(0, 3, 0)) - glm::vec3(0, s, 0)) < 1e-5f);
  CHECK(glm::length(h.point_displacement(1, glm::vec3(0, 1, 0))) < 1e-7f);

  // Continuity: along every vertical edge (0.05 long) the displacement changes by at most the stretch gradient
  // s / length, steepened by half where the skin weights blend (d = w·s·u, |w'| = 5 over u <= 0.1), times the edge
  // length. Without the hierarchy (fig. 53) the hand stays behind and the border tears by the whole stretch.
  const auto largest_jump = [&](const std::vector<glm::vec3>& field) {
    float jump = 0.0f;
    for (int r = 0; r + 1 < rings; ++r)
      for (int a = 0; a < ring_points; ++a)
        jump = std::max(
            jump, glm::length(field[std::size_t((r + 1) * ring_points + a)] - field[std::size_t(r * ring_points + a)]));
    return jump;
  };
  CHECK(largest_jump(d) <= 1.5f * s * 0.05f + 1e-6f);
  LatticeSpec torn = spec_on("fore", 2);
  torn.carry_descendants = false;
  DeformerHierarchy without = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {torn});
  without.set_stretch_target(0, s);
  settle(without);
  CHECK(without.carried_count(0) == 0);
  CHECK(largest_jump(displacements(without, skinned, world)) > 0.9f * s);
}

TEST_CASE("points the lattice does not select are never moved, even inside its box (fig. 52)") {
  const Limb limb = make_limb();
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("upper", 1)});
  h.set_stretch_target(0, 0.5f);
  settle(h);
  const auto world = world_of(limb.skeleton, limb.skeleton.bind_pose());
  const auto skinned = skin(limb, world);
  std::vector<glm::vec3> out = skinned;
  REQUIRE(h.update(world));
  REQUIRE(h.apply(out));
  CHECK(out[limb.intruder] == skinned[limb.intruder]);               // bit for bit
  CHECK(out[0] == skinned[0]);                                       // below the lattice
  CHECK(out[out.size() - 2].y > skinned[out.size() - 2].y + 0.49f);  // the hand's tip is carried
}

TEST_CASE("the stretch follows the bones: rotate the limb and the displacement turns with it") {
  const Limb limb = make_limb();
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("fore", 2)});
  h.set_stretch_target(0, 0.4f);
  settle(h);
  deform::Pose pose = limb.skeleton.bind_pose();
  limb.skeleton.set_euler(pose, 0, glm::vec3(0.0f, 0.0f, 90.0f), false);  // +Y turns to -X
  limb.skeleton.set_euler(pose, 2, glm::vec3(30.0f, 0.0f, 0.0f), false);
  const auto world = world_of(limb.skeleton, pose);
  const glm::vec3 direction = glm::normalize(glm::mat3(world[2]) * glm::vec3(0, 1, 0));
  const auto d = displacements(h, skin(limb, world), world);
  for (std::size_t p = 0; p < limb.points.size(); ++p) {
    if (limb.points[p].y < 3.1f) continue;  // the hand, rigidly carried
    CHECK(glm::length(d[p] - 0.4f * direction) < 1e-5f);
  }
  CHECK(glm::length(h.point_displacement(3, glm::vec3(0, 3, 0)) - 0.4f * direction) < 1e-5f);
}

TEST_CASE("lattices compose down the hierarchy: parent, carried control points, summed stretch") {
  const Limb limb = make_limb();
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights,
                                               {spec_on("upper", 1), spec_on("fore", 2), spec_on("hand", 3)});
  CHECK(h.parent(0) == -1);
  CHECK(h.parent(1) == 0);
  CHECK(h.parent(2) == 1);
  CHECK(h.find("fore") == 1);
  CHECK(h.find("nope") == -1);
  h.set_stretch_target(0, 0.3f);
  h.set_stretch_target(1, 0.5f);
  settle(h);
  const auto world = world_of(limb.skeleton, limb.skeleton.bind_pose());
  const auto d = displacements(h, skin(limb, world), world);
  for (std::size_t p = 0; p < limb.points.size(); ++p) {
    if (limb.points[p].y > 3.1f && p != limb.intruder) CHECK(glm::length(d[p] - glm::vec3(0, 0.8f, 0)) < 1e-5f);
  }
  // The hand lattice is drawn where the two stretches carry it.
  const deform::BezierLattice& rest = h.rest_lattice(2);
  for (std::size_t n = 0; n < rest.point_count(); ++n) {
    const glm::vec3 expected = glm::vec3(world[3] * glm::vec4(rest.control_points()[n], 1.0f)) + glm::vec3(0, 0.8f, 0);
    CHECK(glm::length(h.control_points(2)[n] - expected) < 1e-5f);
  }
  // The hand lattice is a leaf: it spans its points.
  CHECK(h.length(2) == doctest::Approx(1.0f).epsilon(1e-3));
}

TEST_CASE("apply equals a plain Bernstein reference, with springs making the lattice non-affine") {
  const Limb limb = make_limb();
  LatticeSpec spec = spec_on("fore", 2, 0.2f);
  spec.degree = glm::ivec3(3, 2, 2);
  spec.elastic.springs.structural = spec.elastic.springs.shear = spec.elastic.springs.bend = true;
  spec.elastic.springs.stiffness = 300.0f;
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec});
  h.set_stretch_target(0, 0.7f);
  for (int i = 0; i < 4; ++i) h.step(1.0f / 60.0f);
  deform::Pose pose = limb.skeleton.bind_pose();
  limb.skeleton.set_euler(pose, 1, glm::vec3(20.0f, 10.0f, -35.0f), false);
  const auto world = world_of(limb.skeleton, pose);
  const auto skinned = skin(limb, world);
  const auto d = displacements(h, skinned, world);

  const deform::BezierLattice& rest = h.rest_lattice(0);
  const glm::ivec3 degree = rest.degree();
  std::vector<glm::dvec3> delta(rest.point_count());
  glm::dvec3 far(0.0);
  for (std::size_t n = 0; n < rest.point_count(); ++n) {
    delta[n] = glm::dvec3(h.control_points(0)[n] - glm::vec3(world[2] * glm::vec4(rest.control_points()[n], 1.0f)));
  }
  bool non_affine = false;
  for (int k = 0; k <= degree.z; ++k)
    for (int j = 0; j <= degree.y; ++j) {
      far = delta[rest.index(degree.x, j, k)];
      non_affine = non_affine || glm::length(delta[rest.index(1, j, k)] - delta[rest.index(1, 0, 0)]) > 1e-4;
    }
  CHECK(non_affine);
  const glm::mat4 to_bone = limb.skeleton.inverse_bind_world()[2];
  int inside = 0, carried = 0;
  for (std::size_t p = 0; p < limb.points.size(); ++p) {
    CAPTURE(p);
    const double w = p == limb.intruder ? 0.0 : subtree_weight(limb, p, 2);
    const glm::vec3 uvw = rest.frame().to_lattice(glm::vec3(to_bone * glm::vec4(limb.points[p], 1.0f)));
    glm::dvec3 expected(0.0);
    if (w > 0.0 && uvw.x >= 1.0f) {
      expected = w * far;
      ++carried;
    } else if (w > 0.0 && glm::all(glm::greaterThanEqual(uvw, glm::vec3(0.0f))) &&
               glm::all(glm::lessThanEqual(uvw, glm::vec3(1.0f)))) {
      for (int k = 0; k <= degree.z; ++k)
        for (int j = 0; j <= degree.y; ++j)
          for (int i = 0; i <= degree.x; ++i)
            expected += delta[rest.index(i, j, k)] *
                        (bernstein(degree.x, i, uvw.x) * bernstein(degree.y, j, uvw.y) * bernstein(degree.z, k, uvw.z));
      expected *= w;
      ++inside;
    }
    CHECK(glm::length(glm::dvec3(d[p]) - expected) < 1e-5);
  }
  CHECK(inside > 100);
  CHECK(carried > 100);
}

TEST_CASE("apply is apply_carried plus the fields a caller evaluates from binding, weights and displacements") {
  const Limb limb = make_limb();
  LatticeSpec upper = spec_on("upper", 1, 0.3f), fore = spec_on("fore", 2, 0.2f), hand = spec_on("hand", 3);
  fore.degree = glm::ivec3(4, 2, 3);
  fore.elastic.springs.structural = fore.elastic.springs.shear = true;
  fore.elastic.springs.stiffness = 300.0f;
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {upper, fore, hand});
  deform::Pose pose = limb.skeleton.bind_pose();
  limb.skeleton.set_euler(pose, 1, glm::vec3(20.0f, 10.0f, -35.0f), false);
  limb.skeleton.set_euler(pose, 2, glm::vec3(-40.0f, 0.0f, 15.0f), false);
  const auto world = world_of(limb.skeleton, pose);
  const auto skinned = skin(limb, world);

  // The caller's half: every active lattice's field, evaluated from what the hierarchy exposes, in index order.
  const auto add_fields = [&](std::vector<glm::vec3>& positions) {
    std::vector<glm::vec3> field(positions.size());
    for (std::size_t l = 0; l < h.lattice_count(); ++l) {
      if (!h.active(l)) continue;
      const deform::LatticeBinding& binding = h.binding(l);
      REQUIRE(h.bound_weights(l).size() == binding.vertices.size());
      REQUIRE(h.displacements(l).size() == h.rest_lattice(l).point_count());
      deform::LatticeEvaluateJob job;
      job.binding = &binding;
      job.control_points = h.displacements(l);
      job.positions = field;
      REQUIRE(job.run());
      for (std::size_t n = 0; n < binding.vertices.size(); ++n) {
        const std::uint32_t p = binding.vertices[n];
        if (p != deform::LatticeBinding::no_vertex) positions[p] += h.bound_weights(l)[n] * field[p];
      }
    }
  };

  // Every lane weight is the point's selection weight; padding lanes weigh nothing.
  for (std::size_t l = 0; l < h.lattice_count(); ++l) {
    const deform::LatticeBinding& binding = h.binding(l);
    CHECK(binding.vertex_count == h.bound_count(l));
    std::size_t real = 0;
    for (std::size_t n = 0; n < binding.vertices.size(); ++n) {
      const std::uint32_t p = binding.vertices[n];
      if (p == deform::LatticeBinding::no_vertex) {
        CHECK(h.bound_weights(l)[n] == 0.0f);
        continue;
      }
      ++real;
      CHECK(p != limb.intruder);
      CHECK(h.bound_weights(l)[n] == doctest::Approx(std::min(1.0f, subtree_weight(limb, p, h.spec(l).bone))));
      CHECK(h.bound_weights(l)[n] > 0.0f);
    }
    CHECK(real == binding.vertex_count);
  }

  // At rest nothing is active and both halves add nothing.
  REQUIRE(h.update(world));
  for (std::size_t l = 0; l < h.lattice_count(); ++l) CHECK_FALSE(h.active(l));
  std::vector<glm::vec3> whole = skinned, split = skinned;
  REQUIRE(h.apply(whole));
  REQUIRE(h.apply_carried(split));
  CHECK(whole == skinned);
  CHECK(split == skinned);

  // Stretched, mid-oscillation (non-affine with the springs), in a bent pose: the same positions to the bit.
  h.set_stretch_target(0, 0.3f);
  h.set_stretch_target(1, 0.6f);
  h.set_stretch_target(2, -0.2f);
  for (int frame = 0; frame < 8; ++frame) REQUIRE(h.step(1.0f / 60.0f));
  for (int frame = 0; frame < 7; ++frame) {
    REQUIRE(h.step(1.0f / 60.0f));
    REQUIRE(h.update(world));
    for (std::size_t l = 0; l < h.lattice_count(); ++l) CHECK(h.active(l));
    whole = skinned;
    split = skinned;
    REQUIRE(h.apply(whole));
    REQUIRE(h.apply_carried(split));
    // apply_carried is exactly each active lattice's carried points moved by weight · far displacement, from the
    // accessors a caller adding them itself reads (GpuLatticeFields::apply_into).
    std::vector<glm::vec3> carried = skinned;
    std::size_t carried_points = 0;
    for (std::size_t l = 0; l < h.lattice_count(); ++l) {
      REQUIRE(h.carried_points(l).size() == h.carried_weights(l).size());
      carried_points += h.carried_points(l).size();
      for (std::size_t n = 0; n < h.carried_points(l).size(); ++n)
        carried[h.carried_points(l)[n]] += h.carried_weights(l)[n] * h.far_displacement(l);
    }
    CHECK(carried_points > 0);
    CHECK(carried == split);
    float fields = 0.0f;  // what the fields move, to be sure the split leaves something to the caller
    for (std::size_t p = 0; p < split.size(); ++p) fields = std::max(fields, glm::length(whole[p] - split[p]));
    CHECK(fields > 0.01f);
    add_fields(split);
    for (std::size_t p = 0; p < split.size(); ++p) {
      CAPTURE(p);
      CHECK(split[p] == whole[p]);
    }
  }
  std::vector<glm::vec3> short_points(3);
  CHECK_FALSE(h.apply_carried(short_points));
}

TEST_CASE("the stretch moves as the oscillator says") {
  const Limb limb = make_limb();
  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("fore", 2, 0.3f)});
  h.set_stretch_target(0, 0.5f);
  const deform::ElasticParams params{400.0f, 0.3f, 1.0f};
  double t = 0.0;
  for (int frame = 0; frame < 60; ++frame) {
    h.step(1.0f / 60.0f);
    t += 1.0 / 60.0;
    // From rest toward a target 0.5 away: offset -0.5 decaying as the unit response.
    CHECK(h.stretch(0) ==
          doctest::Approx(0.5 * (1.0 - deform::oscillator_step(params, t).position_from_offset)).epsilon(1e-4));
  }
  h.reset();
  CHECK(h.stretch(0) == 0.0f);
  CHECK(h.stretch_target(0) == 0.0f);
}

TEST_CASE("bad set-ups throw naming the lattice; bad per-frame calls return false") {
  const Limb limb = make_limb();
  const auto throws_with = [&](LatticeSpec spec, const char* text) {
    CAPTURE(text);
    CHECK_THROWS_WITH_AS(deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec}),
                         doctest::Contains(text), deform::Error);
  };
  LatticeSpec spec = spec_on("fore", 7);
  throws_with(spec, "lattice 'fore'");
  spec = spec_on("fore", 2);
  spec.degree = glm::ivec3(3, 0, 3);
  throws_with(spec, "degree");
  spec.degree = glm::ivec3(17, 3, 3);
  throws_with(spec, "degree");
  spec = spec_on("fore", 2);
  spec.weight_threshold = 1.0f;
  throws_with(spec, "weight_threshold");
  spec = spec_on("fore", 2);
  spec.margin = 2.0f;
  throws_with(spec, "margin");
  spec = spec_on("fore", 2);
  spec.selection = deform::VertexSelection::list;
  spec.vertices = {5, 100000};
  throws_with(spec, "out of range");
  spec.vertices = {5, 5};
  throws_with(spec, "repeated");
  spec.vertices = {0, 1};  // at the root, behind the lattice
  throws_with(spec, "no point inside");
  spec = spec_on("fore", 2);
  spec.elastic.oscillator.mass = 0.0f;
  throws_with(spec, "mass");
  CHECK_THROWS_WITH_AS(
      deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("a", 1), spec_on("a", 2)}),
      doctest::Contains("twice"), deform::Error);

  DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec_on("fore", 2)});
  CHECK(std::string(h.set_stretch_target(0, -1.0f).reason()) == "stretch not finite and > -length");
  CHECK_FALSE(h.set_stretch_target(0, NAN));
  CHECK(std::string(h.set_stretch_target(1, 0.1f).reason()) == "lattice index out of range");
  CHECK(h.stretch_target(0) == 0.0f);
  CHECK(std::string(h.step(-1.0f).reason()) == "dt is negative or not finite");
  CHECK_FALSE(h.step(INFINITY));
  std::vector<glm::mat4> short_world(2);
  CHECK(std::string(h.update(short_world).reason()) == "world does not have one entry per bone");
  std::vector<glm::vec3> short_points(3);
  CHECK(std::string(h.apply(short_points).reason()) == "positions do not have one entry per point");
  CHECK(std::string(h.apply_carried(short_points).reason()) == "positions do not have one entry per point");

  // A refused step, update or apply changes nothing.
  REQUIRE(h.set_stretch_target(0, 0.4f));
  for (int frame = 0; frame < 5; ++frame) REQUIRE(h.step(1.0f / 60.0f));
  const std::vector<glm::mat4> world = world_of(limb.skeleton, limb.skeleton.bind_pose());
  REQUIRE(h.update(world));
  const float stretch = h.stretch(0);
  const std::vector<glm::vec3> points(h.control_points(0).begin(), h.control_points(0).end());
  CHECK_FALSE(h.step(NAN));
  CHECK_FALSE(h.update(short_world));
  CHECK(h.stretch(0) == stretch);
  CHECK(std::equal(points.begin(), points.end(), h.control_points(0).begin()));
  std::vector<glm::vec3> out = limb.points;
  out.pop_back();
  const std::vector<glm::vec3> before = out;
  CHECK_FALSE(h.apply(out));
  CHECK(out == before);
}

// --- the stretch shape: length floor and volume compensation ---

TEST_CASE("soft_length_floor: identity above the knee, smooth, increasing, never below the floor") {
  using deform::soft_length_floor;
  CHECK(soft_length_floor(1.0f, 0.7f) == 1.0f);
  CHECK(soft_length_floor(0.8f, 0.7f) == 0.8f);
  CHECK(soft_length_floor(2.5f, 0.7f) == 2.5f);
  CHECK(soft_length_floor(-3.0f, 0.0f) == -3.0f);  // no floor
  const float bend = 0.8f;
  const float h = 1e-3f;
  CHECK(soft_length_floor(bend - h, 0.7f) == doctest::Approx(bend - h).epsilon(1e-4));  // slope 1 at the knee
  CHECK(soft_length_floor(0.5f, 0.7f) > 0.7f);
  float previous = soft_length_floor(-10.0f, 0.7f);  // the exponential underflows: the floor itself
  for (float r = -10.0f; r <= 2.0f; r += 0.01f) {
    const float shown = soft_length_floor(r, 0.7f);
    CHECK(shown >= 0.7f);
    CHECK(shown >= previous);
    CHECK(shown <= std::max(r, 0.8f) + 1e-6f);
    previous = shown;
  }
  CHECK_THROWS_AS(deform::require_valid_shape({1.0f, 1.0f}), deform::Error);
  CHECK_THROWS_AS(deform::require_valid_shape({0.7f, 1.5f}), deform::Error);
  CHECK_THROWS_AS(deform::require_valid_shape({0.7f, -0.1f}), deform::Error);
  CHECK_THROWS_AS(deform::require_valid_shape({NAN, 1.0f}), deform::Error);
  CHECK_NOTHROW(deform::require_valid_shape({0.0f, 0.0f}));
}

namespace {

// A closed tube around bone 1 (head at y = 0.5, child at y = 1.5: the lattice spans y in [0.5, 1.5]): radius 0.2,
// from y = 0.52 to 1.48, capped, wound outward, every point fully on bone 1.
struct Tube {
  deform::Skeleton skeleton;
  std::vector<glm::vec3> points;
  std::vector<glm::uvec3> triangles;
  deform::SkinWeights weights;
};

Tube make_tube() {
  std::vector<deform::Bone> bones(3);
  bones[0] = {"root", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  bones[1] = {"limb", 0, {2}, glm::vec3(0, 0.5f, 0), glm::vec3(0.0f), {}};
  bones[2] = {"tip", 1, {}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  Tube tube{deform::Skeleton(bones), {}, {}, {}};
  constexpr int around = 24;
  constexpr int along = 25;
  for (int r = 0; r < along; ++r) {
    const float y = 0.52f + 0.96f * float(r) / float(along - 1);
    for (int a = 0; a < around; ++a) {
      const float angle = 2.0f * float(std::numbers::pi) * float(a) / around;
      tube.points.emplace_back(0.2f * std::cos(angle), y, 0.2f * std::sin(angle));
    }
  }
  const auto ring = [](int r, int a) { return std::uint32_t(r * around + (a % around)); };
  for (int r = 0; r + 1 < along; ++r) {
    for (int a = 0; a < around; ++a) {
      tube.triangles.emplace_back(ring(r, a), ring(r + 1, a), ring(r + 1, a + 1));
      tube.triangles.emplace_back(ring(r, a), ring(r + 1, a + 1), ring(r, a + 1));
    }
  }
  const auto bottom = std::uint32_t(tube.points.size());
  tube.points.emplace_back(0.0f, 0.52f, 0.0f);
  const auto top = std::uint32_t(tube.points.size());
  tube.points.emplace_back(0.0f, 1.48f, 0.0f);
  for (int a = 0; a < around; ++a) {
    tube.triangles.emplace_back(bottom, ring(0, a), ring(0, a + 1));
    tube.triangles.emplace_back(top, ring(along - 1, a + 1), ring(along - 1, a));
  }
  tube.weights.bones.assign(tube.points.size(), glm::u16vec4(1, 0, 0, 0));
  tube.weights.weights.assign(tube.points.size(), glm::vec4(1, 0, 0, 0));
  return tube;
}

// Enclosed volume by the divergence theorem, in double.
double enclosed_volume(const std::vector<glm::vec3>& points, const std::vector<glm::uvec3>& triangles) {
  double sum = 0.0;
  for (const glm::uvec3& t : triangles) {
    const glm::dvec3 a(points[t.x]), b(points[t.y]), c(points[t.z]);
    sum += glm::dot(a, glm::cross(b, c));
  }
  return sum / 6.0;
}

// The tube's points with the lattice settled at a stretch target (model units), in the bind pose.
std::vector<glm::vec3> settled_tube(const Tube& tube, deform::StretchShape shape, float target, float* shown) {
  LatticeSpec spec = spec_on("limb", 1);
  spec.shape = shape;
  DeformerHierarchy h = deform::bind_hierarchy(tube.skeleton, tube.points, tube.weights, {spec});
  REQUIRE(h.bound_count(0) == tube.points.size());
  REQUIRE(h.length(0) == doctest::Approx(1.0f));
  REQUIRE(h.set_stretch_target(0, target));
  settle(h);
  *shown = h.stretch(0);
  std::vector<glm::vec3> out = tube.points;
  REQUIRE(h.update(world_of(tube.skeleton, tube.skeleton.bind_pose())));
  REQUIRE(h.apply(out));
  return out;
}

}  // namespace

TEST_CASE("volume 1 keeps a closed tube's volume within 2% for stretches 0.5 to 3; volume 0 is the plain stretch") {
  const Tube tube = make_tube();
  const double rest = enclosed_volume(tube.points, tube.triangles);
  REQUIRE(rest > 0.0);
  for (const float s : {0.5f, 0.7f, 1.0f, 1.5f, 2.0f, 3.0f}) {
    CAPTURE(s);
    float shown = 0.0f;
    const auto rubber = settled_tube(tube, {0.0f, 1.0f}, s - 1.0f, &shown);
    CHECK(shown == doctest::Approx(s - 1.0f).epsilon(1e-4));
    const double kept = enclosed_volume(rubber, tube.triangles) / rest;
    MESSAGE("stretch ", s, ": volume at volume 1 differs from rest by ", kept - 1.0);
    CHECK(std::abs(kept - 1.0) < 0.02);
    // Thinner when stretched, thicker when squashed: the middle ring's radius is 0.2 / sqrt(s).
    const glm::vec3 middle = rubber[12 * 24];
    CHECK(glm::length(glm::vec2(middle.x, middle.z)) == doctest::Approx(0.2f / std::sqrt(s)).epsilon(1e-3));
    const auto plain = settled_tube(tube, {0.0f, 0.0f}, s - 1.0f, &shown);
    CHECK(enclosed_volume(plain, tube.triangles) / rest == doctest::Approx(s).epsilon(1e-3));
    // Half compensation: the cross-section scales by 1/sqrt(s).
    const auto half = settled_tube(tube, {0.0f, 0.5f}, s - 1.0f, &shown);
    CHECK(enclosed_volume(half, tube.triangles) / rest == doctest::Approx(std::sqrt(s)).epsilon(1e-3));
  }
}

TEST_CASE("the length floor: a lattice squashed to half shows at least 70% of its length, and bulges") {
  const Tube tube = make_tube();
  const double rest = enclosed_volume(tube.points, tube.triangles);
  float shown = 0.0f;
  const auto squashed = settled_tube(tube, {}, -0.5f, &shown);  // default shape: floor 0.7, volume 1
  CHECK(shown > -0.3f);
  CHECK(shown < -0.29f);  // the floor is soft: just above it
  CHECK(enclosed_volume(squashed, tube.triangles) / rest == doctest::Approx(1.0).epsilon(0.02));
  const glm::vec3 middle = squashed[12 * 24];
  CHECK(glm::length(glm::vec2(middle.x, middle.z)) > 0.2f / std::sqrt(0.71f));
  // Every ring keeps at least 70% of its rest spacing.
  for (int r = 0; r + 1 < 25; ++r)
    CHECK(squashed[std::size_t((r + 1) * 24)].y - squashed[std::size_t(r * 24)].y >= 0.7f * 0.04f);
}

TEST_CASE("the shape is a function of the springs' state: frame-rate independent through an under-damped release") {
  const Tube tube = make_tube();
  LatticeSpec spec = spec_on("limb", 1, 0.2f);
  spec.shape = {};  // floor 0.7, volume 1
  const auto world = world_of(tube.skeleton, tube.skeleton.bind_pose());
  const auto run = [&](int hertz) {
    DeformerHierarchy h = deform::bind_hierarchy(tube.skeleton, tube.points, tube.weights, {spec});
    REQUIRE(h.set_stretch_target(0, 1.0f));
    settle(h);
    REQUIRE(h.set_stretch_target(0, 0.0f));
    std::vector<float> curve;  // the shown stretch every 1/30 s over 1.5 s
    float lowest = 1.0f;
    for (int n = 1; n <= hertz * 3 / 2; ++n) {
      REQUIRE(h.step(1.0f / float(hertz)));
      lowest = std::min(lowest, h.stretch(0));
      if (n % (hertz / 30) == 0) curve.push_back(h.stretch(0));
    }
    CHECK(lowest > -0.3f);
    REQUIRE(h.update(world));
    return curve;
  };
  const auto coarse = run(30);
  const auto fine = run(240);
  REQUIRE(coarse.size() == fine.size());
  float largest = 0.0f;
  for (std::size_t n = 0; n < coarse.size(); ++n) largest = std::max(largest, std::abs(coarse[n] - fine[n]));
  MESSAGE("30 Hz vs 240 Hz: largest difference of the shown stretch ", largest);
  CHECK(largest < 1e-4f);
}

TEST_CASE("set_shape changes the shape, refuses bad values and bad indices") {
  const Tube tube = make_tube();
  DeformerHierarchy h = deform::bind_hierarchy(tube.skeleton, tube.points, tube.weights, {spec_on("limb", 1)});
  REQUIRE(h.set_stretch_target(0, -0.6f));
  settle(h);
  CHECK(h.stretch(0) > -0.3f);  // the default floor, 0.7
  h.set_shape(0, {0.0f, 0.0f});
  CHECK(h.stretch(0) == doctest::Approx(-0.6f).epsilon(1e-4));
  CHECK(h.spec(0).shape == deform::StretchShape{0.0f, 0.0f});
  h.set_shape(0, {0.5f, 0.0f});
  CHECK(h.stretch(0) > -0.5f);
  CHECK_THROWS_AS(h.set_shape(0, {0.7f, 2.0f}), deform::Error);
  CHECK_THROWS_AS(h.set_shape(1, {}), deform::Error);
  CHECK_THROWS_AS(h.set_motion(1, {}), deform::Error);
  CHECK_THROWS_AS(h.set_elastic(1, {}), deform::Error);
  // The per-frame restart refuses a bad index with a Status, and takes a good one.
  CHECK_FALSE(h.restart_motion(1));
  CHECK(h.restart_motion(0));
  LatticeSpec bad = spec_on("limb", 1);
  bad.shape.min_length_fraction = -0.5f;
  CHECK_THROWS_AS(deform::bind_hierarchy(tube.skeleton, tube.points, tube.weights, {bad}), deform::Error);
}

namespace {

// The same lattices with their rest control points moved off the frame's grid (a sculpted rest lattice), built from
// what the fitted hierarchy exposes: apply() with normals then evaluates the map's own control points for the normals.
DeformerHierarchy sculpted_rest(const DeformerHierarchy& fitted, const deform::Skeleton& skeleton, std::size_t points) {
  std::vector<deform::BoundLattice> bound;
  std::mt19937 rng(92);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  for (std::size_t l = 0; l < fitted.lattice_count(); ++l) {
    deform::BoundLattice b;
    b.spec = fitted.spec(l);
    b.rest = fitted.rest_lattice(l);
    for (glm::vec3& x : b.rest.control_points()) x += glm::vec3{jitter(rng), jitter(rng), jitter(rng)};
    b.axis = glm::normalize(b.rest.frame().u_axis);
    b.length = fitted.length(l);
    b.binding = fitted.binding(l);
    b.lane_weights.assign(fitted.bound_weights(l).begin(), fitted.bound_weights(l).end());
    b.carried_points.assign(fitted.carried_points(l).begin(), fitted.carried_points(l).end());
    b.carried_weights.assign(fitted.carried_weights(l).begin(), fitted.carried_weights(l).end());
    bound.push_back(std::move(b));
  }
  return DeformerHierarchy(skeleton, std::move(bound), points);
}

}  // namespace

TEST_CASE("apply with normals: apply's positions to the bit, and the normals of linear · rest + field") {
  // Reference: the composed map's control points (linear · rest + displacement) evaluated with normals, one lattice at
  // a time as apply() goes. For rest lattices on their frame's grid (what bind_hierarchy fits) apply() evaluates the
  // field once, the linear part's Jacobian added as an offset; for sculpted ones, the map's own control points.
  const Limb limb = make_limb();
  LatticeSpec upper = spec_on("upper", 1, 0.3f), fore = spec_on("fore", 2, 0.2f), hand = spec_on("hand", 3);
  fore.degree = glm::ivec3(4, 2, 3);  // unequal degrees: each derivative carries its own degree factor
  DeformerHierarchy fitted = deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {upper, fore, hand});
  DeformerHierarchy sculpted = sculpted_rest(fitted, limb.skeleton, limb.points.size());
  deform::Pose pose = limb.skeleton.bind_pose();
  limb.skeleton.set_euler(pose, 1, glm::vec3(20.0f, 10.0f, -35.0f), false);
  limb.skeleton.set_euler(pose, 2, glm::vec3(-40.0f, 0.0f, 15.0f), false);
  const auto world = world_of(limb.skeleton, pose);
  const auto skinned = skin(limb, world);
  std::mt19937 rng(91);
  std::normal_distribution<float> normal;
  std::vector<glm::vec3> normals0(skinned.size());
  for (glm::vec3& n : normals0) n = glm::normalize(glm::vec3{normal(rng), normal(rng), normal(rng)});
  for (DeformerHierarchy* h : {&fitted, &sculpted}) {
    const std::string label = std::string(h == &fitted ? "fitted" : "sculpted") + " rest lattices";
    INFO(label);
    h->set_stretch_target(0, 0.3f);
    h->set_stretch_target(1, 0.6f);
    h->set_stretch_target(2, -0.2f);
    double worst = 0.0, moved = 0.0;
    for (int frame = 0; frame < 12; ++frame) {
      REQUIRE(h->step(1.0f / 60.0f));
      REQUIRE(h->update(world));
      std::vector<glm::vec3> plain = skinned, positions = skinned, normals = normals0;
      REQUIRE(h->apply(plain));
      REQUIRE(h->apply(positions, normals));
      CHECK(positions == plain);

      std::vector<glm::vec3> expected = normals0, scratch(skinned.size()), in(skinned.size());
      for (std::size_t l = 0; l < h->lattice_count(); ++l) {
        if (!h->active(l)) continue;
        const std::size_t bone = std::size_t(h->spec(l).bone);
        const glm::mat3 linear(world[bone]);
        const glm::mat3 to_bind = glm::transpose(linear * glm::mat3(limb.skeleton.inverse_bind_world()[bone]));
        const std::span<const glm::vec3> rest = h->rest_lattice(l).control_points();
        std::vector<glm::vec3> mapped(rest.size());
        for (std::size_t n = 0; n < rest.size(); ++n) mapped[n] = linear * rest[n] + h->displacements(l)[n];
        const deform::LatticeBinding& binding = h->binding(l);
        for (std::uint32_t p : binding.vertices)
          if (p != deform::LatticeBinding::no_vertex) in[p] = to_bind * expected[p];
        deform::LatticeEvaluateJob job;
        job.binding = &binding;
        job.control_points = mapped;
        job.positions = scratch;
        job.normals_in = in;
        job.normals_out = in;
        REQUIRE(job.run());
        for (std::size_t n = 0; n < binding.vertices.size(); ++n) {
          const std::uint32_t p = binding.vertices[n];
          if (p == deform::LatticeBinding::no_vertex) continue;
          const glm::vec3 blended = expected[p] + h->bound_weights(l)[n] * (in[p] - expected[p]);
          if (glm::dot(blended, blended) > 1e-12f) expected[p] = glm::normalize(blended);
        }
      }
      for (std::size_t p = 0; p < normals.size(); ++p) {
        worst = std::max(worst, double(glm::length(normals[p] - expected[p])));
        moved = std::max(moved, double(glm::length(normals[p] - normals0[p])));
      }
    }
    MESSAGE("apply with normals vs the composed map's evaluation: largest difference ", worst);
    CHECK(worst < 1e-5);
    CHECK(moved > 0.05);  // the lattices do turn normals
  }
}

TEST_CASE("bind_hierarchy selects by the whole skin: influences past the fourth count toward a subtree") {
  // Every point on five bones, the hand's (3) the weakest, so it lies past the four slots: the forearm's subtree
  // (2 and 3) weighs 0.17 + 0.13.
  Limb limb = make_limb();
  deform::SkinWeights weights;
  const std::uint16_t bones[5] = {0, 4, 1, 2, 3};
  const float values[5] = {0.25f, 0.25f, 0.20f, 0.17f, 0.13f};
  for (std::size_t p = 0; p < limb.points.size(); ++p) deform::append_influences(weights, bones, values);
  REQUIRE(weights.has_extra());
  const DeformerHierarchy h = deform::bind_hierarchy(limb.skeleton, limb.points, weights, {spec_on("fore", 2)});
  REQUIRE(h.bound_count(0) > 0);
  for (std::size_t n = 0; n < h.binding(0).vertices.size(); ++n) {
    if (h.binding(0).vertices[n] == deform::LatticeBinding::no_vertex) continue;
    CHECK(h.bound_weights(0)[n] == doctest::Approx(0.30f).epsilon(1e-5));
  }

  // A malformed extra layout is refused at bind time, naming the problem.
  deform::SkinWeights broken = weights;
  broken.extra_offsets.back() += 1;
  CHECK_THROWS_WITH_AS(deform::bind_hierarchy(limb.skeleton, limb.points, broken, {spec_on("fore", 2)}),
                       doctest::Contains("extra influences are malformed"), deform::Error);
}
