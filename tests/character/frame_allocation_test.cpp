// The per-frame path allocates nothing: 1,000 frames of pose, reach, update and normals (transported, then
// recomputed) on the built-in character and on an imported one, with a global operator new that counts (this
// executable's own, so no other test sees it).
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/skeleton.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#endif

#include "allocation_counter.hpp"

using deform::Character;

namespace {

constexpr int frames = 1000;
constexpr float dt = 1.0f / 60.0f;

// What a frame loop saw, counted without allocating (doctest's assertions stay out of the loop).
struct Tally {
  long allocations = 0;
  int refused = 0;          // calls that returned a failure Status
  const char* reason = "";  // the first one's reason
  int reaches = 0;
  float largest_stretch = 0.0f;
  float normals_checksum = 0.0f;
  void note(const deform::Status& status) {
    if (status) return;
    if (refused++ == 0) reason = status.reason();
  }
};

void check(const Tally& tally) {
  MESSAGE(tally.reaches << " reaches, largest stretch " << tally.largest_stretch << ", " << tally.allocations
                        << " allocations, " << tally.refused << " refusals");
  CAPTURE(tally.reason);
  CHECK(tally.allocations == 0);
  CHECK(tally.refused == 0);
  CHECK(tally.reaches >= 5);
  CHECK(tally.largest_stretch > 0.01f);  // the lattices did stretch
  CHECK(std::isfinite(tally.normals_checksum));
}

std::vector<int> escaped;  // the control allocation below lands here, so no optimiser can drop it

}  // namespace

TEST_CASE("the counting operator new sees the library's allocations") {
  const long before = allocations.load();
  escaped.assign(1000, 1);
  const Character c = deform::make_builtin_character();
  CHECK(allocations.load() - before > 100);
  CHECK(c.positions().size() > 1000);
}

TEST_CASE(
    "1,000 frames of the built-in character allocate nothing: pose, reach (pole, swing-twist, two-bone), release, "
    "update, normals") {
  // Held in a vector, moved there after construction: a move keeps the storage the frame relies on.
  std::vector<Character> characters;
  characters.push_back(deform::make_builtin_character());
  Character& c = characters.front();
  const deform::Skeleton& skeleton = c.skeleton();
  const std::int32_t hand_l = skeleton.find("hand_l"), hand_r = skeleton.find("hand_r");
  const std::int32_t foot_l = skeleton.find("foot_l"), spine = skeleton.find("spine"), neck = skeleton.find("neck");
  REQUIRE(hand_l > 0);
  REQUIRE(hand_r > 0);
  REQUIRE(foot_l > 0);
  const glm::vec3 shoulder = c.bone_position(skeleton.find("clavicle_l"));
  deform::Pose pose = skeleton.bind_pose();  // rewritten in place every frame
  const deform::Pose bind = pose;

  // Normals transported (the default) until frame 700, recomputed after: the recomputed mode's scratch is allocated
  // by its first set_normals_mode, at set-up.
  c.set_normals_mode(Character::NormalsMode::recomputed);
  c.set_normals_mode(Character::NormalsMode::transported);
  Tally tally;
  const long before = allocations.load();
  for (int frame = 0; frame < frames; ++frame) {
    const float t = float(frame) * dt;
    if (frame == 700) c.set_normals_mode(Character::NormalsMode::recomputed);
    // The pose: the bind pose with the spine and the neck swaying (Euler angles within their limits).
    std::copy(bind.rotations.begin(), bind.rotations.end(), pose.rotations.begin());
    skeleton.set_euler(pose, spine, skeleton.bone(spine).bind_rotation + glm::vec3(5.0f * std::sin(t), 0.0f, 0.0f));
    skeleton.set_euler(pose, neck, glm::vec3(0.0f, 20.0f * std::sin(0.7f * t), 0.0f));
    tally.note(c.set_pose(pose));
    // Reach far at 100 (the arm stretches), elsewhere in between (the chain changes with the effector), let go at
    // 500; from 100 to 500 the reach follows the moving pose every frame, as a viewer playing a clip does.
    const bool reaching = frame >= 100 && frame < 500;
    if (reaching) {
      const int phase = (frame - 100) / 60;
      const std::int32_t effector = phase == 2 ? hand_r : phase == 4 ? foot_l : hand_l;
      const glm::vec3 target = effector == hand_l   ? shoulder + glm::vec3(0.9f + 0.1f * float(phase), 0.2f, 0.3f)
                               : effector == hand_r ? glm::vec3(-0.4f, 1.3f, 0.4f)
                                                    : glm::vec3(0.2f, 0.3f, 0.3f);
      // Phases 1 and 3 reach with a pole, 3 with swing-twist limits too (the chain is rebuilt with them), 5 with the
      // two-bone solver and soften.
      c.settings.use_reach_pole = phase % 2 == 1;
      c.settings.reach_pole = shoulder + glm::vec3(0.0f, -0.5f, 1.0f);
      c.settings.reach_limits = phase == 3 ? Character::JointLimits::swing_twist : Character::JointLimits::euler;
      c.settings.reach_solver = phase == 5 ? Character::ReachSolver::two_bone : Character::ReachSolver::ccd;
      c.settings.reach_soften = 0.2f;
      const deform::ReachResult result = c.reach(effector, target);
      tally.note(result.status);
      ++tally.reaches;
    }
    if (frame == 500) c.release();
    tally.note(c.update(dt));
    const auto normals = c.normals();
    tally.normals_checksum += normals[std::size_t(frame) % normals.size()].x;
    tally.largest_stretch = std::max(tally.largest_stretch, c.stretch());
  }
  tally.allocations = allocations.load() - before;
  check(tally);
  CHECK(std::abs(c.stretch()) < 0.05f * tally.largest_stretch);  // 500 frames after the release: settled back
}

