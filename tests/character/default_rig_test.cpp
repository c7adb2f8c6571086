// default_rig / survey_rig (offline/rig.hpp): limbs from the skeleton's structure and weights, names as hints; a
// reach with the default rig moves only the limb and keeps the feet on the floor, on the built-in character and on
// every rigged character of Debian's assimp-testmodels.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/skeleton.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#endif

namespace {

using deform::LimbKind;

// A synthetic skeleton in the bind pose, Y up, facing +Z (left = +X), every bone given its head in model space, and
// one skinned point at each bone's head (weight 1 to it) unless `unskinned` names it.
struct Spec {
  std::string name;
  std::string parent;  // empty: the root
  glm::vec3 head;
  bool skinned = true;
};

deform::Model make_model(const std::vector<Spec>& specs) {
  std::vector<deform::Bone> bones(specs.size());
  std::vector<glm::vec3> heads;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    bones[i].name = specs[i].name;
    heads.push_back(specs[i].head);
    if (specs[i].parent.empty()) continue;
    for (std::size_t p = 0; p < i; ++p)
      if (specs[p].name == specs[i].parent) bones[i].parent = std::int32_t(p);
    REQUIRE(bones[i].parent >= 0);
    bones[std::size_t(bones[i].parent)].children.push_back(std::int32_t(i));
    bones[i].bind_translation = specs[i].head - specs[std::size_t(bones[i].parent)].head;
  }
  deform::Model model;
  model.name = "synthetic";
  model.skeleton = deform::Skeleton(bones);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    if (!specs[i].skinned) continue;
    model.mesh.positions.push_back(specs[i].head);
    model.weights.bones.push_back(glm::u16vec4(std::uint16_t(i), 0, 0, 0));
    model.weights.weights.push_back(glm::vec4(1, 0, 0, 0));
  }
  return model;
}

// A humanoid named through `name` (a role and a side: "hand", 'L'), with an IK goal for the left hand under the
// spine and a twist bone on each upper arm: the helpers the survey must leave out.
std::vector<Spec> humanoid(const std::function<std::string(const std::string&, char)>& name) {
  const auto n = [&](const char* role, char side = 0) { return name(role, side); };
  std::vector<Spec> s = {{n("hips"), "", {0, 1.0f, 0}},
                         {n("spine"), n("hips"), {0, 1.2f, 0}},
                         {n("chest"), n("spine"), {0, 1.4f, 0}},
                         {n("neck"), n("chest"), {0, 1.6f, 0}},
                         {n("head"), n("neck"), {0, 1.7f, 0}}};
  for (const char side : {'L', 'R'}) {
    const float x = side == 'L' ? 1.0f : -1.0f;
    s.push_back({n("clavicle", side), n("chest"), {0.05f * x, 1.5f, 0}});
    s.push_back({n("upperarm", side), n("clavicle", side), {0.2f * x, 1.5f, 0}});
    s.push_back({n("twist", side), n("upperarm", side), {0.3f * x, 1.5f, 0}});
    s.push_back({n("forearm", side), n("upperarm", side), {0.48f * x, 1.5f, 0}});
    s.push_back({n("hand", side), n("forearm", side), {0.74f * x, 1.5f, 0}});
    s.push_back({n("finger", side), n("hand", side), {0.82f * x, 1.5f, 0}});
    s.push_back({n("thigh", side), n("hips"), {0.1f * x, 0.95f, 0}});
    s.push_back({n("shin", side), n("thigh", side), {0.1f * x, 0.5f, 0}});
    s.push_back({n("foot", side), n("shin", side), {0.1f * x, 0.08f, 0}});
    s.push_back({n("toe", side), n("foot", side), {0.1f * x, 0.02f, 0.12f}});
  }
  s.push_back({n("handik", 'L'), n("spine"), {0.74f, 1.5f, 0}, false});  // an IK goal: no skin
  s.push_back({n("pole", 'L'), n("hips"), {0.48f, 1.5f, -0.4f}, false});
  return s;
}

// The name of a survey's limb end, and the chain's root.
std::string end_of(const deform::Model& m, const deform::Limb& l) { return m.skeleton.bone(l.chain.back()).name; }
std::string root_of(const deform::Model& m, const deform::Limb& l) { return m.skeleton.bone(l.chain.front()).name; }

