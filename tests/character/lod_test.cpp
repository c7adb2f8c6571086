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
#include "deform/offline/topology.hpp"
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
  explicit Walker(Character character) : c(std::move(character)) {}
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

namespace {

// Mesh levels (LevelOptions::points): hand-made subsets, as simplify_model's source_point would give (any order).
// The built-in character with a morph target, "bulge", on every fifth point.
deform::Model bulged_builtin() {
  deform::Model model = deform::builtin_character();
  deform::MorphTarget target;
  target.name = "bulge";
  for (std::uint32_t p = 0; p < model.mesh.point_count(); p += 5) {
    target.points.push_back(p);
    target.position_deltas.push_back({0.0f, 0.01f, 0.02f});
    target.normal_deltas.push_back({0.1f, 0.0f, 0.0f});
  }
  model.morph_targets.push_back(target);
  return model;
}

std::vector<std::uint32_t> every(std::size_t points, std::uint32_t step, bool keep) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t p = std::uint32_t(points); p-- > 0;)
    if ((p % step == 0) == keep) out.push_back(p);
  return out;
}

float height(const Character& c) {
  float low = c.model().mesh.positions.front().y, high = low;
  for (const glm::vec3& p : c.model().mesh.positions) low = std::min(low, p.y), high = std::max(high, p.y);
  return high - low;
}

}  // namespace

TEST_CASE(
    "levels: a point subset deforms its points as the whole level would, its vertices' normals too, and no more") {
  Walker full, mesh;
  const std::size_t points = full.c.model().mesh.point_count();
  const std::vector<std::uint32_t> half = every(points, 2, true);
  full.c.set_levels(builtin_lod(full.c), options);
  std::vector<Character::LevelOptions> subset_options = options;
  subset_options[2].points = half;
  mesh.c.set_levels(builtin_lod(mesh.c), subset_options);
  CHECK(mesh.c.level_cost(2).points == half.size());
  CHECK(mesh.c.level_cost(2).influences < full.c.level_cost(2).influences);
  CHECK(mesh.c.level_cost(3).points == points);
  for (int f = 0; f < 30; ++f) full.frame(), mesh.frame();  // level 0: the same
  REQUIRE(full.c.set_level(2));
  REQUIRE(mesh.c.set_level(2));
  const float tolerance = 1e-6f * height(full.c);
  std::size_t bit_equal = 0;
  float largest = 0.0f, largest_normal = 0.0f;
  for (int f = 0; f < 40; ++f) {
    const std::vector<glm::vec3> before(mesh.c.positions().begin(), mesh.c.positions().end());
    full.frame(), mesh.frame();
    const auto a = full.c.positions(), b = mesh.c.positions();
    REQUIRE(b.size() == points);
    for (std::size_t p = 0; p < points; ++p) {
      if (p % 2 == 0) {
        largest = std::max(largest, glm::length(a[p] - b[p]));
        bit_equal += a[p] == b[p];
      } else if (f > 0) {
        CHECK(b[p] == before[p]);  // not the level's: untouched (the switch's update deforms the outgoing level 0)
      }
    }
    const auto na = full.c.normals(), nb = mesh.c.normals();
    REQUIRE(nb.size() == na.size());
    for (std::size_t v = 0; v < na.size(); ++v)
      if (full.c.model().mesh.vertex_point[v] % 2 == 0)
        largest_normal = std::max(largest_normal, glm::length(na[v] - nb[v]));
  }
  MESSAGE("subset against the whole level: largest difference " << largest << ", " << bit_equal << " of "
                                                                << 40 * half.size() << " bit-equal");
  CHECK(largest <= tolerance);
  CHECK(largest_normal <= 1e-5f);
  // The whole level moved the others: the check above would see them if the subset did.
  CHECK(largest_move(full.c.positions(), mesh.c.positions()) > 1e-3f);
  // Recomputed normals: a subset level transports them still (the full mesh's triangles would read stale points).
  mesh.c.set_normals_mode(Character::NormalsMode::recomputed);
  full.c.set_normals_mode(Character::NormalsMode::transported);
  full.frame(), mesh.frame();
  const auto na = full.c.normals(), nb = mesh.c.normals();
  for (std::size_t v = 0; v < na.size(); ++v)
    if (full.c.model().mesh.vertex_point[v] % 2 == 0) CHECK(glm::length(na[v] - nb[v]) <= 1e-5f);
}