TEST_CASE(
    "1,000 frames of secondary motion allocate nothing: a clip with its lead, spring chains, inertial lattices, "
    "reach") {
  const deform::Model model = deform::builtin_character();
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& lattice : rig.lattices) lattice.motion = {1.0f, glm::vec3(0.0f, -9.81f, 0.0f), 1.0f};
  deform::SpringChainSpec fingers;
  fingers.name = "fingers_r";
  fingers.bones = {model.skeleton.find("fingers1_r"), model.skeleton.find("fingers2_r")};
  fingers.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  fingers.radius = 0.01f;
  fingers.colliders = {0};
  rig.colliders = {{model.skeleton.find("thigh_r"), glm::vec3(0.0f), glm::vec3(0.0f, -0.3f, 0.0f), 0.07f}};
  rig.spring_chains = {fingers};
  std::vector<Character> characters;
  characters.emplace_back(deform::builtin_character(), rig);
  Character& c = characters.front();
  const deform::Animation walk = deform::builtin_walk(c.model());
  deform::Pose pose = c.skeleton().bind_pose(), later = pose;
  deform::SamplingJob sampling;
  sampling.animation = &walk;
  const std::int32_t hand = c.skeleton().find("hand_l");
  const glm::vec3 shoulder = c.bone_position(c.skeleton().find("clavicle_l"));
  Tally tally;
  const long before = allocations.load();
  for (int frame = 0; frame < frames; ++frame) {
    for (deform::Pose* p : {&pose, &later}) {
      sampling.time = float(frame) * dt + (p == &later ? 1e-3f : 0.0f);
      sampling.rotations = p->rotations;
      sampling.translations = p->translations;
      tally.note(sampling.run());
    }
    tally.note(c.set_pose(pose, later, 1e-3f));
    if (frame >= 100 && frame < 500) {
      tally.note(c.reach(hand, shoulder + glm::vec3(1.0f, 0.2f, 0.3f)).status);
      ++tally.reaches;
    }
    if (frame == 500) c.release();
    if (frame == 800) c.springs().reset();
    tally.note(c.update(frame % 7 == 0 ? 0.5f * dt : dt));
    tally.normals_checksum += c.normals()[std::size_t(frame) % 100].z;
    tally.largest_stretch = std::max(tally.largest_stretch, c.stretch());
  }
  tally.allocations = allocations.load() - before;
  check(tally);
}

