// Rig files: round trip (text and file), every field, and bad files rejected with the key that is wrong.
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace {

const deform::Model& model() {
  static const deform::Model m = deform::builtin_character();
  return m;
}

deform::Rig parse(const std::string& text) {
  return deform::parse_rig_json(text, model().skeleton, model().mesh.point_count(), "test.rig.json");
}

// A rig using every field away from its default.
deform::Rig everything() {
  deform::Rig rig = deform::builtin_rig(model());
  rig.model = {false, "arm.obj", "arm.sk", "arm.skw", ""};
  rig.max_stretch = 1.25f;
  deform::LatticeSpec& upper = rig.lattices[0];
  upper.degree = glm::ivec3(2, 4, 1);
  upper.weight_threshold = 0.35f;
  upper.margin = 0.1f;
  upper.carry_descendants = false;
  upper.elastic.integrator = deform::Integrator::verlet;
  upper.elastic.verlet_kd = 0.07f;
  upper.elastic.oscillator = {123.456f, 1.7f, 0.3f};
  upper.shape = {0.55f, 0.25f};
  deform::LatticeSpec& fore = rig.lattices[1];
  fore.selection = deform::VertexSelection::list;
  fore.vertices = {3, 17, 400, 2000};
  fore.elastic.springs = {true, false, true, 12.5f, 0.1f, 1.0f / 480.0f};
  fore.shape.min_length_fraction = 0.0f;  // no floor; volume stays default
  upper.motion = {0.75f, glm::vec3(0.0f, -9.81f, 0.0f), 100.0f, 0.05f, 0.25f};
  const deform::Skeleton& skeleton = model().skeleton;
  rig.colliders = {{skeleton.find("chest"), glm::vec3(0.0f, 0.1f, 0.0f), glm::vec3(0.0f, 0.3f, 0.0f), 0.12f},
                   {skeleton.find("thigh_r"), glm::vec3(0.0f), glm::vec3(0.0f), 0.08f}};
  deform::SpringChainSpec fingers;
  fingers.name = "fingers_r";
  fingers.bones = {skeleton.find("fingers1_r"), skeleton.find("fingers2_r")};
  fingers.tip = glm::vec3(0.05f, 0.0f, 0.0f);
  fingers.frequency = 3.5f;
  fingers.damping_ratio = 0.45f;
  fingers.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  fingers.units_per_metre = 1.0f;
  fingers.radius = 0.01f;
  fingers.colliders = {0, 1};
  deform::SpringChainSpec head;
  head.name = "head";
  head.bones = {skeleton.find("neck"), skeleton.find("head")};
  rig.spring_chains = {fingers, head};
  rig.spring_substep = 1.0f / 120.0f;
  return rig;
}

}  // namespace

TEST_CASE("rig JSON round trip: text, file, every field") {
  for (const deform::Rig& rig : {deform::builtin_rig(model()), deform::builtin_full_rig(model()), everything()}) {
    const std::string text = deform::format_rig_json(rig, model().skeleton);
    CHECK(parse(text) == rig);
    CHECK(deform::format_rig_json(parse(text), model().skeleton) == text);
  }
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "deform_rig_test.rig.json";
  deform::write_rig_json(path.string(), everything(), model().skeleton);
  CHECK(deform::read_rig_json(path.string(), model().skeleton, model().mesh.point_count()) == everything());
  CHECK(deform::parse_rig_model(deform::read_file_text(path.string())) == everything().model);
  std::filesystem::remove(path);
}

