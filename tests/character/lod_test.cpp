// Levels of detail in the Character (set_levels, set_level): level 0 is the character as it was, a switch blends
// instead of jumping, an update interval interpolates instead of popping, and the costs and the picking helper.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/runtime/animation.hpp"

using deform::Character;

namespace {

constexpr float dt = 1.0f / 60.0f;

deform::BoneLod builtin_lod(const Character& c) {
  deform::BoneLodSettings settings;
  settings.bones_per_level = {c.skeleton().bone_count() - 8, 14, 8};
  return deform::build_bone_lod(c.model(), settings);
}

// Full detail; bones merged; fewer bones, no deformers; fewest, no deformers, every 4th update.
const std::vector<Character::LevelOptions> options = {{true, 1}, {true, 1}, {false, 1}, {false, 4}};

struct Walker {
  Character c = deform::make_builtin_character();
  deform::Animation walk = deform::builtin_walk(c.model());
  deform::Pose pose = c.skeleton().bind_pose();
  float time = 0.0f;
  // The left arm stretched, so the lattices and the ponytail's spring chain both show.
  Walker() {
    for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l)
      c.deformers().set_stretch_target(l, 0.3f * c.deformers().length(l));
  }
  void frame() {
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    sampling.time = time;
    sampling.rotations = pose.rotations;
    sampling.translations = pose.translations;
    REQUIRE(sampling.run());
    REQUIRE(c.set_pose(pose));
    REQUIRE(c.update(dt));
    time += dt;
  }
};

float largest_move(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  float largest = 0.0f;
  for (std::size_t p = 0; p < a.size(); ++p) largest = std::max(largest, glm::length(a[p] - b[p]));
  return largest;
}

// Per frame, the largest distance a point moved since the frame before, over `frames` frames with set_level calls
// from `schedule` (frame -> level), after 60 frames at level 0 to get the springs going.
std::vector<float> moves(Walker& w, int frames, const std::vector<std::pair<int, std::size_t>>& schedule) {
  for (int f = 0; f < 60; ++f) w.frame();
  std::vector<float> out;
  std::vector<glm::vec3> before(w.c.positions().begin(), w.c.positions().end());
  for (int f = 0; f < frames; ++f) {
    for (const auto& [at, level] : schedule)
      if (at == f) REQUIRE(w.c.set_level(level));
    w.frame();
    out.push_back(largest_move(w.c.positions(), before));
    before.assign(w.c.positions().begin(), w.c.positions().end());
  }
  return out;
}

}  // namespace

TEST_CASE("levels: level 0 is the character without levels, to the bit, springs and lattices included") {
  Walker plain, levelled;
  levelled.c.set_levels(builtin_lod(levelled.c), options);
  CHECK(levelled.c.level_count() == 4);
  CHECK(plain.c.level_count() == 1);
  for (int f = 0; f < 90; ++f) {
    plain.frame();
    levelled.frame();
  }
  const auto a = plain.c.positions();
  const auto b = levelled.c.positions();
  CHECK(std::equal(a.begin(), a.end(), b.begin()));
  CHECK(plain.c.deformers().stretch(0) > 0.01f);
}

TEST_CASE("levels: a switch blends over blend_frames, its largest jump within a frame's ordinary motion") {
  // 0 -> 1 (bones merged), -> 2 (deformers off: the stretch and the ponytail go), -> 0 (they come back), -> 3.
  const std::vector<std::pair<int, std::size_t>> schedule = {{20, 1}, {50, 2}, {90, 0}, {130, 3}, {170, 0}};
  Walker still;
  still.c.set_levels(builtin_lod(still.c), options);
  const std::vector<float> ordinary = moves(still, 200, {});
  const float usual = *std::max_element(ordinary.begin(), ordinary.end());
  float blended = 0.0f, abrupt = 0.0f;
  for (const std::uint32_t blend : {24u, 0u}) {
    Walker w;
    w.c.set_levels(builtin_lod(w.c), options, blend);
    const std::vector<float> m = moves(w, 200, schedule);
    (blend == 0 ? abrupt : blended) = *std::max_element(m.begin(), m.end());
  }
  MESSAGE("largest move per frame: ordinary " << usual << ", with switches blended over 24 frames " << blended
                                              << ", unblended " << abrupt);
  CHECK(blended <= 1.5f * usual);
  CHECK(abrupt > 2.0f * usual);  // without the blend the switches do jump: the check above can fail
}