TEST_CASE(
    "1,000 frames of a morphed character allocate nothing: weights from a clip, by name and index, reach, "
    "update, normals (transported and recomputed)") {
  deform::Model model = deform::builtin_character();
  // Two targets: one over every point (with normal deltas), one sparse over every third point.
  for (int k = 0; k < 2; ++k) {
    deform::MorphTarget t;
    t.name = k ? "swell" : "lift";
    for (std::size_t p = 0; p < model.mesh.point_count(); p += k ? 3 : 1) {
      t.points.push_back(std::uint32_t(p));
      t.position_deltas.push_back(glm::vec3(0.0f, 0.01f * float(k + 1), 0.02f));
      if (!k) t.normal_deltas.push_back(glm::vec3(0.0f, 0.1f, 0.0f));
    }
    model.morph_targets.push_back(std::move(t));
  }
  const deform::Rig rig = deform::builtin_rig(model);
  std::vector<Character> characters;
  characters.emplace_back(std::move(model), rig);
  Character& c = characters.front();
  c.set_normals_mode(Character::NormalsMode::recomputed);  // (its scratch at set-up)
  c.set_normals_mode(Character::NormalsMode::transported);
  deform::Animation clip;
  clip.duration = 1.0f;
  deform::MorphChannel channel;
  channel.target = 0;
  channel.weight.times = {0.0f, 0.5f, 1.0f};
  channel.weight.values = {0.0f, 1.0f, 0.0f};
  clip.morph_channels.push_back(channel);
  const std::int32_t hand = c.skeleton().find("hand_l");
  const glm::vec3 shoulder = c.bone_position(c.skeleton().find("clavicle_l"));
  Tally tally;
  const long before = allocations.load();
  for (int frame = 0; frame < frames; ++frame) {
    tally.note(c.set_morph_weights(clip, float(frame) * dt));
    tally.note(c.set_morph_weight("swell", 0.5f + 0.5f * std::sin(float(frame) * 0.1f)));
    if (frame % 100 == 50) tally.note(c.set_morph_weight(std::size_t{1}, 0.0f));
    if (frame == 600) c.set_normals_mode(Character::NormalsMode::recomputed);
    if (frame >= 100 && frame < 500) {
      tally.note(c.reach(hand, shoulder + glm::vec3(1.0f, 0.2f, 0.3f)).status);
      ++tally.reaches;
    }
    if (frame == 500) c.release();
    tally.note(c.update(dt));
    tally.normals_checksum += c.normals()[std::size_t(frame) % 100].z;
    tally.largest_stretch = std::max(tally.largest_stretch, c.stretch());
  }
  tally.allocations = allocations.load() - before;
  check(tally);
  CHECK(c.morphed_bind_positions().data() != c.model().mesh.positions.data());
}