TEST_CASE("a rig names an imported model by its file") {
  deform::Rig rig = deform::builtin_rig(model());
  rig.model = {};
  rig.model.file = "models/CesiumMan.glb";
  const std::string text = deform::format_rig_json(rig, model().skeleton);
  CHECK(nlohmann::json::parse(text)["model"] == nlohmann::json{{"file", "models/CesiumMan.glb"}});
  CHECK(parse(text) == rig);
  CHECK(deform::parse_rig_model(text).file == "models/CesiumMan.glb");
  CHECK_FALSE(deform::parse_rig_model(text).builtin);
  // One model or the other, and a name.
  const auto refused = [](const std::string& model_json) {
    try {
      (void)deform::parse_rig_model(R"({"rig": 1, "model": )" + model_json + R"(, "lattices": []})", "r.json");
    } catch (const deform::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(refused(R"({"file": "a.glb", "obj": "a.obj"})").find("key 'model'") != std::string::npos);
  CHECK(refused(R"({"file": ""})").find("key 'model.file'") != std::string::npos);
  CHECK(refused(R"({"file": 3})").find("key 'model.file'") != std::string::npos);
}

TEST_CASE("the written form: hierarchy, names, model") {
  const nlohmann::json doc =
      nlohmann::json::parse(deform::format_rig_json(deform::builtin_rig(model()), model().skeleton));
  CHECK(doc["rig"] == 1);
  CHECK(doc["model"] == "builtin");
  CHECK(doc["reach"]["effector"] == "hand_l");
  CHECK(doc["reach"]["root"] == "clavicle_l");
  REQUIRE(doc["lattices"].size() == 3);
  CHECK(doc["lattices"][0]["parent"].is_null());
  CHECK(doc["lattices"][1]["parent"] == "upperarm_l");
  CHECK(doc["lattices"][2]["parent"] == "forearm_l");
  CHECK(doc["lattices"][1]["bone"] == "forearm_l");
  CHECK(doc["lattices"][1]["elastic"]["stiffness"] == 150.0);
  CHECK(doc["lattices"][1]["elastic"]["damping_ratio"] == 0.2);  // shortest form of 0.2f, not 0.20000000298...
  CHECK(doc["lattices"][1]["select"]["by"] == "weight");
  // Default stretch shapes are not written, nor an empty springs block, so files from before the keys existed
  // round-trip byte for byte. The built-in rig's motion is its parts' bound and far face share (no inertia).
  for (const auto& lattice : doc["lattices"]) {
    CHECK_FALSE(lattice.contains("min_length_fraction"));
    CHECK_FALSE(lattice.contains("volume"));
  }
  CHECK(doc["lattices"][0]["motion"]["inertia"] == 0.0);
  CHECK(doc["lattices"][0]["motion"]["far_share"] == 0.0);  // the upper arm's elbow stays where the bone puts it
  // Each lattice's part, whose tuned inertia --inertia and the viewer's slider scale; the hand's bound and share are
  // the defaults, its part is not.
  CHECK(doc["lattices"][0]["motion"]["part"] == "upper_limb");
  CHECK(doc["lattices"][1]["motion"]["part"] == "lower_limb");
  CHECK(doc["lattices"][2]["motion"]["part"] == "hand");
  // The built-in rig's ponytail chain and its colliders are written; a rig without chains has no springs block.
  REQUIRE(doc.contains("springs"));
  deform::Rig no_springs = deform::builtin_rig(model());
  no_springs.spring_chains.clear();
  no_springs.colliders.clear();
  CHECK_FALSE(nlohmann::json::parse(deform::format_rig_json(no_springs, model().skeleton)).contains("springs"));
  // Unless its substep is not the default: that is written, and read back (the rig fuzzer found it dropped).
  no_springs.spring_substep = 0.0041644443f;
  const std::string text = deform::format_rig_json(no_springs, model().skeleton);
  CHECK(nlohmann::json::parse(text)["springs"]["chains"].empty());
  CHECK(deform::parse_rig_json(text, model().skeleton, 100, "again.json") == no_springs);
}

TEST_CASE("the stretch shape: written where it differs from the default, read back exactly") {
  const nlohmann::json doc = nlohmann::json::parse(deform::format_rig_json(everything(), model().skeleton));
  CHECK(doc["lattices"][0]["min_length_fraction"] == 0.55);
  CHECK(doc["lattices"][0]["volume"] == 0.25);
  CHECK(doc["lattices"][1]["min_length_fraction"] == 0.0);
  CHECK_FALSE(doc["lattices"][1].contains("volume"));
  CHECK_FALSE(doc["lattices"][2].contains("min_length_fraction"));
  // Read: the values given, the defaults (0.7, 1) where absent.
  const deform::Rig rig = parse(R"({"rig": 1, "lattices": [{"name": "a", "bone": "forearm_l",
      "min_length_fraction": 0.8, "volume": 0}]})");
  CHECK(rig.lattices[0].shape == deform::StretchShape{0.8f, 0.0f});
  const deform::Rig defaults = parse(R"({"rig": 1, "lattices": [{"name": "a", "bone": "forearm_l"}]})");
  CHECK(defaults.lattices[0].shape == deform::StretchShape{});
  CHECK(defaults.lattices[0].shape.min_length_fraction == 0.7f);
  CHECK(defaults.lattices[0].shape.volume == 1.0f);
  // A shape on one lattice of the built-in rig survives the round trip.
  deform::Rig shaped = deform::builtin_rig(model());
  shaped.lattices[1].shape = {0.6f, 0.5f};
  CHECK(parse(deform::format_rig_json(shaped, model().skeleton)).lattices[1].shape == shaped.lattices[1].shape);
}