void check_humanoid(const deform::Model& model, const std::function<std::string(const std::string&, char)>& name) {
  const deform::RigSurvey survey = deform::survey_rig(model);
  REQUIRE(survey.limbs.size() == 4);
  CHECK_FALSE(survey.four_legged);
  const struct {
    LimbKind kind;
    int side;
    const char* end;
    const char* root;
  } expected[] = {{LimbKind::arm, 1, "hand", "clavicle"},
                  {LimbKind::arm, -1, "hand", "clavicle"},
                  {LimbKind::leg, 1, "foot", "thigh"},
                  {LimbKind::leg, -1, "foot", "thigh"}};
  for (std::size_t i = 0; i < 4; ++i) {
    const deform::Limb& limb = survey.limbs[i];
    const char side = expected[i].side > 0 ? 'L' : 'R';
    CAPTURE(limb.why);
    CHECK(limb.kind == expected[i].kind);
    CHECK(limb.side == expected[i].side);
    CHECK(end_of(model, limb) == name(expected[i].end, side));
    CHECK(root_of(model, limb) == name(expected[i].root, side));
  }
  CHECK(survey.up.y == doctest::Approx(1.0f));
  // The helpers are set aside with a reason; the rig's reach chains are the limbs'.
  std::vector<std::string> skipped;
  for (const auto& [bone, why] : survey.skipped) skipped.push_back(model.skeleton.bone(bone).name);
  CHECK(std::count(skipped.begin(), skipped.end(), name("handik", 'L')) == 1);
  CHECK(std::count(skipped.begin(), skipped.end(), name("pole", 'L')) == 1);
  const deform::Rig rig = deform::default_rig(model);
  CHECK(model.skeleton.bone(rig.reach_effector).name == name("hand", 'L'));
  CHECK(model.skeleton.bone(rig.reach_root).name == name("clavicle", 'L'));
  REQUIRE(rig.reach_chains.size() == 3);
  CHECK(model.skeleton.bone(rig.reach_chains[2].root).name == name("thigh", 'R'));
  CHECK(rig.lattices.size() == 12);
}

}  // namespace

TEST_CASE("survey_rig reads Mixamo, rigify, Unreal, VRM and unnamed humanoids alike") {
  struct Convention {
    const char* what;
    std::function<std::string(const std::string&, char)> name;
  };
  const auto words = [](const std::string& role, const std::vector<std::pair<std::string, std::string>>& map) {
    for (const auto& [from, to] : map)
      if (from == role) return to;
    return role;
  };
  const std::vector<Convention> conventions = {
      {"Mixamo",
       [&](const std::string& role, char side) {
         const std::string w = words(role, {{"hips", "Hips"},
                                            {"spine", "Spine"},
                                            {"chest", "Spine2"},
                                            {"neck", "Neck"},
                                            {"head", "Head"},
                                            {"clavicle", "Shoulder"},
                                            {"upperarm", "Arm"},
                                            {"twist", "ArmTwist"},
                                            {"forearm", "ForeArm"},
                                            {"hand", "Hand"},
                                            {"finger", "HandMiddle1"},
                                            {"thigh", "UpLeg"},
                                            {"shin", "Leg"},
                                            {"foot", "Foot"},
                                            {"toe", "ToeBase"},
                                            {"handik", "HandIK"},
                                            {"pole", "ElbowPole"}});
         return "mixamorig:" + std::string(side == 'L' ? "Left" : side == 'R' ? "Right" : "") + w;
       }},
      {"rigify",
       [&](const std::string& role, char side) {
         const std::string w = words(role, {{"hips", "spine"},
                                            {"spine", "spine.001"},
                                            {"chest", "spine.003"},
                                            {"neck", "spine.004"},
                                            {"head", "spine.006"},
                                            {"clavicle", "shoulder"},
                                            {"upperarm", "upper_arm"},
                                            {"twist", "upper_arm_twist"},
                                            {"finger", "f_middle.01"},
                                            {"thigh", "thigh"},
                                            {"toe", "toe"},
                                            {"handik", "MCH-hand_ik"},
                                            {"pole", "MCH-elbow_pole"}});
         const std::string prefix = w.starts_with("MCH-") ? "" : "DEF-";
         return prefix + w + (side == 'L' ? ".L" : side == 'R' ? ".R" : "");
       }},
      {"Unreal",
       [&](const std::string& role, char side) {
         const std::string w = words(role, {{"hips", "pelvis"},
                                            {"spine", "spine_01"},
                                            {"chest", "spine_03"},
                                            {"neck", "neck_01"},
                                            {"forearm", "lowerarm"},
                                            {"twist", "upperarm_twist_01"},
                                            {"finger", "middle_01"},
                                            {"shin", "calf"},
                                            {"toe", "ball"},
                                            {"handik", "ik_hand"},
                                            {"pole", "ik_elbow_pole"}});
         return w + (side == 'L' ? "_l" : side == 'R' ? "_r" : "");
       }},
      {"VRM",
       [&](const std::string& role, char side) {
         const std::string w = words(role, {{"hips", "hips"},
                                            {"chest", "upperChest"},
                                            {"clavicle", "Shoulder"},
                                            {"upperarm", "UpperArm"},
                                            {"twist", "UpperArmTwist"},
                                            {"forearm", "LowerArm"},
                                            {"hand", "Hand"},
                                            {"finger", "MiddleProximal"},
                                            {"thigh", "UpperLeg"},
                                            {"shin", "LowerLeg"},
                                            {"foot", "Foot"},
                                            {"toe", "Toes"},
                                            {"handik", "HandIKTarget"},
                                            {"pole", "ElbowPole"}});
         return side == 0 ? w : std::string(side == 'L' ? "left" : "right") + w;
       }},
      // No telling names at all: the structure alone (sides from +X).
      {"unnamed",
       [&](const std::string& role, char side) {
         static const std::vector<std::string> roles = {"hips",     "spine", "chest",   "neck",   "head",   "clavicle",
                                                        "upperarm", "twist", "forearm", "hand",   "finger", "thigh",
                                                        "shin",     "foot",  "toe",     "handik", "pole"};
         const auto at = std::find(roles.begin(), roles.end(), role) - roles.begin();
         return "j" + std::to_string(at) + (side == 'L' ? "a" : side == 'R' ? "b" : "");
       }},
  };
  for (const Convention& c : conventions) {
    CAPTURE(c.what);
    check_humanoid(make_model(humanoid(c.name)), c.name);
  }
}