TEST_CASE("levels: a switch between subsets blends the shared points and starts the new ones at their place") {
  // Level 2 deforms the points p % 3 != 0, level 3 the even ones: shared p % 6 == 2 or 4, new to level 3 p % 6 == 0.
  const auto make = [](Walker& w, std::uint32_t blend, std::uint32_t interval, const std::vector<std::uint32_t>& a,
                       const std::vector<std::uint32_t>& b) {
    std::vector<Character::LevelOptions> opts = {{true, 1}, {true, 1}, {false, 1}, {false, interval}};
    opts[2].points = a;
    opts[3].points = b;
    w.c.set_levels(builtin_lod(w.c), opts, blend);
    REQUIRE(w.c.set_level(2));
  };
  Walker probe;
  const std::size_t points = probe.c.model().mesh.point_count();
  const std::vector<std::uint32_t> thirds = every(points, 3, false), halves = every(points, 2, true);
  for (const std::uint32_t interval : {1u, 4u}) {
    CAPTURE(interval);
    Walker blended, abrupt, still;
    make(blended, 8, interval, thirds, halves);
    make(abrupt, 0, 1, thirds, halves);  // level 3's points at the pose, at once
    make(still, 8, interval, thirds, halves);
    for (int f = 0; f < 30; ++f) blended.frame(), abrupt.frame(), still.frame();
    const std::vector<glm::vec3> before(blended.c.positions().begin(), blended.c.positions().end());
    std::vector<glm::vec3> still_before(still.c.positions().begin(), still.c.positions().end());
    REQUIRE(blended.c.set_level(3));
    REQUIRE(abrupt.c.set_level(3));
    blended.frame(), abrupt.frame(), still.frame();
    const auto b = blended.c.positions(), a = abrupt.c.positions(), s = still.c.positions();
    float shared_move = 0.0f, usual = 0.0f, new_error = 0.0f, abrupt_jump = 0.0f;
    for (std::size_t p = 0; p < points; ++p) {
      if (p % 2 != 0) {
        if (p % 3 != 0) usual = std::max(usual, glm::length(s[p] - still_before[p]));
        if (p % 3 == 0) CHECK(b[p] == before[p]);  // in neither level: untouched
      } else if (p % 3 != 0) {
        shared_move = std::max(shared_move, glm::length(b[p] - before[p]));
        abrupt_jump = std::max(abrupt_jump, glm::length(a[p] - before[p]));
      } else {
        new_error = std::max(new_error, glm::length(b[p] - a[p]));  // at its place, not blended from a stale one
      }
    }
    MESSAGE("switch: shared points moved " << shared_move << " (unblended " << abrupt_jump << ", ordinary " << usual
                                           << "), new points off their place by " << new_error);
    CHECK(new_error <= 1e-6f * height(blended.c));
    CHECK(shared_move <= 1.5f * usual);
    CHECK(abrupt_jump > 2.0f * usual);  // the bones of level 3 differ: without the blend the shared points jump
    // Interpolating, no update deforms until the 4th: the new points stay at their place meanwhile.
    if (interval == 4) {
      const std::vector<glm::vec3> at_switch(a.begin(), a.end());
      for (int f = 0; f < 3; ++f) {
        CHECK_FALSE(blended.c.next_update_deforms());
        blended.frame();
        for (std::size_t p = 0; p < points; p += 6) CHECK(blended.c.positions()[p] == at_switch[p]);
      }
    } else {
      for (int f = 0; f < 8; ++f) blended.frame(), abrupt.frame();  // the blend over: the points level 3 deforms
      for (std::size_t p = 0; p < points; p += 2)
        CHECK(glm::length(blended.c.positions()[p] - abrupt.c.positions()[p]) <= 1e-6f * height(blended.c));
    }
  }
}

TEST_CASE("levels: a subset skins the morphed points as the whole level does") {
  const deform::Model model = bulged_builtin();
  Character full(model), mesh(model);
  const std::vector<std::uint32_t> half = every(model.mesh.point_count(), 2, true);
  const std::vector<Character::LevelOptions> whole = {{true, 1}, {false, 1}};
  std::vector<Character::LevelOptions> subset = whole;
  subset[1].points = half;
  deform::BoneLodSettings settings;
  settings.bones_per_level = {14};
  full.set_levels(deform::build_bone_lod(full.model(), settings), whole);
  mesh.set_levels(deform::build_bone_lod(mesh.model(), settings), subset);
  for (Character* c : {&full, &mesh}) {
    REQUIRE(c->set_morph_weight(0, 1.0f));
    REQUIRE(c->set_level(1));
    deform::Pose pose = c->skeleton().bind_pose();
    pose.rotations[3] = glm::angleAxis(0.5f, glm::vec3(0.0f, 0.0f, 1.0f));
    REQUIRE(c->set_pose(pose));
    REQUIRE(c->update(dt));
  }
  const auto na = full.normals(), nb = mesh.normals();
  for (const std::uint32_t p : half)
    CHECK(glm::length(full.positions()[p] - mesh.positions()[p]) <= 1e-6f * height(full));
  for (std::size_t v = 0; v < na.size(); ++v)
    if (model.mesh.vertex_point[v] % 2 == 0) CHECK(glm::length(na[v] - nb[v]) <= 1e-5f);
  CHECK(largest_move(full.positions(), std::span<const glm::vec3>(model.mesh.positions)) > 1e-3f);
}