TEST_CASE(
    "600 frames with Direct Delta Mush skinning allocate nothing: morph weights, reach, release, Delta Mush after it, "
    "normals (transported and recomputed), cleared mid-way") {
  deform::Model model = deform::builtin_character();
  deform::MorphTarget swell;
  swell.name = "swell";
  for (std::size_t p = 0; p < model.mesh.point_count(); p += 3) {
    swell.points.push_back(std::uint32_t(p));
    swell.position_deltas.push_back(glm::vec3(0.0f, 0.01f, 0.02f));
    swell.normal_deltas.push_back(glm::vec3(0.0f, 0.1f, 0.0f));
  }
  model.morph_targets.push_back(std::move(swell));
  const deform::Rig rig = deform::builtin_rig(model);
  std::vector<Character> characters;
  characters.emplace_back(std::move(model), rig);
  Character& c = characters.front();
  c.set_normals_mode(Character::NormalsMode::recomputed);  // (its scratch at set-up)
  c.set_normals_mode(Character::NormalsMode::transported);
  c.set_direct_delta_mush({});  // binds here, at set-up: the frame then allocates nothing
  c.set_delta_mush({4, 0.5f, {}});
  const std::int32_t hand = c.skeleton().find("hand_l");
  const glm::vec3 shoulder = c.bone_position(c.skeleton().find("clavicle_l"));
  Tally tally;
  const long before = allocations.load();
  for (int frame = 0; frame < 600; ++frame) {
    tally.note(c.set_morph_weight("swell", 0.5f + 0.5f * std::sin(float(frame) * 0.1f)));
    if (frame == 200) c.set_normals_mode(Character::NormalsMode::recomputed);
    if (frame == 550) c.clear_direct_delta_mush();  // back to LBS: freeing the binding allocates nothing
    if (frame >= 100 && frame < 300) {
      tally.note(c.reach(hand, shoulder + glm::vec3(1.0f, 0.2f, 0.3f)).status);
      ++tally.reaches;
    }
    if (frame == 300) c.release();
    tally.note(c.update(dt));
    tally.normals_checksum += c.normals()[std::size_t(frame) % 100].z;
    tally.largest_stretch = std::max(tally.largest_stretch, c.stretch());
  }
  tally.allocations = allocations.load() - before;
  check(tally);
}

TEST_CASE("1,000 frames of a crowd switching levels of detail allocate nothing: set_level, update, normals") {
  // Three instances walking, each set to a level every frame from a schedule that visits every level (deformers on
  // and off, an update interval of 3) and switches mid-blend; the arm stretched so the deformers have work.
  std::vector<Character> characters;
  characters.push_back(deform::make_builtin_character());
  deform::BoneLodSettings settings;
  settings.bones_per_level = {25, 14, 8};
  // Level 3 deforms a subset of the points (a simplified mesh's: every third point here).
  std::vector<Character::LevelOptions> options = {{true, 1}, {true, 1}, {false, 1}, {false, 3}};
  std::vector<std::uint32_t> subset;
  for (std::uint32_t p = 0; p < characters.front().model().mesh.point_count(); p += 3) subset.push_back(p);
  options[3].points = subset;
  characters.front().set_levels(deform::build_bone_lod(characters.front().model(), settings), options, 6);
  characters.push_back(characters.front().instance());
  characters.push_back(characters.front().instance());
  characters.back().settings.renderer_interpolates = true;  // the third: level 3 interpolated on the renderer
  const deform::Animation walk = deform::builtin_walk(characters.front().model());
  deform::Pose pose = characters.front().skeleton().bind_pose();
  deform::SamplingJob sampling;
  sampling.animation = &walk;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  for (Character& c : characters)
    for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l)
      c.deformers().set_stretch_target(l, 0.2f * c.deformers().length(l));
  Tally tally;
  tally.reaches = 5;  // (no reaches here)
  const long before = allocations.load();
  for (int frame = 0; frame < frames; ++frame) {
    for (std::size_t i = 0; i < characters.size(); ++i) {
      Character& c = characters[i];
      sampling.time = float(frame) * dt + 0.3f * float(i);
      tally.note(sampling.run());
      tally.note(c.set_pose(pose));
      tally.note(c.set_level(std::size_t((frame / (7 + 3 * int(i)) + int(i)) % 4)));
      tally.note(c.update(dt));
      tally.normals_checksum += c.normals()[std::size_t(frame) % 100].y;
      const Character::Interpolation shown = c.interpolation();
      tally.normals_checksum += shown.share * shown.to[std::size_t(frame) % 100].y;
      tally.largest_stretch = std::max(tally.largest_stretch, c.deformers().stretch(0));
    }
  }
  tally.allocations = allocations.load() - before;
  check(tally);
}