TEST_CASE("secondary motion: lattice motion and spring chains are written and read back, defaults filled in") {
  const nlohmann::json doc = nlohmann::json::parse(deform::format_rig_json(everything(), model().skeleton));
  CHECK(doc["lattices"][0]["motion"]["inertia"] == 0.75);
  CHECK(doc["lattices"][0]["motion"]["units_per_metre"] == 100.0);
  CHECK(doc["lattices"][0]["motion"]["along_bound"] == 0.05);
  CHECK(doc["lattices"][0]["motion"]["far_share"] == 0.25);
  // Absent, the bound and the far face's share take their defaults.
  const deform::Rig partial = parse(R"({"rig": 1, "lattices": [{"name": "a", "bone": "forearm_l",
      "motion": {"inertia": 0.5}}]})");
  CHECK(partial.lattices[0].motion.along_bound == deform::LatticeMotion{}.along_bound);
  CHECK(partial.lattices[0].motion.far_share == deform::LatticeMotion{}.far_share);
  CHECK(doc["lattices"][1]["motion"]["along_bound"] == doctest::Approx(0.02));
  // The part: absent (a file from before parts) it is unspecified and is not written back; given, it is kept.
  CHECK(partial.lattices[0].motion.part == deform::BodyPart::unspecified);
  CHECK_FALSE(
      nlohmann::json::parse(deform::format_rig_json(partial, model().skeleton))["lattices"][0]["motion"].contains(
          "part"));
  using deform::BodyPart;
  for (const BodyPart part : {BodyPart::upper_limb, BodyPart::lower_limb, BodyPart::hand, BodyPart::foot,
                              BodyPart::torso, BodyPart::head, BodyPart::appendage}) {
    deform::Rig with_part = partial;
    with_part.lattices[0].motion.part = part;
    const std::string text = deform::format_rig_json(with_part, model().skeleton);
    CHECK(nlohmann::json::parse(text)["lattices"][0]["motion"]["part"] == std::string(deform::body_part_name(part)));
    CHECK(parse(text).lattices[0].motion == with_part.lattices[0].motion);
  }
  CHECK(parse(R"({"rig": 1, "lattices": [{"name": "a", "bone": "forearm_l", "motion": {"part": "foot"}}]})")
            .lattices[0]
            .motion.part == deform::BodyPart::foot);
  CHECK(doc["springs"]["chains"][0]["bones"] == nlohmann::json::array({"fingers1_r", "fingers2_r"}));
  CHECK(doc["springs"]["colliders"][0]["bone"] == "chest");
  const deform::Rig rig = parse(R"({"rig": 1, "lattices": [], "springs": {"colliders": [{"bone": "head",
      "start": [0, 0.1, 0], "radius": 0.1}], "chains": [{"name": "t", "bones": ["neck", "head"],
      "colliders": [0]}]}})");
  REQUIRE(rig.spring_chains.size() == 1);
  CHECK(rig.colliders[0].end == rig.colliders[0].start);  // a sphere
  deform::SpringChainSpec expected;
  expected.name = "t";
  expected.bones = {model().skeleton.find("neck"), model().skeleton.find("head")};
  expected.colliders = {0};
  CHECK(rig.spring_chains[0] == expected);
  CHECK(rig.spring_substep == deform::SpringChains::default_substep);
  // The rig's chains and motion reach the character.
  deform::Rig moving = deform::builtin_rig(model());
  moving.lattices[0].motion = everything().lattices[0].motion;
  moving.spring_chains = everything().spring_chains;
  moving.colliders = everything().colliders;
  deform::Model m = model();
  const deform::Character character(std::move(m), moving);
  CHECK(character.springs().chain_count() == 2);
  CHECK(character.deformers().spec(0).motion.inertia == 0.75f);
}

TEST_CASE("a minimal rig takes the defaults") {
  const deform::Rig rig = parse(R"({"rig": 1, "lattices": [{"name": "a", "bone": "forearm_l"}]})");
  REQUIRE(rig.lattices.size() == 1);
  deform::LatticeSpec expected;
  expected.name = "a";
  expected.bone = model().skeleton.find("forearm_l");
  CHECK(rig.lattices[0] == expected);
  CHECK(rig.reach_effector == -1);
  CHECK(rig.model == deform::RigModel{});
}