TEST_CASE("levels: an update interval interpolates the points (no pop) and deforms every Nth update") {
  Walker w;
  w.c.set_levels(builtin_lod(w.c), options);
  Walker reference;  // level 2: the same skin and no deformers, every update
  reference.c.set_levels(builtin_lod(reference.c), options);
  REQUIRE(w.c.set_level(2));
  REQUIRE(reference.c.set_level(2));
  for (int f = 0; f < 30; ++f) w.frame(), reference.frame();  // both settled at level 2
  const std::vector<float> every = moves(reference, 80, {});
  const std::vector<float> nth = moves(w, 80, {{0, 3}});
  // Level 3 skins with fewer bones than 2: measure its own ordinary motion against the interval's.
  Walker third;
  third.c.set_levels(builtin_lod(third.c), {{{true, 1}, {true, 1}, {false, 1}, {false, 1}}});
  REQUIRE(third.c.set_level(3));
  const std::vector<float> third_every = moves(third, 80, {});
  const float usual = std::max(*std::max_element(every.begin(), every.end()),
                               *std::max_element(third_every.begin(), third_every.end()));
  const float interval = *std::max_element(nth.begin() + 1, nth.end());
  MESSAGE("largest move per frame: every update " << usual << ", every 4th interpolated " << interval);
  CHECK(interval <= 1.5f * usual);
  // Every 4th update deforms: the switch's update deforms at its pose (what level 3 shows at once when it updates
  // every time), positions() reaches those points 3 updates later, and none of those updates deforms anew.
  Walker probe, at_once;
  probe.c.set_levels(builtin_lod(probe.c), options, 0);
  at_once.c.set_levels(builtin_lod(at_once.c), {{{true, 1}, {true, 1}, {false, 1}, {false, 1}}}, 0);
  REQUIRE(probe.c.set_level(3));
  REQUIRE(at_once.c.set_level(3));
  probe.frame();
  at_once.frame();
  const std::vector<glm::vec3> target(at_once.c.positions().begin(), at_once.c.positions().end());
  CHECK(largest_move(probe.c.positions(), target) > 1e-3f);  // a quarter of the way
  for (int f = 0; f < 3; ++f) {
    CHECK_FALSE(probe.c.next_update_deforms());
    probe.frame();
  }
  CHECK(probe.c.next_update_deforms());
  CHECK(at_once.c.next_update_deforms());
  CHECK(largest_move(probe.c.positions(), target) < 1e-5f);
  probe.frame();  // the next deformed update: on toward the new pose's points
  CHECK(largest_move(probe.c.positions(), target) > 1e-4f);
}

TEST_CASE("levels: costs, the camera helper, refusals") {
  Character c = deform::make_builtin_character();
  const Character::LevelCost plain = c.level_cost(0);
  CHECK(plain.points == c.model().mesh.point_count());
  CHECK(plain.bones == c.skeleton().bone_count());
  CHECK(c.level_cost(1).points == 0);
  CHECK_FALSE(c.set_level(1));
  c.set_levels(builtin_lod(c), options);
  CHECK(c.level_cost(0).influences == plain.influences);
  for (std::size_t l = 1; l < c.level_count(); ++l) {
    CHECK(c.level_cost(l).influences < c.level_cost(l - 1).influences);
    CHECK(c.level_cost(l).bones <= c.level_cost(l - 1).bones);
  }
  CHECK(c.level_cost(3).update_interval == 4);
  CHECK_FALSE(c.level_cost(2).deformers);
  CHECK_FALSE(c.set_level(4));
  CHECK(c.set_level(3));
  CHECK(c.level() == 3);
  // An instance shares the levels and starts at this one's.
  Character other = c.instance();
  CHECK(other.level_count() == 4);
  CHECK(other.level() == 3);

  const float near = deform::screen_height(1.8f, 2.0f, 1.0f);
  const float far = deform::screen_height(1.8f, 200.0f, 1.0f);
  CHECK(near > 0.7f);
  CHECK(far < 0.01f);
  CHECK(deform::screen_height(1.8f, 0.0f, 1.0f) == 0.0f);
  const std::vector<float> thresholds = {0.3f, 0.1f, 0.03f};
  CHECK(deform::pick_level(thresholds, near) == 0);
  CHECK(deform::pick_level(thresholds, 0.2f) == 1);
  CHECK(deform::pick_level(thresholds, 0.05f) == 2);
  CHECK(deform::pick_level(thresholds, far) == 3);

  const auto refused = [&](const std::vector<Character::LevelOptions>& opts, std::uint32_t blend,
                           const std::string& element) {
    try {
      c.set_levels(builtin_lod(c), opts, blend);
      FAIL("accepted");
    } catch (const deform::Error& error) {
      CHECK(std::string(error.what()).find(element) != std::string::npos);
    }
  };
  refused({{true, 1}, {true, 1}}, 8, "level 2");
  refused({{true, 1}, {true, 0}, {true, 1}, {true, 1}}, 8, "level 1");
  refused(options, 5000, "blend_frames");
  deform::BoneLod broken = builtin_lod(c);
  broken.levels[2].weights.bones[7].x = 999;
  try {
    c.set_levels(broken, options);
    FAIL("accepted");
  } catch (const deform::Error& error) {
    CHECK(std::string(error.what()).find("level 2") != std::string::npos);
  }
  CHECK(c.level_count() == 4);  // the refused calls changed nothing
}
