// The weights study (docs/weights.md) on every one of its characters, so that its figures cannot regress unnoticed:
// heat weights stay within a tenth above the figures docs/weights.md reports, within the targets where the
// table says they are met, and nearer the artists' weights than distance weights in mean, 99th percentile and
// largest distance; in the study's random poses, within a tenth of the side-by-side table and at or below Blender's
// recorded figures where heat leads (Blender itself is never run here). Fails when Debian's assimp-testmodels are
// not installed.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "deform/import/import.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/offline/weights.hpp"
#include "study.hpp"

namespace {

struct Expected {
  const char* path;  // under /usr/share/assimp/models
  double heat_mean;  // % of the diagonal, as docs/weights.md reports it
  double heat_p99;
  double heat_max;
};

// The targets of the weights issue (docs/weights.md, "Against the targets").
constexpr double target_mean = 0.5;
constexpr double target_p99 = 2.0;

void check_model(const Expected& e) {
  const std::filesystem::path path = std::filesystem::path("/usr/share/assimp/models") / e.path;
  REQUIRE_MESSAGE(std::filesystem::exists(path), path.string() << " is missing: install Debian's assimp-testmodels");
  const deform::ImportedModel imported = deform::import_model(path.string());
  const std::vector<std::uint8_t> deforming =
      deform::weighted_bones(imported.model.weights, imported.model.skeleton.bone_count());
  deform::HeatWeightsOptions heat_options;
  heat_options.deforming = deforming;
  const deform::WeightsResult heat =
      deform::compute_heat_weights(imported.model.mesh, imported.model.skeleton, heat_options);
  deform::AutoWeightsOptions distance_options;
  distance_options.deforming = deforming;
  const deform::SkinWeights distance =
      deform::compute_automatic_weights(imported.model.mesh, imported.model.skeleton, distance_options);
  const weights_study::Figures h = weights_study::compare(imported.model, imported.clips, heat.weights);
  const weights_study::Figures d = weights_study::compare(imported.model, imported.clips, distance);
  MESSAGE(std::string(e.path) << ": heat mean " << h.mean_percent << "%, p99 " << h.p99_percent << "%; distance mean "
                              << d.mean_percent << "%, p99 " << d.p99_percent << "%");
  REQUIRE(h.poses > 0);
  CHECK(h.mean_percent <= 1.1 * e.heat_mean);
  CHECK(h.p99_percent <= 1.1 * e.heat_p99);
  CHECK(h.max_percent <= 1.1 * e.heat_max);
  if (e.heat_mean <= target_mean) CHECK(h.mean_percent <= target_mean);
  if (e.heat_p99 <= target_p99) CHECK(h.p99_percent <= target_p99);
  CHECK(h.mean_percent < d.mean_percent);
  CHECK(h.p99_percent < d.p99_percent);
  CHECK(h.max_percent < d.max_percent);
}

}  // namespace

TEST_CASE("heat weights stay near the artists' on X/Testwuson.X") { check_model({"X/Testwuson.X", 0.23, 2.62, 5.31}); }
TEST_CASE("heat weights stay near the artists' on X/BCN_Epileptic.X") {
  check_model({"X/BCN_Epileptic.X", 0.17, 1.90, 4.46});
}
TEST_CASE("heat weights stay near the artists' on X/anim_test.x") { check_model({"X/anim_test.x", 0.60, 4.23, 5.43}); }
TEST_CASE("heat weights stay near the artists' on FBX/animation_with_skeleton.fbx") {
  check_model({"FBX/animation_with_skeleton.fbx", 0.46, 5.30, 5.55});
}
TEST_CASE("heat weights stay near the artists' on FBX/huesitos.fbx") {
  check_model({"FBX/huesitos.fbx", 0.78, 2.38, 3.01});
}
TEST_CASE("heat weights stay near the artists' on IQM/mrfixit.iqm") {
  check_model({"IQM/mrfixit.iqm", 0.24, 1.12, 1.70});
}