TEST_CASE("levels: a point subset with deformers runs the spring chains, its points as the whole level's") {
  // The built-in character with its ponytail's spring chain and no lattices: the whole level with deformers runs the
  // springs alone, so a subset that runs them must give its points.
  const auto springs_only = [] {
    deform::Model model = deform::builtin_character();
    deform::Rig rig = deform::builtin_rig(model);
    rig.lattices.clear();
    return Character(std::move(model), rig);
  };
  Walker full(springs_only()), mesh(springs_only()), still(springs_only());
  REQUIRE(full.c.springs().chain_count() == 1);
  const std::size_t points = full.c.model().mesh.point_count();
  const std::vector<std::uint32_t> half = every(points, 2, true);
  std::vector<Character::LevelOptions> with_springs = options;  // level 1: deformers on
  with_springs[1].points = half;
  std::vector<Character::LevelOptions> without = with_springs;
  without[1].deformers = false;
  full.c.set_levels(builtin_lod(full.c), options);
  mesh.c.set_levels(builtin_lod(mesh.c), with_springs);
  still.c.set_levels(builtin_lod(still.c), without);
  for (int f = 0; f < 60; ++f) full.frame(), mesh.frame(), still.frame();  // level 0: the ponytail swinging
  for (Walker* w : {&full, &mesh, &still}) REQUIRE(w->c.set_level(1));
  float largest = 0.0f, swing = 0.0f;
  for (int f = 0; f < 60; ++f) {
    full.frame(), mesh.frame(), still.frame();
    for (std::size_t p = 0; p < points; p += 2) {
      largest = std::max(largest, glm::length(full.c.positions()[p] - mesh.c.positions()[p]));
      swing = std::max(swing, glm::length(mesh.c.positions()[p] - still.c.positions()[p]));
    }
  }
  MESSAGE("subset with springs against the whole level: " << largest << "; against the subset without: " << swing);
  CHECK(largest <= 1e-6f * height(full.c));
  CHECK(swing > 1e-3f * height(full.c));  // the springs ran: the check above would see a subset without them
}

TEST_CASE("levels: a subset running the springs waits with the lattices: back at level 0 they start from the pose") {
  // 0 -> 1 (a subset with deformers: the springs go on, the stretched arm's lattices wait) -> 0 (they come back).
  Walker still;
  still.c.set_levels(builtin_lod(still.c), options);
  const std::vector<float> ordinary = moves(still, 120, {});
  const float usual = *std::max_element(ordinary.begin(), ordinary.end());
  Walker w;
  std::vector<Character::LevelOptions> subset = options;
  const std::vector<std::uint32_t> all = every(w.c.model().mesh.point_count(), 1, true);
  subset[1].points = all;  // every point listed: a subset still, so the lattices wait
  w.c.set_levels(builtin_lod(w.c), subset, 24);
  const std::vector<float> m = moves(w, 120, {{20, 1}, {70, 0}});
  const float switched = *std::max_element(m.begin(), m.end());
  MESSAGE("largest move per frame: ordinary " << usual << ", through a subset level with springs " << switched);
  CHECK(switched <= 1.5f * usual);
  CHECK(w.c.deformers().stretch(0) > 0.01f);  // the lattices run again at level 0
}

