// Direct Delta Mush as the Character's skinning (set_direct_delta_mush): update() against DirectDeltaMushJob run by
// hand on the morphed bind points with palette() (positions and transported normals), the rest pose reproduced, the
// precedence over settings.skinning, the refusals, set then cleared giving the frame without it to the bit, and
// instances sharing the binding. The frame's allocations are counted in frame_allocation_test.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/direct_delta_mush.hpp"

using deform::Character;

namespace {

float diagonal(std::span<const glm::vec3> p) {
  const deform::Bounds bounds = deform::compute_bounds(p);
  return glm::length(bounds.max - bounds.min);
}

double max_distance(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, glm::length(glm::dvec3(a[i]) - glm::dvec3(b[i])));
  return d;
}

bool same_bits(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

// The left elbow bent 110 degrees, the upper arm turned.
deform::Pose bent_elbow(const deform::Skeleton& sk) {
  deform::Pose pose = sk.bind_pose();
  sk.set_euler(pose, sk.find("forearm_l"), {110.0f, 0.0f, 0.0f});
  sk.set_euler(pose, sk.find("upperarm_l"), {0.0f, 20.0f, 30.0f});
  return pose;
}

// One morph target that moves every tenth point of the built-in character, so the job's input points matter.
deform::Model morphed_builtin() {
  deform::Model model = deform::builtin_character();
  deform::MorphTarget target;
  target.name = "bulge";
  for (std::size_t p = 0; p < model.mesh.point_count(); p += 10) {
    target.points.push_back(std::uint32_t(p));
    target.position_deltas.push_back({0.01f, 0.02f, -0.015f});
  }
  model.morph_targets.push_back(target);
  return model;
}

}  // namespace

TEST_CASE("Character: Direct Delta Mush equals DirectDeltaMushJob by hand on the morphed bind points, palette()") {
  Character c(morphed_builtin());  // no lattices: the skinning alone
  CHECK(c.direct_delta_mush() == nullptr);
  c.set_direct_delta_mush({});
  REQUIRE(c.direct_delta_mush() != nullptr);
  const float size = diagonal(c.model().mesh.positions);
  REQUIRE(c.set_pose(bent_elbow(c.skeleton())));

  for (const float weight : {0.0f, 0.7f}) {
    CAPTURE(weight);
    REQUIRE(c.set_morph_weight(std::size_t(0), weight));
    REQUIRE(c.update(0.0f));
    const std::span<const glm::vec3> morphed = c.morphed_bind_positions();
    if (weight != 0.0f) CHECK(max_distance(morphed, c.model().mesh.positions) > 0.005 * size);
    std::vector<glm::vec3> positions(c.model().mesh.point_count()), normals(positions.size());
    deform::DirectDeltaMushJob job;
    job.binding = c.direct_delta_mush();
    job.matrices = c.palette();
    job.in_positions = morphed;
    job.out_positions = positions;
    if (weight == 0.0f) {  // the morph moved no normal: the transported ones are the bind normals turned
      job.in_normals = c.bind_normals();
      job.out_normals = normals;
    }
    REQUIRE(job.validate());
    REQUIRE(job.run());
    CHECK(max_distance(c.positions(), positions) <= 1e-6 * size);
    if (weight == 0.0f) {
      const std::span<const glm::vec3> rendered = c.normals();
      const std::vector<std::uint32_t>& vertex_point = c.model().mesh.vertex_point;
      double worst = 0.0;
      for (std::size_t v = 0; v < vertex_point.size(); ++v)
        worst = std::max(worst, double(glm::length(rendered[v] - normals[vertex_point[v]])));
      CHECK(worst <= 1e-6);
    }
  }

  // It did something LBS does not: the bent elbow's points differ.
  Character lbs(morphed_builtin());
  REQUIRE(lbs.set_pose(bent_elbow(lbs.skeleton())));
  REQUIRE(lbs.set_morph_weight(std::size_t(0), 0.7f));
  REQUIRE(lbs.update(0.0f));
  CHECK(max_distance(lbs.positions(), c.positions()) > 1e-3 * size);

  // Bound, it takes precedence over settings.skinning: DQS asked for, DDM given, to the bit.
  std::vector<glm::vec3> with_lbs(c.positions().begin(), c.positions().end());
  c.settings.skinning = deform::SkinningMethod::dqs;
  REQUIRE(c.update(0.0f));
  CHECK(same_bits(c.positions(), with_lbs));
}