TEST_CASE("bad rig files: the error names the file and the key") {
  const std::string lattice = R"({"name": "a", "bone": "forearm_l")";
  struct Case {
    std::string text;
    const char* expected;
  };
  const Case cases[] = {
      {"{\"rig\": 1, \"lattices\": [", "byte"},
      {"[]", "must be an object"},
      {R"({"lattices": []})", "key 'rig'"},
      {R"({"rig": 2, "lattices": []})", "key 'rig'"},
      {R"({"rig": 1})", "key 'lattices': is missing"},
      {R"({"rig": 1, "lattices": [], "extra": 1})", "key 'extra': unknown key"},
      {R"({"rig": 1, "lattices": [{"bone": "forearm_l"}]})", "key 'lattices[0].name'"},
      {R"({"rig": 1, "lattices": [{"name": "a", "bone": "elbow"}]})", "unknown bone 'elbow'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "degree": [3, 0, 3]}]})", "key 'lattices[0].degree[1]'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "degree": [3, 3]}]})", "key 'lattices[0].degree'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "degree": [3, 3.5, 3]}]})", "must be an integer"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "margin": "wide"}]})", "key 'lattices[0].margin'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "margin": 1e300}]})", "key 'lattices[0].margin'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "select": {"by": "list", "vertices": [1, 999999]}}]})",
       "key 'lattices[0].select.vertices[1]'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "select": {"by": "list", "vertices": [4, 4]}}]})",
       "listed twice"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "select": {"by": "nearest"}}]})", "key 'lattices[0].select.by'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "select": {"by": "weight", "threshold": 1}}]})",
       "key 'lattices[0].select.threshold'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "min_length_fraction": 1}]})",
       "key 'lattices[0].min_length_fraction': must be in [0, 1)"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "min_length_fraction": -0.1}]})",
       "key 'lattices[0].min_length_fraction'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "min_length_fraction": "soft"}]})",
       "key 'lattices[0].min_length_fraction'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "volume": 1.5}]})", "key 'lattices[0].volume'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "volume": -1}]})", "key 'lattices[0].volume'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "volume": 1e300}]})", "key 'lattices[0].volume'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "elastic": {"stiffness": 0}}]})",
       "key 'lattices[0].elastic.stiffness'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "elastic": {"integrator": "rk4"}}]})",
       "key 'lattices[0].elastic.integrator'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "elastic": {"springs": {"substep": -1}}}]})",
       "key 'lattices[0].elastic.springs.substep'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "elastic": {"dampening": 1}}]})",
       "key 'lattices[0].elastic.dampening': unknown key"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(}, )" + lattice + R"(}]})", "used twice"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "parent": "someone"}]})", "key 'lattices[0].parent'"},
      {R"({"rig": 1, "lattices": [{"name": "u", "bone": "upperarm_l"}, )" + lattice + R"(, "parent": null}]})",
       "the bones make the parent 'u'"},
      {R"({"rig": 1, "reach": {"effector": "hand_l", "root": "thigh_l"}, "lattices": []})", "key 'reach.root'"},
      {R"({"rig": 1, "model": "hero.fbx", "lattices": []})", "key 'model'"},
      {R"({"rig": 1, "model": {"obj": "a.obj"}, "lattices": []})", "key 'model.skeleton'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"inertia": 2}}]})",
       "key 'lattices[0].motion.inertia'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"gravity": [0, 1]}}]})",
       "key 'lattices[0].motion.gravity'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"units_per_metre": 0}}]})",
       "key 'lattices[0].motion.units_per_metre'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"along_bound": -0.1}}]})",
       "key 'lattices[0].motion.along_bound'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"far_share": 1.5}}]})",
       "key 'lattices[0].motion.far_share'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"part": "elbow"}}]})",
       "key 'lattices[0].motion.part': must be \"upper_limb\""},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"part": ""}}]})", "key 'lattices[0].motion.part'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"part": 3}}]})", "key 'lattices[0].motion.part'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"part": null}}]})", "key 'lattices[0].motion.part'"},
      {R"({"rig": 1, "lattices": [)" + lattice + R"(, "motion": {"part": "Hand"}}]})", "key 'lattices[0].motion.part'"},
      {R"({"rig": 1, "lattices": [], "springs": {"chains": [{"name": "t", "bones": []}]}})",
       "key 'springs.chains[0].bones'"},
      {R"({"rig": 1, "lattices": [], "springs": {"chains": [{"name": "t", "bones": ["neck", "chest"]}]}})",
       "key 'springs.chains[0].bones[1]': must be a child"},
      {R"({"rig": 1, "lattices": [], "springs": {"chains": [{"name": "t", "bones": ["neck"], "frequency": 0}]}})",
       "key 'springs.chains[0].frequency'"},
      {R"({"rig": 1, "lattices": [], "springs": {"chains": [{"name": "t", "bones": ["neck"], "colliders": [0]}]}})",
       "key 'springs.chains[0].colliders[0]'"},
      {R"({"rig": 1, "lattices": [], "springs": {"chains": [{"name": "t", "bones": ["neck"]},
           {"name": "t", "bones": ["head"]}]}})",
       "used twice"},
      {R"({"rig": 1, "lattices": [], "springs": {"colliders": [{"bone": "head", "start": [0, 0, 0], "radius": 0}]}})",
       "key 'springs.colliders[0].radius'"},
      {R"({"rig": 1, "lattices": [], "springs": {"substep": 2}})", "key 'springs.substep'"},
      {R"({"rig": 1, "lattices": [], "springs": {"stiffness": 2}})", "key 'springs.stiffness': unknown key"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.text);
    CHECK_THROWS_WITH_AS(parse(c.text), doctest::Contains(c.expected), deform::Error);
    CHECK_THROWS_WITH_AS(parse(c.text), doctest::Contains("test.rig.json"), deform::Error);
  }
  CHECK_THROWS_AS(deform::read_rig_json("/nonexistent/rig.json", model().skeleton, 10), deform::Error);
}

