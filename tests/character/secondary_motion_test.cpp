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
#ifdef DEFORM_HAVE_IMPORT
#include <filesystem>

#include "deform/import/import.hpp"
#endif

namespace {

// The built-in rig with inertia on the arm's lattices (the hand carried by their far faces' motion) and a spring
// chain on the right hand's fingers.
deform::Rig jiggling_rig(const deform::Model& model) {
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& lattice : rig.lattices) {
    lattice.motion.inertia = 1.0f;
    lattice.motion.far_share = 1.0f;  // the hand lags with the forearm's far face
  }
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
      : character(deform::builtin_character(), rig),
        clip(deform::builtin_walk(character.model())),
        pose(character.skeleton().bind_pose()),
        later(pose) {}
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
  const glm::vec3 target =
      walk.character.bone_position(walk.character.skeleton().find("clavicle_l")) + glm::vec3(0.9f, 0.1f, 0.3f);
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

namespace {

// Distance from p to the segment a–b.
float segment_distance(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  const glm::vec3 ab = b - a;
  const float t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0f, 1.0f);
  return glm::length(p - (a + t * ab));
}

}  // namespace

TEST_CASE("the built-in ponytail swings behind the walking head, stays out of the body, and settles when still") {
  const deform::Model model = deform::builtin_character();
  const deform::Rig rig = deform::builtin_rig(model);
  REQUIRE(rig.spring_chains.size() == 1);
  deform::Rig rigid_rig = rig;  // the same walk without the chain: where the ponytail is carried rigidly
  rigid_rig.spring_chains.clear();
  Walk walk(rig), rigid(rigid_rig);
  const deform::Skeleton& sk = walk.character.skeleton();
  const std::int32_t chest = sk.find("chest"), neck = sk.find("neck"), head = sk.find("head");
  const std::int32_t last = sk.find("ponytail4");
  REQUIRE(walk.character.springs().chain_count() == 1);
  float swing = 0.0f, nearest_chest = 1e9f, nearest_neck = 1e9f, nearest_head = 1e9f;
  for (int n = 0; n <= 180; ++n) {  // 3 s at 60 Hz
    const double t = n / 60.0;
    walk.frame(t, n == 0 ? 0.0f : 1.0f / 60.0f, true);
    rigid.frame(t, n == 0 ? 0.0f : 1.0f / 60.0f, true);
    const auto points = walk.character.springs().points(0);
    REQUIRE(points.size() == 5);
    if (t > 1.0) swing = std::max(swing, glm::length(points[3] - rigid.character.bone_position(last)));
    const glm::vec3 c = walk.character.bone_position(chest), k = walk.character.bone_position(neck),
                    h = walk.character.bone_position(head);
    const glm::vec3 up = glm::normalize(h - k);
    for (std::size_t i = 1; i < points.size(); ++i) {
      nearest_chest = std::min(nearest_chest, segment_distance(points[i], c + 0.2f * (k - c), k));
      nearest_neck = std::min(nearest_neck, segment_distance(points[i], k, h));
      nearest_head = std::min(nearest_head, segment_distance(points[i], h + 0.07f * up, h + 0.15f * up));
    }
  }
  MESSAGE("ponytail swing " << swing << " m; nearest chest " << nearest_chest << ", neck " << nearest_neck << ", head "
                            << nearest_head);
  CHECK(swing > 0.01f);                           // centimetres off the rigidly carried ponytail
  CHECK(swing < 0.15f);                           // ... a swing, not a flail
  CHECK(nearest_chest >= 0.11f + 0.02f - 1e-3f);  // the capsules' radii plus the chain's
  CHECK(nearest_neck >= 0.055f + 0.02f - 1e-3f);
  CHECK(nearest_head >= 0.085f + 0.02f - 0.01f);  // the head's capsule, its axis estimated from neck → head

  // Still in the bind pose: it sags under gravity at first, then keeps still.
  Walk still(rig);
  const deform::Pose bind = still.character.skeleton().bind_pose();
  std::vector<glm::vec3> tips;
  for (int n = 0; n <= 180; ++n) {
    REQUIRE(still.character.set_pose(bind, bind, 1e-3f));
    REQUIRE(still.character.update(n == 0 ? 0.0f : 1.0f / 60.0f));
    tips.push_back(still.character.springs().points(0).back());
  }
  const float sag = glm::length(tips.back() - tips.front());
  float late = 0.0f;
  for (std::size_t n = 150; n < tips.size(); ++n) late = std::max(late, glm::length(tips[n] - tips.back()));
  MESSAGE("still: sag " << sag << " m, movement over the last half second " << late << " m");
  CHECK(sag > 1e-3f);
  CHECK(sag < 0.08f);  // 6.1 cm at the tip: g/ω² ≈ 3.3 cm per tail, along the chain
  CHECK(late < 1e-3f);
  CHECK(tips.back().y < tips.front().y);
}