TEST_CASE("levels: point subsets refused") {
  Character c = deform::make_builtin_character();
  const std::uint32_t points = std::uint32_t(c.model().mesh.point_count());
  const auto refused = [&](std::vector<std::uint32_t> list, bool deformers, const std::string& reason) {
    std::vector<Character::LevelOptions> opts = options;
    opts[2].points = list;
    opts[2].deformers = deformers;
    try {
      c.set_levels(builtin_lod(c), opts);
      FAIL("accepted");
    } catch (const deform::Error& error) {
      CHECK(std::string(error.what()).find("level 2") != std::string::npos);
      CHECK(std::string(error.what()).find(reason) != std::string::npos);
    }
  };
  refused({0, points, 2}, false, "out of range");
  refused({0, 5, 2, 5}, false, "listed twice");
  CHECK(c.level_count() == 1);  // the refused calls changed nothing
  std::vector<Character::LevelOptions> opts = options;
  const std::vector<std::uint32_t> some = {7, 3, 5};
  opts[2].points = some;
  c.set_levels(builtin_lod(c), opts);
  CHECK(c.level_cost(2).points == 3);
  CHECK(c.level_cost(2).bones <= 3 * 8);
}

TEST_CASE(
    "order_points_first: the listed points first, the model drawing and skinning the same; a subset level a prefix") {
  deform::Model model = deform::builtin_character();
  deform::MorphTarget target;  // with normal deltas, over points that the renumbering reorders
  target.name = "bulge";
  for (std::uint32_t p = 1; p < model.mesh.point_count(); p += 7) {
    target.points.push_back(p);
    target.position_deltas.push_back({0.0f, 0.001f * float(p % 13), 0.01f});
    target.normal_deltas.push_back({0.1f, 0.0f, 0.0f});
  }
  model.morph_targets.push_back(target);
  const deform::Model before = model;
  const std::vector<std::uint32_t> first = every(model.mesh.point_count(), 3, true);  // descending ids
  const deform::PointOrder order = deform::order_points_first(model, first);
  REQUIRE(order.point.size() == before.mesh.point_count());
  REQUIRE(order.vertex.size() == before.mesh.vertex_count());
  for (std::size_t i = 0; i < first.size(); ++i) CHECK(order.point[first[i]] == i);
  for (std::size_t p = 0; p < before.mesh.point_count(); ++p) {
    CHECK(model.mesh.positions[order.point[p]] == before.mesh.positions[p]);
    CHECK(model.weights.bones[order.point[p]] == before.weights.bones[p]);
  }
  for (std::size_t c = 0; c < before.mesh.triangles.size(); ++c) {  // every corner draws the same point, normal, UV
    const std::uint32_t v = before.mesh.triangles[c];
    CHECK(model.mesh.triangles[c] == order.vertex[v]);
    CHECK(model.mesh.vertex_point[order.vertex[v]] == order.point[before.mesh.vertex_point[v]]);
    CHECK(model.mesh.vertex_normals[order.vertex[v]] == before.mesh.vertex_normals[v]);
  }
  CHECK(std::is_sorted(model.morph_targets[0].points.begin(), model.morph_targets[0].points.end()));
  CHECK(model.morph_targets[0].points != before.morph_targets[0].points);
  // Skinned and morphed at a pose: the same points, renumbered (the same arithmetic on the same values: bit-equal).
  Character a(before), b(model);
  for (Character* c : {&a, &b}) {
    REQUIRE(c->set_morph_weight(0, 1.0f));
    deform::Pose pose = c->skeleton().bind_pose();
    pose.rotations[3] = glm::angleAxis(0.5f, glm::vec3(0.0f, 0.0f, 1.0f));
    REQUIRE(c->set_pose(pose));
    REQUIRE(c->update(dt));
  }
  const auto na = a.normals(), nb = b.normals();
  for (std::size_t p = 0; p < before.mesh.point_count(); ++p)
    CHECK(glm::length(a.positions()[p] - b.positions()[order.point[p]]) <= 1e-6f * height(a));
  for (std::size_t v = 0; v < before.mesh.vertex_count(); ++v) CHECK(glm::length(na[v] - nb[order.vertex[v]]) <= 1e-5f);
  // Refused, the model unchanged.
  const deform::Model kept = model;
  CHECK_THROWS_AS(deform::order_points_first(model, std::vector<std::uint32_t>{4, 2, 4}), deform::Error);
  CHECK_THROWS_AS(deform::order_points_first(model, std::vector<std::uint32_t>{std::uint32_t(kept.mesh.point_count())}),
                  deform::Error);
  CHECK(model.mesh.positions == kept.mesh.positions);
  CHECK(model.mesh.vertex_point == kept.mesh.vertex_point);
}