// default_rig: any model gets lattices on its limbs (tests/character/default_rig_test.cpp tests how they are found),
// and on the limb of a chosen effector; the rig binds.
TEST_CASE("default_rig puts lattices on every limb, or on the chosen effector's, and binds") {
  deform::Model renamed = model();
  renamed.name = "imported";
  const deform::Rig by_name = deform::default_rig(renamed);
  const deform::Rig full = deform::builtin_full_rig(model());
  REQUIRE(by_name.lattices.size() == full.lattices.size());
  for (std::size_t i = 0; i < full.lattices.size(); ++i) CHECK(by_name.lattices[i].bone == full.lattices[i].bone);
  CHECK(by_name.reach_effector == full.reach_effector);
  CHECK(by_name.reach_root == full.reach_root);
  REQUIRE(by_name.reach_chains.size() == 3);  // right hand, and the feet from their hip joints
  CHECK(by_name.reach_chains[1].root == renamed.skeleton.find("thigh_l"));

  // A chosen effector that ends no limb: it and its weighted ancestors get lattices, reaching from the bone above.
  const std::int32_t chosen = renamed.skeleton.find("ponytail4");
  REQUIRE(chosen > 0);
  const deform::Rig by_depth = deform::default_rig(renamed, chosen);
  CHECK(by_depth.reach_effector == chosen);
  CHECK(by_depth.reach_root != chosen);
  CHECK(renamed.skeleton.is_ancestor(by_depth.reach_root, chosen));
  CHECK(std::any_of(by_depth.lattices.begin(), by_depth.lattices.end(),
                    [&](const deform::LatticeSpec& spec) { return spec.bone == chosen; }));
  // The chains survive a rig file.
  const std::string text = deform::format_rig_json(by_name, renamed.skeleton);
  CHECK(deform::parse_rig_json(text, renamed.skeleton, renamed.mesh.point_count(), "chains.json") == by_name);
  CHECK_THROWS_WITH_AS(
      deform::parse_rig_json(R"({"rig": 1, "reach": {"chains": [{"effector": "foot_l", "root": "hand_l"}]},
                                 "lattices": []})",
                             renamed.skeleton, renamed.mesh.point_count(), "bad.json"),
      doctest::Contains("reach.chains[0].root"), deform::Error);

  // A reach chain whose root is not above its effector does not bind.
  deform::Rig crossed = by_name;
  crossed.reach_chains.push_back({renamed.skeleton.find("foot_l"), renamed.skeleton.find("hand_l")});
  CHECK_THROWS_WITH_AS(deform::Character(renamed, crossed), doctest::Contains("reach chain"), deform::Error);

  // The rig binds, and a far target stretches the limb.
  deform::Character character(renamed, by_depth);
  const glm::vec3 tip = character.bone_position(by_depth.reach_effector);
  const deform::ReachResult reach = character.reach(by_depth.reach_effector, tip + glm::vec3(0.0f, -0.5f, 0.3f));
  CHECK(reach.status);
  CHECK(reach.stretch > 0.0f);

  CHECK_THROWS_AS(deform::default_rig(renamed, 1000), deform::Error);
}