TEST_CASE("flesh: the tuned jiggle keeps every limb's length within 2% and every lattice's volume within 3%") {
  // Every limb's lattice with its part's default_lattice_motion, on the built-in walk and run, against the same clip
  // with no inertia (tools/motion_study --flesh-csv draws it; docs/elasticity.md, "Measured").
  const deform::Rig tuned = motion_study::tuned_full_rig();
  for (const char* clip : {"walk", "run"}) {
    const motion_study::FleshMeasure m = motion_study::measure_flesh(tuned, clip, 60.0, 2.0);
    INFO(clip << ": limb " << m.limb_percent << "% (" << m.worst_limb << "), volume " << m.volume_percent << "% ("
              << m.worst_lattice << "), jiggle " << m.jiggle << " m");
    CHECK(m.limb_percent < 2.0);
    CHECK(m.volume_percent < 3.0);
    CHECK(m.jiggle > 0.01);  // centimetres: still visible
  }
  // The viewer's inertia 1 on every lattice, with the parts' bounds and far face shares: the walk's limbs still keep
  // their length (before the bound and the split, the stepping leg grew by about 8% of the body's height).
  deform::Rig heavy = tuned;
  for (deform::LatticeSpec& lattice : heavy.lattices) lattice.motion.inertia = 1.0f;
  const motion_study::FleshMeasure walk = motion_study::measure_flesh(heavy, "walk", 60.0, 2.0);
  INFO("walk at inertia 1: limb " << walk.limb_percent << "% (" << walk.worst_limb << ")");
  CHECK(walk.limb_percent < 2.0);
  CHECK(walk.volume_percent < 3.0);
}

TEST_CASE("flesh at the viewer's inertia 1: a scale of each part's tuned inertia, the run's limbs within 2%") {
  // The viewer's slider and `deform simulate --inertia` scale each lattice's tuned inertia (set_inertia_scale): at 1
  // the rig as shipped (parts, no inertia) moves exactly as the tuned rig; at inertia 1 on every lattice, as the
  // slider set it before, the run's left arm changed length by 6.2%.
  const deform::Rig shipped = deform::builtin_full_rig(deform::builtin_character());
  for (const deform::LatticeSpec& lattice : shipped.lattices) CHECK(lattice.motion.inertia == 0.0f);
  const motion_study::FleshMeasure slider = motion_study::measure_flesh(shipped, "run", 60.0, 2.0, 1.0f);
  const motion_study::FleshMeasure tuned =
      motion_study::measure_flesh(motion_study::tuned_full_rig(), "run", 60.0, 2.0);
  INFO("run at the slider's 1: limb " << slider.limb_percent << "% (" << slider.worst_limb << "), volume "
                                      << slider.volume_percent << "%, jiggle " << slider.jiggle << " m");
  CHECK(slider.limb_length == tuned.limb_length);
  CHECK(slider.jiggle == tuned.jiggle);
  CHECK(slider.limbs.size() == 4);
  CHECK(slider.limb_percent < 2.0);
  CHECK(slider.volume_percent < 3.0);
  CHECK(slider.jiggle > 0.01);
  // Half the slider: half of each part's inertia, still jiggling, less.
  const motion_study::FleshMeasure half = motion_study::measure_flesh(shipped, "run", 60.0, 2.0, 0.5f);
  CHECK(half.jiggle > 0.005);
  CHECK(half.jiggle < slider.jiggle);
  CHECK(half.limb_percent < 2.0);
}

