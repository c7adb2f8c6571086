// Bone levels of detail (deform/offline/bone_lod.hpp): the weights stay normalised, the kept sets nested and closed
// under parents, and the skinned error against the full character, as a fraction of its size, is 0 at level 0 and
// grows with the level: on the built-in character under its walk and on assimp-testmodels' rigged characters.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "import/skin_model.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skinning.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#endif

namespace {

using deform::BoneLod;
using deform::Model;
using deform::Pose;

float model_size(const Model& model) {
  const deform::Bounds bounds = deform::compute_bounds(model.mesh.positions);
  const glm::vec3 extent = bounds.max - bounds.min;
  return std::max({extent.x, extent.y, extent.z});
}

using import_test::skin;

// Poses to measure with: the clip sampled over its length when there is one, and seeded random bends of every bone.
std::vector<Pose> test_poses(const Model& model, const deform::Animation* clip) {
  std::vector<Pose> poses;
  if (clip != nullptr) {
    for (int k = 0; k < 8; ++k) {
      Pose pose = model.skeleton.bind_pose();
      deform::SamplingJob sampling;
      sampling.animation = clip;
      sampling.time = clip->duration * float(k) / 8.0f;
      sampling.rotations = pose.rotations;
      sampling.translations = pose.translations;
      REQUIRE(sampling.run());
      poses.push_back(std::move(pose));
    }
  }
  std::mt19937 random(36);
  std::uniform_real_distribution<float> angle(-0.6f, 0.6f);
  for (int k = 0; k < 4; ++k) {
    Pose pose = model.skeleton.bind_pose();
    for (glm::quat& q : pose.rotations) {
      const float x = angle(random), y = angle(random), z = angle(random);  // in this order on every compiler
      q = q * glm::quat(glm::vec3(x, y, z));
    }
    poses.push_back(std::move(pose));
  }
  return poses;
}

struct LevelError {
  double mean = 0.0;  // over poses and points, a fraction of the size
  double max = 0.0;
};

std::vector<LevelError> level_errors(const Model& model, const BoneLod& lod, const std::vector<Pose>& poses) {
  const double size = model_size(model);
  std::vector<LevelError> errors(lod.levels.size());
  for (const Pose& pose : poses) {
    const std::vector<glm::vec3> full = skin(model, model.weights, pose);
    for (std::size_t l = 0; l < lod.levels.size(); ++l) {
      const std::vector<glm::vec3> level = skin(model, lod.levels[l].weights, pose);
      for (std::size_t p = 0; p < full.size(); ++p) {
        const double d = glm::length(level[p] - full[p]) / size;
        errors[l].mean += d / double(full.size() * poses.size());
        errors[l].max = std::max(errors[l].max, d);
      }
    }
  }
  return errors;
}

// The structural properties every level has, and the errors measured on `poses`, checked to grow with the level.
void check_levels(const std::string& name, const Model& model, const BoneLod& lod, const std::vector<Pose>& poses) {
  CAPTURE(name);
  const deform::Skeleton& skeleton = model.skeleton;
  for (std::size_t l = 0; l < lod.levels.size(); ++l) {
    CAPTURE(l);
    const deform::BoneLodLevel& level = lod.levels[l];
    CHECK(deform::bone_lod_consistent(skeleton, level));
    REQUIRE(level.weights.size() == model.mesh.point_count());
    if (l > 0) {
      CHECK(level.kept_bones <= lod.levels[l - 1].kept_bones);
      CHECK(level.influences <= lod.levels[l - 1].influences);
      CHECK(level.weight_error >= lod.levels[l - 1].weight_error);
      // Nested: a bone this level keeps, the level before kept.
      for (std::size_t b = 0; b < skeleton.bone_count(); ++b)
        if (level.bone_map[b] == std::int32_t(b)) CHECK(lod.levels[l - 1].bone_map[b] == std::int32_t(b));
      CHECK(level.weights.extra_points.empty());  // max_influences 4
    }
    for (std::size_t b = 0; b < skeleton.bone_count(); ++b)
      if (skeleton.bones()[b].parent < 0) CHECK(level.bone_map[b] == std::int32_t(b));  // the roots stay
    // Weights sum to 1, strongest first, on kept bones only.
    for (std::size_t p = 0; p < level.weights.size(); ++p) {
      const glm::vec4 w = level.weights.weights[p];
      CHECK(std::abs(w.x + w.y + w.z + w.w - 1.0f) < 1e-5f);
      CHECK((w.x >= w.y && w.y >= w.z && w.z >= w.w));
      for (int k = 0; k < 4; ++k)
        if (w[k] > 0.0f) CHECK(level.bone_map[level.weights.bones[p][k]] == std::int32_t(level.weights.bones[p][k]));
    }
  }
  const std::vector<LevelError> errors = level_errors(model, lod, poses);
  CHECK(errors[0].max == 0.0);
  for (std::size_t l = 0; l < errors.size(); ++l) {
    MESSAGE(name << " level " << l << ": " << lod.levels[l].kept_bones << " bones, " << lod.levels[l].influences
                 << " influences, weight error " << lod.levels[l].weight_error << ", skinned error mean "
                 << errors[l].mean << " max " << errors[l].max << " of the size");
    if (l > 0) CHECK(errors[l].mean >= errors[l - 1].mean - 1e-7);
  }
  CHECK(errors.back().mean > errors[0].mean);  // the coarsest level does differ
}

}  // namespace