TEST_CASE("Character: Direct Delta Mush keeps the rest pose, refuses bad settings, clears to the frame without it") {
  Character on = deform::make_builtin_character();  // with the rig's lattices
  const float size = diagonal(on.model().mesh.positions);
  on.set_direct_delta_mush({});
  REQUIRE(on.update(0.0f));
  CHECK(max_distance(on.positions(), on.model().mesh.positions) <= 1e-5 * size);
  const std::span<const glm::vec3> normals = on.normals();
  const std::vector<std::uint32_t>& vertex_point = on.model().mesh.vertex_point;
  double worst = 0.0;
  for (std::size_t v = 0; v < vertex_point.size(); ++v)
    worst = std::max(worst, double(glm::length(normals[v] - on.bind_normals()[vertex_point[v]])));
  CHECK(worst <= 1e-4);

  // Refused settings: deform::Error, the binding in place kept.
  const deform::DirectDeltaMushBinding* bound = on.direct_delta_mush();
  deform::DirectDeltaMushSettings bad;
  bad.iterations = 0;
  CHECK_THROWS_AS(on.set_direct_delta_mush(bad), deform::Error);
  bad = {};
  bad.step = -1.0f;
  CHECK_THROWS_AS(on.set_direct_delta_mush(bad), deform::Error);
  CHECK(on.direct_delta_mush() == bound);

  // Set, then cleared: the same bits as never set, LBS and DQS, through a reach that stretches the lattices.
  for (const deform::SkinningMethod method : {deform::SkinningMethod::lbs, deform::SkinningMethod::dqs}) {
    Character never = deform::make_builtin_character();
    Character cleared = deform::make_builtin_character();
    cleared.set_direct_delta_mush({});
    cleared.clear_direct_delta_mush();
    CHECK(cleared.direct_delta_mush() == nullptr);
    Character ddm = deform::make_builtin_character();
    ddm.set_direct_delta_mush({});
    const deform::Pose pose = bent_elbow(never.skeleton());
    for (Character* c : {&never, &cleared, &ddm}) {
      c->settings.skinning = method;
      REQUIRE(c->set_pose(pose));
      REQUIRE(c->reach(c->skeleton().find("hand_l"), {1.4f, 1.6f, 0.4f}).status);
      for (int frame = 0; frame < 2; ++frame) REQUIRE(c->update(1.0f / 60.0f));
    }
    CHECK(never.stretch() > 0.05f);
    CHECK(same_bits(cleared.positions(), never.positions()));
    CHECK(same_bits(cleared.normals(), never.normals()));
    // The lattices ran after DDM as after LBS: stretched, the points differ from LBS's but stay near them.
    CHECK(max_distance(ddm.positions(), never.positions()) > 1e-3 * size);
    CHECK(max_distance(ddm.positions(), never.positions()) < 0.1 * size);
  }
}

TEST_CASE("Character: instances share the Direct Delta Mush binding and give what their own would") {
  Character on = deform::make_builtin_character();
  deform::DirectDeltaMushSettings settings;
  settings.iterations = 6;
  on.set_direct_delta_mush(settings);
  on.set_delta_mush({4, 0.5f, {}});  // Delta Mush after it, as after LBS
  Character copy = on.instance();
  CHECK(copy.direct_delta_mush() == on.direct_delta_mush());
  CHECK(copy.delta_mush() == on.delta_mush());
  Character own = deform::make_builtin_character();
  own.set_direct_delta_mush(settings);
  own.set_delta_mush({4, 0.5f, {}});
  for (Character* c : {&copy, &own}) {
    REQUIRE(c->set_pose(bent_elbow(c->skeleton())));
    REQUIRE(c->update(0.0f));
  }
  CHECK(same_bits(copy.positions(), own.positions()));
  CHECK(same_bits(copy.normals(), own.normals()));
  // Clearing one leaves the other's binding alone.
  copy.clear_direct_delta_mush();
  CHECK(copy.direct_delta_mush() == nullptr);
  CHECK(on.direct_delta_mush() != nullptr);
}