// The side-by-side study with Blender (docs/weights.md, "Side by side with Blender"): heat weights in 32 random poses
// (seed 1) stay within a tenth above the figures the table reports and, on the models where the table says heat
// leads, at or below Blender 3.4.1's recorded figures in mean, p99 and max (Blender given each mesh with its normals
// recalculated outside, as a rigger binds). Blender is not run here: its figures are the table's.
namespace {

struct SideBySide {
  const char* path;  // under /usr/share/assimp/models
  double heat[3];    // mean, p99, max: % of the diagonal, as the table reports them
  double blender[3];
  bool leads;  // the table says heat is at or below Blender in all three
};

void check_side_by_side(const SideBySide& e) {
  const std::filesystem::path path = std::filesystem::path("/usr/share/assimp/models") / e.path;
  REQUIRE_MESSAGE(std::filesystem::exists(path), path.string() << " is missing: install Debian's assimp-testmodels");
  const deform::ImportedModel imported = deform::import_model(path.string());
  const std::vector<std::uint8_t> deforming =
      deform::weighted_bones(imported.model.weights, imported.model.skeleton.bone_count());
  deform::HeatWeightsOptions heat_options;
  heat_options.deforming = deforming;
  const deform::WeightsResult heat =
      deform::compute_heat_weights(imported.model.mesh, imported.model.skeleton, heat_options);
  const weights_study::Figures h = weights_study::compare_palettes(
      imported.model, weights_study::random_palettes(imported.model.skeleton, deforming, 32, 1), heat.weights);
  MESSAGE(std::string(e.path) << ": random poses, heat mean " << h.mean_percent << "%, p99 " << h.p99_percent
                              << "%, max " << h.max_percent << "%");
  REQUIRE(h.poses == 32);
  const double got[3] = {h.mean_percent, h.p99_percent, h.max_percent};
  for (int k = 0; k < 3; ++k) {
    CHECK(got[k] <= 1.1 * e.heat[k]);
    if (e.leads) CHECK(got[k] <= e.blender[k]);
  }
}

}  // namespace

TEST_CASE("side by side with Blender's bone heat: X/Testwuson.X") {
  check_side_by_side({"X/Testwuson.X", {0.77, 5.35, 11.62}, {1.40, 21.50, 39.73}, true});
}
TEST_CASE("side by side with Blender's bone heat: X/BCN_Epileptic.X") {
  check_side_by_side({"X/BCN_Epileptic.X", {0.36, 2.19, 4.98}, {0.54, 4.45, 31.64}, true});
}
TEST_CASE("side by side with Blender's bone heat: X/anim_test.x") {
  check_side_by_side({"X/anim_test.x", {1.18, 6.74, 11.43}, {1.52, 10.53, 16.98}, true});
}
TEST_CASE("side by side with Blender's bone heat: FBX/animation_with_skeleton.fbx") {
  check_side_by_side({"FBX/animation_with_skeleton.fbx", {1.47, 12.49, 19.72}, {1.60, 14.37, 23.80}, true});
}
TEST_CASE("side by side with Blender's bone heat: FBX/huesitos.fbx") {
  check_side_by_side({"FBX/huesitos.fbx", {0.69, 1.91, 2.37}, {0.0, 0.0, 0.0}, false});
}
TEST_CASE("side by side with Blender's bone heat: IQM/mrfixit.iqm") {
  check_side_by_side({"IQM/mrfixit.iqm", {0.35, 1.93, 5.77}, {0.35, 2.21, 6.17}, true});
}

// The random-pose mode (weights_study --random-poses): the same seed gives the same poses, another seed others; every
// bone the artist weighted turns by at most the three ±20° axis turns (60° in all) from its bind local rotation,
// some by more than one axis' 20°; the other bones keep their bind local transform.
TEST_CASE("the study's random poses are seeded and turn only the weighted bones, within ±20° per axis") {
  const std::filesystem::path path = "/usr/share/assimp/models/IQM/mrfixit.iqm";
  REQUIRE_MESSAGE(std::filesystem::exists(path), path.string() << " is missing: install Debian's assimp-testmodels");
  const deform::ImportedModel imported = deform::import_model(path.string());
  const deform::Skeleton& skeleton = imported.model.skeleton;
  const std::vector<std::uint8_t> posed = deform::weighted_bones(imported.model.weights, skeleton.bone_count());
  const std::vector<deform::Pose> a = weights_study::random_poses(skeleton, posed, 16, 1);
  const std::vector<deform::Pose> b = weights_study::random_poses(skeleton, posed, 16, 1);
  const std::vector<deform::Pose> c = weights_study::random_poses(skeleton, posed, 16, 2);
  REQUIRE(a.size() == 16);
  const deform::Pose bind = skeleton.bind_pose();
  double largest = 0.0;
  bool other_seed_differs = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    CHECK(a[k].rotations == b[k].rotations);
    CHECK(a[k].translations == bind.translations);
    other_seed_differs = other_seed_differs || a[k].rotations != c[k].rotations;
    for (std::size_t bone = 0; bone < skeleton.bone_count(); ++bone) {
      if (posed[bone] == 0) {
        CHECK(a[k].rotations[bone] == bind.rotations[bone]);
        continue;
      }
      const glm::dquat turn = glm::inverse(glm::dquat(bind.rotations[bone])) * glm::dquat(a[k].rotations[bone]);
      const double degrees = glm::degrees(2.0 * std::acos(std::min(1.0, std::abs(turn.w))));
      CHECK(degrees <= 60.01);
      largest = std::max(largest, degrees);
    }
  }
  CHECK(other_seed_differs);
  CHECK(largest > 20.0);
  CHECK(weights_study::random_palettes(skeleton, posed, 16, 1).size() == 16);
}