TEST_CASE(
    "survey_rig: a four-legged creature gets four legs, a neck and a tail; an arm without a clavicle reaches "
    "from the shoulder") {
  // Unnamed bones: a dog-like body along +Z, the root at the pelvis, the tail behind it, the neck and head ahead.
  std::vector<Spec> s = {
      {"root", "", {0, 0.6f, 0}},        {"s1", "root", {0, 0.62f, 0.25f}}, {"s2", "s1", {0, 0.62f, 0.5f}},
      {"n1", "s2", {0, 0.75f, 0.6f}},    {"n2", "n1", {0, 0.85f, 0.7f}},    {"hd", "n2", {0, 0.9f, 0.8f}},
      {"t1", "root", {0, 0.62f, -0.1f}}, {"t2", "t1", {0, 0.66f, -0.25f}},  {"t3", "t2", {0, 0.7f, -0.4f}}};
  for (const float x : {1.0f, -1.0f}) {
    const std::string k = x > 0 ? "a" : "b";
    for (const auto& [at, parent, z] : {std::tuple{"f", "s2", 0.5f}, std::tuple{"h", "root", 0.0f}}) {
      s.push_back({k + at + "1", parent, {0.12f * x, 0.55f, z}});
      s.push_back({k + at + "2", k + at + "1", {0.12f * x, 0.3f, z}});
      s.push_back({k + at + "3", k + at + "2", {0.12f * x, 0.06f, z}});
      s.push_back({k + at + "4", k + at + "3", {0.12f * x, 0.01f, z + 0.06f}});
    }
  }
  const deform::Model model = make_model(s);
  const deform::RigSurvey survey = deform::survey_rig(model);
  CHECK(survey.four_legged);
  REQUIRE(survey.limbs.size() == 6);
  for (std::size_t i = 0; i < 4; ++i) {
    CAPTURE(survey.limbs[i].why);
    CHECK(survey.limbs[i].kind == (i < 2 ? LimbKind::front_leg : LimbKind::hind_leg));
    CHECK(end_of(model, survey.limbs[i]).ends_with("3"));  // the foot, before the toe
    CHECK(root_of(model, survey.limbs[i]).ends_with("1"));
    CHECK(survey.limbs[i].side == (i % 2 == 0 ? 1 : -1));
  }
  CHECK(survey.limbs[4].kind == LimbKind::neck);
  CHECK(end_of(model, survey.limbs[4]) == "hd");
  CHECK(survey.limbs[5].kind == LimbKind::tail);
  CHECK(root_of(model, survey.limbs[5]) == "t1");
  const deform::Rig rig = deform::default_rig(model);
  REQUIRE(rig.spring_chains.size() == 1);
  CHECK(rig.spring_chains[0].bones.size() == 3);
  CHECK(rig.reach_chains.size() == 4);  // three legs and the neck beside the reach effector

  // A humanoid whose arms hang from the chest with no clavicle: the reach starts at the upper arm.
  std::vector<Spec> h = humanoid([](const std::string& role, char side) {
    return role + (side == 'L' ? ".L" : side == 'R' ? ".R" : "");
  });
  for (Spec& b : h) {
    if (b.name.starts_with("clavicle")) b.name = "gone" + b.name;
    if (b.name.starts_with("upperarm")) b.parent = "chest";
  }
  std::erase_if(h, [](const Spec& b) { return b.name.starts_with("gone"); });
  const deform::Model armless = make_model(h);
  const deform::RigSurvey bare = deform::survey_rig(armless);
  REQUIRE(bare.limbs.size() == 4);
  CHECK(root_of(armless, bare.limbs[0]) == "upperarm.L");
  CHECK(end_of(armless, bare.limbs[0]) == "hand.L");
}