TEST_CASE("levels: a subset that is a range of points (renumbered) is skinned in place, as the whole level") {
  // From point 0 the normals are skinned in place too (vertex p is point p's own, the seams' vertices after them all,
  // as order_points_first leaves a mesh); from 100 through a buffer of the level's.
  std::uint32_t begin = 0;
  SUBCASE("from point 0") { begin = 0; }
  SUBCASE("from point 100") { begin = 100; }
  Walker full, mesh;
  const std::size_t points = full.c.model().mesh.point_count();
  const std::vector<std::uint32_t>& vertex_point = full.c.model().mesh.vertex_point;
  std::size_t seams = 0;
  for (std::size_t v = 0; v < vertex_point.size(); ++v) {
    REQUIRE((v >= points || vertex_point[v] == v));  // the built-in character's layout
    seams += v >= points && vertex_point[v] >= begin && vertex_point[v] < 1600;
  }
  CHECK(seams > 10);  // the seams' copies are checked below
  std::vector<std::uint32_t> range;
  for (std::uint32_t p = 1600; p-- > begin;) range.push_back(p);  // any order
  std::vector<Character::LevelOptions> subset_options = options;
  subset_options[3].points = range;
  full.c.set_levels(builtin_lod(full.c), options);
  mesh.c.set_levels(builtin_lod(mesh.c), subset_options);
  REQUIRE(full.c.set_level(3));
  REQUIRE(mesh.c.set_level(3));
  for (int f = 0; f < 6; ++f) full.frame(), mesh.frame();  // past the switch
  std::vector<glm::vec3> before(mesh.c.positions().begin(), mesh.c.positions().end());
  for (int f = 0; f < 9; ++f) {
    full.frame(), mesh.frame();
    const auto a = full.c.positions(), b = mesh.c.positions();
    for (std::size_t p = 0; p < points; ++p) CHECK(((p >= begin && p < 1600) ? a[p] == b[p] : b[p] == before[p]));
    const auto na = full.c.normals(), nb = mesh.c.normals();
    for (std::size_t v = 0; v < na.size(); ++v)
      if (vertex_point[v] >= begin && vertex_point[v] < 1600) CHECK(na[v] == nb[v]);
  }
  CHECK(largest_move(full.c.positions(), before) > 1e-3f);
}

namespace {

// The frame a renderer draws from Character::interpolation(): from + share · (to − from), per point.
glm::vec3 drawn(const Character::Interpolation& i, std::size_t p) {
  return i.from[p] + i.share * (i.to[p] - i.from[p]);
}

// Two walkers through the same frames and set_level calls (frame -> level), one interpolating on the CPU, the other
// on the renderer: what the renderer draws is what the CPU shows, on the shown level's points (`member(level, p)`:
// whether the level deforms point p), every update; the buffers move as interpolation() says.
template <class Member>
void compare_interpolations(Walker& cpu, Walker& gpu, Member&& member, int frames,
                            const std::vector<std::pair<int, std::size_t>>& schedule) {
  gpu.c.settings.renderer_interpolates = true;
  const float tolerance = 1e-5f * height(cpu.c);
  int interpolated = 0, swapped = 0;
  float largest = 0.0f;
  Character::Interpolation last = gpu.c.interpolation();
  std::vector<glm::vec3> last_to;
  for (int f = 0; f < frames; ++f) {
    for (const auto& [at, level] : schedule)
      if (at == f) {
        REQUIRE(cpu.c.set_level(level));
        REQUIRE(gpu.c.set_level(level));
      }
    // Once, mid-interval: the renderer's interpolation given up and taken up again between deformed updates.
    if (f == frames / 2) gpu.c.settings.renderer_interpolates = false;
    if (f == frames / 2 + 1) gpu.c.settings.renderer_interpolates = true;
    const bool deforms = gpu.c.next_update_deforms();
    REQUIRE(deforms == cpu.c.next_update_deforms());
    last_to.assign(last.to.begin(), last.to.end());
    cpu.frame(), gpu.frame();
    const Character::Interpolation now = gpu.c.interpolation();
    const auto shown = cpu.c.positions();
    REQUIRE(now.from.size() == shown.size());
    REQUIRE(now.to.size() == shown.size());
    CHECK(now.to.data() == gpu.c.positions().data());
    for (std::size_t p = 0; p < shown.size(); ++p)
      if (member(gpu.c.level(), p)) largest = std::max(largest, glm::length(drawn(now, p) - shown[p]));
    if (now.from.data() != now.to.data()) {
      ++interpolated;
      CHECK(now.share > 0.0f);
      CHECK(now.share <= 1.0f);
      if (!deforms) {
        if (last.from.data() != last.to.data()) {  // nothing moved: the buffers and versions as they were
          CHECK(now.from.data() == last.from.data());
          CHECK(now.to.data() == last.to.data());
          CHECK(now.from_version == last.from_version);
          CHECK(now.to_version == last.to_version);
        }
      } else if (now.from_version == last.to_version) {
        // A whole interval: the new `from` is the old `to` (the same buffer, swapped rather than copied).
        ++swapped;
        CHECK(last.share == 1.0f);
        CHECK(now.from.data() == last.to.data());
        CHECK(std::equal(now.from.begin(), now.from.end(), last_to.begin()));
      }
      if (deforms) CHECK(now.to_version != last.to_version);
    } else {
      CHECK(now.share == 0.0f);
      CHECK(now.from_version == now.to_version);
      CHECK(now.from_version != last.to_version);  // without the renderer's interpolation every update moves them
    }
    last = now;
  }
  MESSAGE("renderer against CPU interpolation: largest difference "
          << largest << " (tolerance " << tolerance << "), " << interpolated << " of " << frames
          << " updates interpolated, " << swapped << " whole intervals swapped");
  CHECK(largest <= tolerance);
  CHECK(interpolated > frames / 2);  // the comparison above did see the renderer's interpolation
  CHECK(swapped > 5);
}

}  // namespace