TEST_CASE("bone LOD on the built-in character: levels by bone count under the walk and random poses") {
  const Model model = deform::builtin_character();
  const deform::Animation walk = deform::builtin_walk(model);
  const std::size_t bones = model.skeleton.bone_count();
  deform::BoneLodSettings settings;
  settings.bones_per_level = {bones - 8, 14, 8};
  const BoneLod lod = deform::build_bone_lod(model, settings);
  REQUIRE(lod.levels.size() == 4);
  CHECK(lod.levels[0].kept_bones == bones);
  CHECK(lod.levels[0].weights == model.weights);
  CHECK(lod.levels[1].kept_bones == bones - 8);
  CHECK(lod.levels[2].kept_bones == 14);
  CHECK(lod.levels[3].kept_bones == 8);
  // Leaves first: the first level merges leaves only (bones with no children in the full skeleton or whose children
  // were merged at that level).
  for (std::size_t b = 0; b < bones; ++b) {
    if (lod.levels[1].bone_map[b] == std::int32_t(b)) continue;
    for (const std::int32_t child : model.skeleton.bones()[b].children)
      CHECK(lod.levels[1].bone_map[std::size_t(child)] != child);
  }
  for (std::size_t l = 1; l < lod.levels.size(); ++l) {
    std::string kept;
    for (std::size_t b = 0; b < bones; ++b)
      if (lod.levels[l].bone_map[b] == std::int32_t(b)) kept += model.skeleton.bones()[b].name + " ";
    MESSAGE("builtin level " << l << " keeps " << kept);
  }
  check_levels("builtin", model, lod, test_poses(model, &walk));
  // The consistency check refuses a kept bone under a merged one, and a bone mapped outside its ancestors.
  deform::BoneLodLevel broken = lod.levels[3];
  const std::int32_t hand = model.skeleton.find("hand_l");
  REQUIRE(broken.bone_map[std::size_t(hand)] != hand);
  broken.bone_map[std::size_t(hand)] = hand;
  ++broken.kept_bones;
  CHECK_FALSE(deform::bone_lod_consistent(model.skeleton, broken));
  broken = lod.levels[3];
  broken.bone_map[std::size_t(hand)] = model.skeleton.find("thigh_r");
  CHECK_FALSE(deform::bone_lod_consistent(model.skeleton, broken));
}

TEST_CASE("bone LOD judged on the motion: the walk's poses keep the bones the walk moves") {
  const Model model = deform::builtin_character();
  const deform::Animation walk = deform::builtin_walk(model);
  // The motion given (the walk sampled at other times than the poses measured on) against weight alone, without a
  // keep list, at bone counts where the walk's limbs compete with the bones it leaves still: the walk's error at each
  // level is less than half (by weight alone the shins and forearms go before the head and the clavicles).
  std::vector<Pose> motion;
  for (int k = 0; k < 12; ++k) {
    Pose pose = model.skeleton.bind_pose();
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    sampling.time = walk.duration * (float(k) + 0.5f) / 12.0f;
    sampling.rotations = pose.rotations;
    sampling.translations = pose.translations;
    REQUIRE(sampling.run());
    motion.push_back(std::move(pose));
  }
  deform::BoneLodSettings by_weight;
  by_weight.bones_per_level = {14, 10, 8};
  deform::BoneLodSettings by_motion = by_weight;
  by_motion.poses = motion;
  const BoneLod weight_lod = deform::build_bone_lod(model, by_weight);
  const BoneLod motion_lod = deform::build_bone_lod(model, by_motion);
  std::vector<Pose> walk_poses = test_poses(model, &walk);
  walk_poses.resize(8);  // the walk only: the random bends move every bone alike
  check_levels("builtin by motion", model, motion_lod, walk_poses);
  const std::vector<LevelError> by_weight_errors = level_errors(model, weight_lod, walk_poses);
  const std::vector<LevelError> by_motion_errors = level_errors(model, motion_lod, walk_poses);
  for (std::size_t l = 1; l < 4; ++l) {
    MESSAGE("level " << l << ": walk error mean/max by weight " << by_weight_errors[l].mean << " / "
                     << by_weight_errors[l].max << ", by motion " << by_motion_errors[l].mean << " / "
                     << by_motion_errors[l].max);
    CHECK(by_motion_errors[l].mean < 0.5 * by_weight_errors[l].mean);
    CHECK(by_motion_errors[l].max < 0.6 * by_weight_errors[l].max);
  }
  // A pose that does not fit the skeleton is refused, naming it.
  by_motion.poses[3].rotations.pop_back();
  try {
    (void)deform::build_bone_lod(model, by_motion);
    FAIL("a short pose was accepted");
  } catch (const deform::Error& error) {
    CHECK(std::string(error.what()).find("pose 3") != std::string::npos);
  }
  by_motion.poses[3] = model.skeleton.bind_pose();
  by_motion.poses[3].translations[2].x = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS((void)deform::build_bone_lod(model, by_motion), deform::Error);
}