namespace {

// Reaches with each of the rig's arms (or front legs) for a point a bit beyond the hand, and checks that only the
// limb moved: every bone off the chain (and not below it) keeps its position, the root and pelvis included, the
// feet stay where they were, and the lowest skinned point does not rise.
void check_reach_moves_only_the_limb(deform::Model model, const deform::Rig& rig, const deform::RigSurvey& survey) {
  deform::Character character(std::move(model), rig);
  const deform::Skeleton& sk = character.skeleton();
  const auto bones = std::int32_t(sk.bone_count());
  // Every limb's end is one the viewer's click may reach with (reach_effectors), a hand without a lattice included.
  const std::vector<std::int32_t> effectors = deform::reach_effectors(character);
  for (const deform::Limb& limb : survey.limbs)
    if (limb.kind != LimbKind::tail) CHECK(std::count(effectors.begin(), effectors.end(), limb.chain.back()) == 1);
  character.update(1.0f / 60.0f);
  std::vector<glm::vec3> before(static_cast<std::size_t>(bones));
  for (std::int32_t b = 0; b < bones; ++b) before[std::size_t(b)] = character.bone_position(b);
  const deform::Bounds bounds = deform::compute_bounds(character.positions());
  const float size = glm::length(bounds.max - bounds.min);
  float lowest = 1e30f;
  for (const glm::vec3& p : character.positions()) lowest = std::min(lowest, glm::dot(p, survey.up));

  for (const deform::Limb& limb : survey.limbs) {
    if (limb.kind != LimbKind::arm && limb.kind != LimbKind::front_leg) continue;
    CAPTURE(sk.bone(limb.chain.back()).name);
    deform::Character reacher = character.instance();
    reacher.update(1.0f / 60.0f);
    const std::int32_t hand = limb.chain.back();
    const glm::vec3 shoulder = reacher.bone_position(limb.chain.front());
    const glm::vec3 out = reacher.bone_position(hand) - shoulder;
    // A bit away from the hand: outward and forward by a tenth of the body's size.
    const glm::vec3 target =
        reacher.bone_position(hand) + 0.1f * size * glm::normalize(out + 0.5f * glm::length(out) * glm::vec3(0, 0, 1));
    const deform::ReachResult result = reacher.reach(hand, target);
    REQUIRE(result.status);
    REQUIRE(reacher.reach_chain().front() == limb.chain.front());
    for (int frame = 0; frame < 90; ++frame) reacher.update(1.0f / 60.0f);
    CHECK(glm::length(reacher.bone_position(hand) - target) < 0.05f * size);  // it did reach
    for (std::int32_t b = 0; b < bones; ++b) {
      bool on_limb = false;
      for (const std::int32_t c : limb.chain) on_limb = on_limb || b == c || sk.is_ancestor(c, b);
      if (on_limb) continue;
      CAPTURE(sk.bone(b).name);
      CHECK(glm::length(reacher.bone_position(b) - before[std::size_t(b)]) < 1e-3f * size);
    }
    for (const deform::Limb& leg : survey.limbs)
      if (leg.kind == LimbKind::leg || leg.kind == LimbKind::hind_leg)
        CHECK(glm::length(reacher.bone_position(leg.chain.back()) - before[std::size_t(leg.chain.back())]) <
              1e-3f * size);
    float low = 1e30f;
    for (const glm::vec3& p : reacher.positions()) low = std::min(low, glm::dot(p, survey.up));
    CHECK(low <= lowest + 1e-3f * size);
  }
}

}  // namespace

