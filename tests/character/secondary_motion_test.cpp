// Secondary motion on the built-in character: a walk jiggles the arm's lattices and swings a spring chain, the same
// at every frame rate; a still pose stays still; reach still arrives while walking.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"

namespace {

// The built-in rig with inertia on the arm's lattices and a spring chain on the right hand's fingers.
deform::Rig jiggling_rig(const deform::Model& model) {
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& lattice : rig.lattices) lattice.motion.inertia = 1.0f;
  deform::SpringChainSpec fingers;
  fingers.name = "fingers_r";
  fingers.bones = {model.skeleton.find("fingers1_r"), model.skeleton.find("fingers2_r")};
  fingers.frequency = 3.0f;
  fingers.damping_ratio = 0.4f;
  fingers.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  rig.spring_chains = {fingers};
  return rig;
}

struct Walk {
  deform::Character character;
  deform::Animation clip;
  deform::Pose pose, later;
  explicit Walk(const deform::Rig& rig)
      : character(deform::builtin_character(), rig), clip(deform::builtin_walk(character.model())),
        pose(character.skeleton().bind_pose()), later(pose) {}
  void sample(float t, deform::Pose& into) {
    into = character.skeleton().bind_pose();
    deform::SamplingJob job;
    job.animation = &clip;
    job.time = t;
    job.rotations = into.rotations;
    job.translations = into.translations;
    REQUIRE(job.run());
  }
  // Poses the character at time t (with the pose a millisecond later when `lead`) and steps it by dt.
  void frame(double t, float dt, bool lead) {
    sample(float(t), pose);
    if (lead) {
      sample(float(t + 1e-3), later);
      REQUIRE(character.set_pose(pose, later, 1e-3f));
    } else {
      REQUIRE(character.set_pose(pose));
    }
    REQUIRE(character.update(dt));
  }
};

// The left hand (carried by the jiggling lattices) and the fingers' tip at every 1/15 s over `seconds`, stepped
// at `hz` (or jittered steps averaging 240 Hz).
std::vector<glm::vec3> walk_points(const deform::Rig& rig, double hz, bool jitter, bool lead, double seconds = 2.0) {
  Walk walk(rig);
  std::mt19937 rng(5);
  const std::int32_t hand = walk.character.skeleton().find("hand_l");
  std::vector<glm::vec3> out;
  walk.frame(0.0, 0.0f, lead);
  const int per = std::max(1, int(std::lround(hz / 15.0)));
  for (int c = 0; c < int(std::lround(seconds * 15.0)); ++c) {
    std::vector<double> cuts;
    for (int k = 1; k < per; ++k)
      cuts.push_back(jitter ? std::uniform_real_distribution<double>(0.0, 1.0)(rng) : double(k) / per);
    std::sort(cuts.begin(), cuts.end());
    cuts.push_back(1.0);
    double t = c / 15.0;
    for (const double cut : cuts) {
      const double next = (c + cut) / 15.0;
      walk.frame(next, float(next - t), lead);
      t = next;
    }
    out.push_back(walk.character.bone_position(hand));
    out.push_back(walk.character.springs().chain_count() > 0 ? walk.character.springs().points(0).back()
                                                            : glm::vec3(0.0f));
  }
  return out;
}

// The largest spread (max - min over runs) of either point, as a percentage of that point's motion (max - min over
// the run at 240 Hz, per coordinate, the largest).
double spread_percent(const std::vector<std::vector<glm::vec3>>& runs) {
  double worst = 0.0;
  for (std::size_t which = 0; which < 2; ++which) {
    double amplitude = 0.0, spread = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      double lo = 1e30, hi = -1e30;
      for (std::size_t k = which; k < runs.back().size(); k += 2)
        lo = std::min(lo, double(runs.back()[k][axis])), hi = std::max(hi, double(runs.back()[k][axis]));
      amplitude = std::max(amplitude, hi - lo);
      for (std::size_t k = which; k < runs.front().size(); k += 2) {
        double a = 1e30, b = -1e30;
        for (const auto& run : runs) a = std::min(a, double(run[k][axis])), b = std::max(b, double(run[k][axis]));
        spread = std::max(spread, b - a);
      }
    }
    worst = std::max(worst, 100.0 * spread / amplitude);
  }
  return worst;
}

}  // namespace