TEST_CASE("Character: the reduced variant equals DirectDeltaMushReducedJob by hand; rest, instances, clear") {
  Character c(morphed_builtin());
  deform::DirectDeltaMushSettings settings;
  settings.variant = deform::DirectDeltaMushVariant::reduced;
  c.set_direct_delta_mush(settings);
  CHECK(c.direct_delta_mush() == nullptr);  // only the reduced binding is kept
  REQUIRE(c.direct_delta_mush_reduced() != nullptr);
  const float size = diagonal(c.model().mesh.positions);
  // The rest pose given back.
  REQUIRE(c.update(0.0f));
  CHECK(max_distance(c.positions(), c.model().mesh.positions) <= 1e-6 * size);

  REQUIRE(c.set_pose(bent_elbow(c.skeleton())));
  for (const float weight : {0.0f, 0.7f}) {
    CAPTURE(weight);
    REQUIRE(c.set_morph_weight(std::size_t(0), weight));
    REQUIRE(c.update(0.0f));
    std::vector<glm::vec3> positions(c.model().mesh.point_count()), normals(positions.size());
    std::vector<deform::DualQuat> dual_quats(c.palette().size());
    std::vector<glm::mat3> scales(c.palette().size());
    bool has_scale = false;
    REQUIRE(deform::compute_dual_quat_palette(c.palette(), dual_quats, scales, has_scale));
    deform::DirectDeltaMushReducedJob job;
    job.binding = c.direct_delta_mush_reduced();
    job.matrices = c.palette();
    job.dual_quats = dual_quats;
    job.in_positions = c.morphed_bind_positions();
    job.out_positions = positions;
    if (weight == 0.0f) {
      job.in_normals = c.bind_normals();
      job.out_normals = normals;
    }
    REQUIRE(job.validate());
    REQUIRE(job.run());
    CHECK(same_bits(c.positions(), positions));
    if (weight == 0.0f) {
      const std::span<const glm::vec3> rendered = c.normals();
      const std::vector<std::uint32_t>& vertex_point = c.model().mesh.vertex_point;
      double worst = 0.0;
      for (std::size_t v = 0; v < vertex_point.size(); ++v)
        worst = std::max(worst, double(glm::length(rendered[v] - normals[vertex_point[v]])));
      CHECK(worst <= 1e-6);
    }
  }
  // Not the full form: the two differ at the bent elbow, but not by much.
  Character full(morphed_builtin());
  full.set_direct_delta_mush({});
  REQUIRE(full.set_pose(bent_elbow(full.skeleton())));
  REQUIRE(full.set_morph_weight(std::size_t(0), 0.7f));
  REQUIRE(full.update(0.0f));
  CHECK(max_distance(full.positions(), c.positions()) > 1e-4 * size);
  CHECK(max_distance(full.positions(), c.positions()) < 0.05 * size);

  // An instance shares the reduced binding and gives the same bits; cleared, the frame is LBS's again.
  Character copy = c.instance();
  CHECK(copy.direct_delta_mush_reduced() == c.direct_delta_mush_reduced());
  REQUIRE(copy.set_pose(bent_elbow(copy.skeleton())));
  REQUIRE(copy.set_morph_weight(std::size_t(0), 0.7f));
  REQUIRE(copy.update(0.0f));
  CHECK(same_bits(copy.positions(), c.positions()));
  copy.clear_direct_delta_mush();
  CHECK(copy.direct_delta_mush_reduced() == nullptr);
  CHECK(c.direct_delta_mush_reduced() != nullptr);
  Character lbs(morphed_builtin());
  REQUIRE(lbs.set_pose(bent_elbow(lbs.skeleton())));
  REQUIRE(lbs.set_morph_weight(std::size_t(0), 0.7f));
  REQUIRE(lbs.update(0.0f));
  REQUIRE(copy.update(0.0f));
  CHECK(same_bits(copy.positions(), lbs.positions()));
}