TEST_CASE("the built-in character, its names taken away, gets its every-limb rig back from the structure") {
  const deform::Model builtin = deform::builtin_character();
  const deform::Rig full = deform::builtin_full_rig(builtin);
  deform::Model renamed = builtin;
  std::vector<deform::Bone> bones(renamed.skeleton.bones().begin(), renamed.skeleton.bones().end());
  for (std::size_t b = 0; b < bones.size(); ++b) bones[b].name = "b" + std::to_string(b);
  renamed.skeleton = deform::Skeleton(bones);
  for (const deform::Model* model : {&builtin, static_cast<const deform::Model*>(&renamed)}) {
    const deform::Rig rig = deform::default_rig(*model);
    REQUIRE(rig.lattices.size() == full.lattices.size());
    for (std::size_t i = 0; i < full.lattices.size(); ++i) {
      CHECK(rig.lattices[i].bone == full.lattices[i].bone);
      // The part found from the structure moves as the named part does (default_lattice_motion), still at rest.
      CHECK(rig.lattices[i].motion.along_bound == full.lattices[i].motion.along_bound);
      CHECK(rig.lattices[i].motion.far_share == full.lattices[i].motion.far_share);
      CHECK(rig.lattices[i].motion.inertia == 0.0f);
    }
    CHECK(rig.reach_effector == full.reach_effector);
    CHECK(rig.reach_root == full.reach_root);
    const deform::RigSurvey survey = deform::survey_rig(*model);
    REQUIRE(survey.limbs.size() == 4);
    CHECK(survey.limbs[2].chain.front() == builtin.skeleton.find("thigh_l"));
    CHECK(survey.limbs[3].chain.back() == builtin.skeleton.find("foot_r"));
    check_reach_moves_only_the_limb(*model, rig, survey);
  }
}

#if defined(DEFORM_HAVE_IMPORT)
TEST_CASE("the rigged characters of assimp-testmodels: hands and feet, reaches that move only the limb") {
  struct Case {
    const char* path;
    bool four_legged;
    std::vector<const char*> ends;   // the limbs' ends, in the survey's order
    std::vector<const char*> roots;  // the reach chains' roots
  };
  const std::string dir = "/usr/share/assimp/models/";
  const Case cases[] = {
      // mrfixit skins its hands to IK goals under the spine (HandGoal.L): the arm still ends at Hand.L.
      {"IQM/mrfixit.iqm",
       false,
       {"Hand.L", "Hand.R", "UpperFoot.L", "UpperFoot.R"},
       {"UpperArm.L", "UpperArm.R", "Thigh.L", "Thigh.R"}},
      {"X/BCN_Epileptic.X",
       false,
       {"B_Hand_Left", "B_Hand_Right", "B_Ankle_Left", "B_Ankle_Right"},
       {"B_Clavicle_Left", "B_Clavicle_Right", "B_Hip_Left", "B_Hip_Right"}},
      {"X/Testwuson.X",
       true,
       {"ForeLeg_L_03", "ForeLeg_R_03", "HindLeg_L_03", "HindLeg_R_03", "Neck", "Tail06"},
       {"ForeLeg_L_01", "ForeLeg_R_01", "HindLeg_L_01", "HindLeg_R_01", "Spine_Front04", "Tail01"}},
  };
  for (const Case& c : cases) {
    CAPTURE(std::string(c.path));
    if (!std::filesystem::exists(dir + c.path)) {
      MESSAGE(c.path << " is not installed: skipped");
      continue;
    }
    deform::ImportedModel imported = deform::import_model(dir + c.path);
    REQUIRE(imported.rigged);
    const deform::Skeleton& sk = imported.model.skeleton;
    const deform::RigSurvey survey = deform::survey_rig(imported.model);
    CHECK(survey.four_legged == c.four_legged);
    REQUIRE(survey.limbs.size() == c.ends.size());
    const deform::Bounds bounds = deform::compute_bounds(imported.model.mesh.positions);
    const float size = glm::length(bounds.max - bounds.min);
    for (std::size_t i = 0; i < c.ends.size(); ++i) {
      const deform::Limb& limb = survey.limbs[i];
      CAPTURE(limb.why);
      CHECK(sk.bone(limb.chain.back()).name == c.ends[i]);
      CHECK(sk.bone(limb.chain.front()).name == c.roots[i]);
      if (limb.kind == LimbKind::neck || limb.kind == LimbKind::tail) continue;
      // Structurally: the end is near the limb's leaves (what hangs below it, fingers or toes, is at most two bones
      // deep or reaches less than half as far as the chain), and away from where the limb branches off.
      const auto head = [&](std::int32_t b) { return glm::vec3(sk.bind_world()[std::size_t(b)][3]); };
      const std::int32_t end = limb.chain.back();
      float chain_length = 0.0f, below = 0.0f;
      int deep = 0;
      for (std::size_t k = 1; k < limb.chain.size(); ++k)
        chain_length += glm::length(head(limb.chain[k]) - head(limb.chain[k - 1]));
      for (std::int32_t b = 0; b < std::int32_t(sk.bone_count()); ++b)
        if (sk.is_ancestor(end, b)) {
          below = std::max(below, glm::length(head(b) - head(end)));
          int d = 0;
          for (std::int32_t a = b; a != end; a = sk.bone(a).parent) ++d;
          deep = std::max(deep, d);
        }
      CHECK((deep <= 2 || below < 0.5f * chain_length));
      CHECK(glm::length(head(end) - head(sk.bone(limb.chain.front()).parent)) > 0.15f * size);
    }
    const deform::Rig rig = deform::default_rig(imported.model);
    CHECK(sk.bone(rig.reach_effector).name == c.ends[0]);
    check_reach_moves_only_the_limb(std::move(imported.model), rig, survey);
  }
}