TEST_CASE("flesh on imported characters: default_rig at the tuned inertia keeps limbs within 2%, volumes within 3%") {
#ifdef DEFORM_HAVE_IMPORT
  // Debian's assimp-testmodels on their own clips with the viewer's defaults (docs/elasticity.md, "Measured").
  for (const motion_study::ImportedClip& c : motion_study::imported_clips()) {
    if (!std::filesystem::exists(c.file)) {
      MESSAGE("skipped: " << c.file << " is not installed (assimp-testmodels)");
      continue;
    }
    const std::string file = c.file, clip_name = c.clip;
    CAPTURE(file);
    CAPTURE(clip_name);
    const deform::ImportedModel imported = deform::import_model(c.file);
    const deform::Rig rig = deform::default_rig(imported.model);
    // Every lattice of the default rig knows its part (an arm whose hand has no lattice still has an upper arm).
    for (const deform::LatticeSpec& lattice : rig.lattices) {
      CAPTURE(lattice.name);
      CHECK(lattice.motion.part != deform::BodyPart::unspecified);
      if (lattice.name.starts_with("UpperArm") || lattice.name.starts_with("Thigh"))
        CHECK(lattice.motion.part == deform::BodyPart::upper_limb);
      if (lattice.name.starts_with("LowerArm") || lattice.name.starts_with("Shin"))
        CHECK(lattice.motion.part == deform::BodyPart::lower_limb);
    }
    const auto clip = std::find_if(imported.clips.begin(), imported.clips.end(),
                                   [&](const deform::Animation& a) { return a.name == clip_name; });
    REQUIRE(clip != imported.clips.end());
    const motion_study::FleshMeasure m =
        motion_study::measure_flesh(imported.model, *clip, rig, 60.0, motion_study::measured_seconds(*clip), 1.0f);
    INFO("limb " << m.limb_percent << "% (" << m.worst_limb << "), volume " << m.volume_percent << "% ("
                 << m.worst_lattice << "), jiggle " << m.jiggle_percent() << "% of the height");
    CHECK(m.limbs.size() == 4);  // two arms and two legs, or four legs
    CHECK(m.limb_percent < 2.0);
    CHECK(m.volume_percent < 3.0);
    CHECK(m.jiggle_percent() > 0.02);  // still visible: the rigid clip's skin is not what shows
  }
#else
  MESSAGE("skipped: built without deform::import");
#endif
}

TEST_CASE("the whole character at any frame rate: every point and the ponytail within 0.5% of 240 Hz") {
  // Every limb's lattice (tuned, and at inertia 1) and the ponytail, on the run, posed with a millisecond lead,
  // compared every 1/3 s. The ponytail's first head took its velocity from the lead's rate, off by half the lead
  // times the acceleration: sub-steps inside 30, 60 and 144 Hz frames and those on 240 Hz frames parted by 0.6-1%.
  const deform::Rig rig = motion_study::tuned_full_rig();
  for (const float inertia : {-1.0f, 1.0f}) {
    const motion_study::CharacterPaths reference = motion_study::play_character(rig, "run", 240.0, 2.0, 3.0, inertia);
    const double all = motion_study::amplitude_of(reference.surface);
    const double tail = motion_study::amplitude_of(reference.ponytail);
    for (const double hz : {30.0, 60.0, 144.0}) {
      const motion_study::CharacterPaths run = motion_study::play_character(rig, "run", hz, 2.0, 3.0, inertia);
      const double points = 100.0 * motion_study::largest_difference(run.surface, reference.surface) / all;
      const double ponytail = 100.0 * motion_study::largest_difference(run.ponytail, reference.ponytail) / tail;
      INFO("inertia " << (inertia < 0.0f ? "tuned" : "1") << ", " << hz << " Hz: points " << points << "%, ponytail "
                      << ponytail << "%");
      CHECK(points < 0.5);
      CHECK(ponytail < 0.2);
    }
  }
}