#if defined(DEFORM_HAVE_IMPORT)
TEST_CASE("1,000 frames of an imported character allocate nothing: clip, reach, release, update, normals") {
  const std::string path = "/usr/share/assimp/models/X/Testwuson.X";  // Debian's assimp-testmodels
  if (!std::filesystem::exists(path)) {
    MESSAGE(path << " is not installed: skipped");
    return;
  }
  deform::ImportedModel imported = deform::import_model(path);
  REQUIRE(imported.rigged);
  REQUIRE_FALSE(imported.clips.empty());
  const deform::Rig rig = deform::default_rig(imported.model);
  REQUIRE(rig.reach_effector > 0);
  REQUIRE_FALSE(rig.lattices.empty());
  std::vector<Character> characters;
  characters.emplace_back(std::move(imported.model), rig);
  Character& c = characters.front();
  const deform::Skeleton& skeleton = c.skeleton();
  const deform::Animation& clip = imported.clips.front();
  // A second effector: the deepest bone that is not the rig's, so the chain is rebuilt now and then.
  std::int32_t other = -1;
  std::size_t deepest = 0;
  for (std::size_t b = 1; b < skeleton.bone_count(); ++b) {
    std::size_t depth = 0;
    for (std::int32_t id = std::int32_t(b); id > 0; id = skeleton.bone(id).parent) ++depth;
    if (std::int32_t(b) != rig.reach_effector && depth > deepest) deepest = depth, other = std::int32_t(b);
  }
  REQUIRE(other > 0);
  // Targets scaled to the model: beyond the effector's reach along the model's diagonal.
  const deform::Bounds bounds = deform::compute_bounds(c.model().mesh.positions);
  const float size = glm::length(bounds.max - bounds.min);
  const glm::vec3 start = c.bone_position(rig.reach_effector);
  deform::Pose pose = skeleton.bind_pose();
  const deform::Pose bind = pose;
  deform::SamplingJob sampling;
  sampling.animation = &clip;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  REQUIRE(sampling.validate());

  Tally tally;
  const long before = allocations.load();
  for (int frame = 0; frame < frames; ++frame) {
    std::copy(bind.rotations.begin(), bind.rotations.end(), pose.rotations.begin());
    std::copy(bind.translations.begin(), bind.translations.end(), pose.translations.begin());
    sampling.time = float(frame) * dt;
    tally.note(sampling.run());
    tally.note(c.set_pose(pose));
    if (frame >= 100 && frame < 500) {
      const int phase = (frame - 100) / 50;
      const std::int32_t effector = phase % 3 == 2 ? other : rig.reach_effector;
      const glm::vec3 target = start + size * glm::vec3(0.3f + 0.05f * float(phase), 0.1f, 0.2f);
      tally.note(c.reach(effector, target).status);
      ++tally.reaches;
    }
    if (frame == 500) c.release();
    tally.note(c.update(dt));
    const auto normals = c.normals();
    tally.normals_checksum += normals[std::size_t(frame) % normals.size()].y;
    tally.largest_stretch = std::max(tally.largest_stretch, c.stretch() / size * 10.0f);
  }
  tally.allocations = allocations.load() - before;
  check(tally);
}
#endif

TEST_CASE("100 frames with the reduced Direct Delta Mush allocate nothing: posed, reached, normals transported") {
  Character c = deform::make_builtin_character();
  deform::DirectDeltaMushSettings settings;
  settings.variant = deform::DirectDeltaMushVariant::reduced;
  c.set_direct_delta_mush(settings);  // binds here, at set-up
  REQUIRE(c.direct_delta_mush_reduced() != nullptr);
  const std::int32_t hand = c.skeleton().find("hand_l");
  const glm::vec3 shoulder = c.bone_position(c.skeleton().find("clavicle_l"));
  REQUIRE(c.update(dt));
  const long before = allocations.load();
  bool ok = true;
  for (int frame = 0; frame < 100; ++frame) {
    ok = ok && c.reach(hand, shoulder + glm::vec3(1.0f, 0.2f, 0.3f * std::sin(float(frame) * 0.1f))).status;
    ok = ok && c.update(dt);
  }
  const long allocated = allocations.load() - before;
  CHECK(ok);
  CHECK(allocated == 0);
}