TEST_CASE("rigged models that are no characters keep a one-limb rig that binds and reaches") {
  const std::string dir = "/usr/share/assimp/models/";
  for (const char* path : {"FBX/huesitos.fbx", "FBX/animation_with_skeleton.fbx", "X/anim_test.x"}) {
    CAPTURE(path);
    if (!std::filesystem::exists(dir + path)) continue;
    deform::ImportedModel imported = deform::import_model(dir + path);
    const deform::RigSurvey survey = deform::survey_rig(imported.model);
    CHECK(survey.limbs.empty());
    const deform::Rig rig = deform::default_rig(imported.model);
    REQUIRE(rig.reach_effector > 0);
    deform::Character character(std::move(imported.model), rig);
    const glm::vec3 tip = character.bone_position(rig.reach_effector);
    CHECK(character.reach(rig.reach_effector, tip + glm::vec3(0.1f)).status);
  }
}
#endif

TEST_CASE("survey_rig on hostile skeletons: a chain of 20,000 bones and a root with 20,000 children, quickly") {
  for (const bool chain : {true, false}) {
    CAPTURE(chain);
    std::vector<Spec> s = {{"b0", "", {0, 0, 0}}};
    for (int i = 1; i < 20000; ++i)
      s.push_back({"b" + std::to_string(i), chain ? "b" + std::to_string(i - 1) : "b0",
                   chain ? glm::vec3(0, 0.001f * float(i), 0) : glm::vec3(std::cos(float(i)), 1, std::sin(float(i)))});
    // make_model looks parents up by name: quadratic, so the skeleton is built here directly.
    std::vector<deform::Bone> bones(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      bones[i].name = s[i].name;
      if (i == 0) continue;
      bones[i].parent = chain ? std::int32_t(i - 1) : 0;
      bones[std::size_t(bones[i].parent)].children.push_back(std::int32_t(i));
      bones[i].bind_translation = s[i].head - s[std::size_t(bones[i].parent)].head;
    }
    deform::Model model;
    model.name = "hostile";
    model.skeleton = deform::Skeleton(bones);
    for (std::size_t i = 0; i < s.size(); ++i) {
      model.mesh.positions.push_back(s[i].head);
      model.weights.bones.push_back(glm::u16vec4(std::uint16_t(i), 0, 0, 0));
      model.weights.weights.push_back(glm::vec4(1, 0, 0, 0));
    }
    const deform::RigSurvey survey = deform::survey_rig(model);
    CHECK(survey.limbs.empty());
    const deform::Rig rig = deform::default_rig(model);
    CHECK(rig.reach_effector > 0);
    CHECK(rig.lattices.size() <= 3);
  }
}
