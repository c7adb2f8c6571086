// Secondary motion on the built-in character: a walk jiggles the arm's lattices and swings a spring chain, the same
// at every frame rate; a still pose stays still; reach still arrives while walking.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "study.hpp"  // tools/motion_study

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
// at `hz`, the pose with its lead or without.
std::vector<glm::vec3> walk_points(const deform::Rig& rig, double hz, bool lead, double seconds) {
  Walk walk(rig);
  const std::int32_t hand = walk.character.skeleton().find("hand_l");
  std::vector<glm::vec3> out;
  const std::vector<double> times = motion_study::frame_times(hz, seconds, false);
  for (std::size_t n = 0; n < times.size(); ++n) {
    walk.frame(times[n], n == 0 ? 0.0f : float(times[n] - times[n - 1]), lead);
    if (n == 0 || !motion_study::at_checkpoint(times[n])) continue;
    out.push_back(walk.character.bone_position(hand));
    out.push_back(walk.character.springs().chain_count() > 0 ? walk.character.springs().points(0).back()
                                                            : glm::vec3(0.0f));
  }
  return out;
}

}  // namespace

// The walk's spread over frame rates and scales is measured by tools/motion_study (motion_study_check).

TEST_CASE("the jiggle is real: the walking hand leaves the rigid walk's path, and a still pose stays still") {
  const deform::Model model = deform::builtin_character();
  const std::vector<glm::vec3> rigid = walk_points(deform::builtin_rig(model), 60.0, true, 1.0);
  const std::vector<glm::vec3> jiggly = walk_points(jiggling_rig(model), 60.0, true, 1.0);
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
  // An instance has the rig's chains, at rest, with this character's settings.
  deform::SpringChainSpec tuned = c.springs().spec(0);
  tuned.frequency = 5.0f;
  c.springs().set_settings(0, tuned);
  const deform::Character copy = c.instance();
  REQUIRE(copy.springs().chain_count() == 1);
  CHECK(copy.springs().spec(0).frequency == 5.0f);
}