TEST_CASE("bone LOD by weight-error budget, and kept bones") {
  const Model model = deform::builtin_character();
  deform::BoneLodSettings settings;
  settings.weight_error = {0.0f, 0.01f, 0.05f, 1.0f};
  const std::int32_t hand = model.skeleton.find("hand_l");
  REQUIRE(hand > 0);
  settings.keep = {hand};
  const BoneLod lod = deform::build_bone_lod(model, settings);
  REQUIRE(lod.levels.size() == 5);
  for (std::size_t l = 1; l < lod.levels.size(); ++l) {
    CAPTURE(l);
    CHECK(lod.levels[l].weight_error <= settings.weight_error[l - 1] + 1e-6f);
    // The kept bone and its ancestors stay.
    for (std::int32_t b = hand; b >= 0; b = model.skeleton.bone(b).parent)
      CHECK(lod.levels[l].bone_map[std::size_t(b)] == b);
  }
  // A budget of 0 merges only bones that carry no weight; a budget of 1 leaves the kept chain alone.
  CHECK(lod.levels[1].weight_error == 0.0f);
  std::size_t chain = 0;
  for (std::int32_t b = hand; b >= 0; b = model.skeleton.bone(b).parent) ++chain;
  CHECK(lod.levels[4].kept_bones == chain);
  CHECK(lod.levels[4].weight_error > lod.levels[3].weight_error);
  check_levels("builtin by budget", model, lod, test_poses(model, nullptr));
}

TEST_CASE("bone LOD refuses bad settings, naming the element") {
  const Model model = deform::builtin_character();
  const auto refused = [&](const deform::BoneLodSettings& settings, const std::string& element) {
    try {
      (void)deform::build_bone_lod(model, settings);
      FAIL("accepted");
    } catch (const deform::Error& error) {
      CHECK(std::string(error.what()).find(element) != std::string::npos);
    }
  };
  refused({}, "settings");
  refused({{10}, {0.1f}, {}, 4, {}}, "settings");
  refused({{10, 12}, {}, {}, 4, {}}, "level 2");
  refused({{}, {0.2f, 0.1f}, {}, 4, {}}, "level 2");
  refused({{}, {1.5f}, {}, 4, {}}, "level 1");
  refused({{10}, {}, {999}, 4, {}}, "keep");
  refused({{10}, {}, {}, 0, {}}, "settings");
  Model broken = model;
  broken.weights.weights[5].x = -1.0f;
  try {
    (void)deform::build_bone_lod(broken, {{10}, {}, {}, 4, {}});
    FAIL("accepted");
  } catch (const deform::Error& error) {
    CHECK(std::string(error.what()).find("point 5") != std::string::npos);
  }
}

#if defined(DEFORM_HAVE_IMPORT)
TEST_CASE("bone LOD on assimp-testmodels' rigged characters: errors grow with the level") {
  const std::string dir = "/usr/share/assimp/models/";
  for (const char* path : {"IQM/mrfixit.iqm", "X/Testwuson.X", "FBX/huesitos.fbx"}) {
    const std::string file = path;
    CAPTURE(file);
    REQUIRE_MESSAGE(std::filesystem::exists(dir + path), path << " is missing: install Debian's assimp-testmodels");
    deform::ImportedModel imported = deform::import_model(dir + path);
    REQUIRE(imported.rigged);
    const Model& model = imported.model;
    const std::size_t bones = model.skeleton.bone_count();
    deform::BoneLodSettings settings;
    settings.bones_per_level = {bones * 3 / 4, bones / 2, bones / 4};
    const BoneLod lod = deform::build_bone_lod(model, settings);
    check_levels(path, model, lod, test_poses(model, imported.clips.empty() ? nullptr : &imported.clips.front()));
  }
}
#endif