TEST_CASE("levels: interpolated on the renderer, the frames drawn are the CPU's, through switches, blends, subsets") {
  // Level 1 every 2nd update on a third of the points, level 2 every 4th on the even ones, level 3 every 4th on all:
  // switches between them mid-interval, blended or not, to and from level 0 that deforms every update.
  const auto member = [](std::size_t level, std::size_t p) {
    return level == 1 ? p % 3 == 0 : level == 2 ? p % 2 == 0 : true;
  };
  const std::vector<std::pair<int, std::size_t>> schedule = {{5, 3},  {18, 2},  {21, 1},  {30, 3}, {33, 0}, {37, 2},
                                                             {50, 3}, {62, 1},  {65, 2},  {70, 0}, {71, 3}, {90, 2},
                                                             {99, 3}, {110, 1}, {125, 3}, {142, 2}};
  const std::size_t points = deform::builtin_character().mesh.point_count();
  const std::vector<std::uint32_t> thirds = every(points, 3, true), halves = every(points, 2, true);
  std::vector<Character::LevelOptions> opts = {{true, 1}, {true, 2}, {false, 4}, {false, 4}};
  opts[1].points = thirds;
  opts[2].points = halves;
  const auto make_options = [&](const Character& c) {
    REQUIRE(c.model().mesh.point_count() == points);
    return opts;
  };
  SUBCASE("the built-in character: lattices stretched, the ponytail's springs") {
    for (const std::uint32_t blend : {8u, 0u}) {
      CAPTURE(blend);
      Walker cpu, gpu;
      cpu.c.set_levels(builtin_lod(cpu.c), make_options(cpu.c), blend);
      gpu.c.set_levels(builtin_lod(gpu.c), make_options(gpu.c), blend);
      for (int f = 0; f < 30; ++f) cpu.frame(), gpu.frame();  // level 0: the springs and lattices going
      compare_interpolations(cpu, gpu, member, 160, schedule);
    }
  }
  SUBCASE("a morphed character without a rig") {
    const deform::Model model = bulged_builtin();
    Walker cpu{Character(model)}, gpu{Character(model)};
    for (Walker* w : {&cpu, &gpu}) {
      REQUIRE(w->c.set_morph_weight(0, 0.7f));
      w->c.set_levels(builtin_lod(w->c), make_options(w->c), 6);
    }
    compare_interpolations(cpu, gpu, member, 160, schedule);
  }
}

TEST_CASE("levels: without levels or the renderer's interpolation, interpolation() is positions() at share 0") {
  Walker plain, levelled;
  levelled.c.set_levels(builtin_lod(levelled.c), options);
  REQUIRE(levelled.c.set_level(3));               // every 4th update, interpolated on the CPU
  plain.c.settings.renderer_interpolates = true;  // no levels: nothing to interpolate
  for (int f = 0; f < 6; ++f) {
    plain.frame(), levelled.frame();
    for (Walker* w : {&plain, &levelled}) {
      const Character::Interpolation i = w->c.interpolation();
      CHECK(i.from.data() == w->c.positions().data());
      CHECK(i.to.data() == w->c.positions().data());
      CHECK(i.from.size() == w->c.positions().size());
      CHECK(i.share == 0.0f);
      CHECK(i.from_version == i.to_version);
    }
  }
}