TEST_CASE("a walk with jiggle: the same at 30, 60, 144, 240 Hz and jittered frames within 0.5%, at 15 Hz within 1%") {
  // The lattices feel the rest's acceleration, which a cubic between frames has to O(h²): 15 Hz frames leave the
  // jiggling hand about 4 mm off the 240 Hz curve, 30 Hz about 1 mm (docs/elasticity.md).
  const deform::Model model = deform::builtin_character();
  const deform::Rig rig = jiggling_rig(model);
  std::vector<std::vector<glm::vec3>> runs;
  for (const double hz : {30.0, 60.0, 144.0}) runs.push_back(walk_points(rig, hz, false, true));
  runs.push_back(walk_points(rig, 240.0, true, true));
  runs.push_back(walk_points(rig, 240.0, false, true));
  const double spread = spread_percent(runs);
  MESSAGE("walk spread with the pose's lead, 30-240 Hz and jittered: " << spread << "%");
  CHECK(spread < 0.5);
  runs.insert(runs.begin(), walk_points(rig, 15.0, false, true));
  const double with_15 = spread_percent(runs);
  MESSAGE("... and 15 Hz: " << with_15 << "%");
  CHECK(with_15 < 1.0);
  // Without the lead the motion between frames is linear: worse, still bounded.
  std::vector<std::vector<glm::vec3>> linear;
  for (const double hz : {30.0, 60.0, 240.0}) linear.push_back(walk_points(rig, hz, false, false));
  const double linear_spread = spread_percent(linear);
  MESSAGE("walk spread without it (30-240 Hz): " << linear_spread << "%");
  CHECK(linear_spread > spread);
  CHECK(linear_spread < 10.0);
}

TEST_CASE("the jiggle is real: the walking hand leaves the rigid walk's path, and a still pose stays still") {
  const deform::Model model = deform::builtin_character();
  const std::vector<glm::vec3> rigid = walk_points(deform::builtin_rig(model), 60.0, false, true, 1.0);
  const std::vector<glm::vec3> jiggly = walk_points(jiggling_rig(model), 60.0, false, true, 1.0);
  float largest = 0.0f;
  for (std::size_t k = 0; k < rigid.size(); k += 2) largest = std::max(largest, glm::length(jiggly[k] - rigid[k]));
  MESSAGE("largest lag of the hand behind the rigid walk: " << largest << " m");
  CHECK(largest > 0.005f);
  CHECK(largest < 0.3f);
  // Standing in the bind pose for two seconds: nothing moves but the fingers settling under gravity.
  deform::Character still(deform::builtin_character(), jiggling_rig(model));
  const std::int32_t hand = still.skeleton().find("hand_l");
  const glm::vec3 start = still.bone_position(hand);
  for (int n = 0; n < 120; ++n) REQUIRE(still.update(1.0f / 60.0f));
  CHECK(glm::length(still.bone_position(hand) - start) < 1e-5f);
  // A reached pose while walking: the reach still arrives (the reached joints ride with the body).
  Walk walk(jiggling_rig(model));
  walk.frame(0.0, 0.0f, true);
  const glm::vec3 target = walk.character.bone_position(walk.character.skeleton().find("clavicle_l")) +
                           glm::vec3(0.9f, 0.1f, 0.3f);
  float distance = 0.0f;
  for (int n = 1; n <= 180; ++n) {
    walk.sample(float(n) / 60.0f, walk.pose);
    walk.sample(float(n) / 60.0f + 1e-3f, walk.later);
    REQUIRE(walk.character.set_pose(walk.pose, walk.later, 1e-3f));
    const deform::ReachResult result = walk.character.reach(hand, target);
    REQUIRE(result.status);
    REQUIRE(walk.character.update(1.0f / 60.0f));
    distance = result.distance;
  }
  CHECK(distance < 0.05f);
}

TEST_CASE("set_pose with a lead refuses what set_pose refuses, and a lead that is not > 0") {
  deform::Character c(deform::builtin_character(), jiggling_rig(deform::builtin_character()));
  const deform::Pose bind = c.skeleton().bind_pose();
  CHECK_FALSE(c.set_pose(bind, bind, 0.0f));
  CHECK_FALSE(c.set_pose(bind, bind, NAN));
  deform::Pose bad = bind;
  bad.rotations.pop_back();
  CHECK_FALSE(c.set_pose(bind, bad, 1e-3f));
  CHECK_FALSE(c.set_pose(bad, bind, 1e-3f));
  CHECK(c.set_pose(bind, bind, 1e-3f));
  // An instance has the rig's chains, at rest.
  const deform::Character copy = c.instance();
  CHECK(copy.springs().chain_count() == 1);
}
