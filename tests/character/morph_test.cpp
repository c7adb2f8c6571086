// Character's morph targets: a morphed and skinned Character against MorphJob then SkinningJob run by hand (to the
// bit, LBS and DQS, positions and transported normals) and against a plain double-precision reference (seeded random
// targets, weights and poses: thousands of cases); the weight setters (index, name, span, clip) and their refusals;
// zero weights leave the frame as without targets; instances share the targets and own their weights; and, where the
// importer is built, a glTF morph + skin file through the Character against `deform skin` on the same file.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/skinning.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#include "deform/io/obj.hpp"
#include "import/gltf_doc.hpp"
#endif

using deform::Character;

namespace {

// Random sparse targets over `points` points: each moves a random ascending subset, with normal deltas or none.
std::vector<deform::MorphTarget> random_targets(std::mt19937& rng, std::size_t points, int count) {
  std::uniform_real_distribution<float> delta(-0.05f, 0.05f);
  std::bernoulli_distribution pick(0.3);
  std::vector<deform::MorphTarget> targets(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    deform::MorphTarget& t = targets[std::size_t(k)];
    t.name = k == 2 ? "twice" : k == 3 ? "twice" : "t" + std::to_string(k);
    t.default_weight = k == 0 ? 0.25f : 0.0f;
    const bool normals = k % 2 == 1;
    for (std::size_t p = 0; p < points; ++p) {
      if (!pick(rng)) continue;
      t.points.push_back(std::uint32_t(p));
      t.position_deltas.push_back({delta(rng), delta(rng), delta(rng)});
      if (normals) t.normal_deltas.push_back({delta(rng), delta(rng), delta(rng)});
    }
  }
  return targets;
}

deform::Model morphed_builtin(std::uint32_t seed, int count) {
  std::mt19937 rng(seed);
  deform::Model model = deform::builtin_character();
  model.morph_targets = random_targets(rng, model.mesh.point_count(), count);
  return model;
}

// A random pose within the limits (set_pose clamps anyway): small rotations about random axes.
deform::Pose random_pose(std::mt19937& rng, const deform::Skeleton& skeleton) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  deform::Pose pose = skeleton.bind_pose();
  for (std::size_t b = 0; b < pose.rotations.size(); ++b) {
    const glm::vec3 axis = glm::normalize(glm::vec3{u(rng), u(rng), u(rng)} + glm::vec3(1e-3f));
    pose.rotations[b] = glm::normalize(pose.rotations[b] * glm::angleAxis(0.4f * u(rng), axis));
  }
  return pose;
}

// MorphJob then SkinningJob by hand, as the Character's update() should run them: positions and point normals.
void by_hand(const Character& c, deform::SkinningMethod method, std::vector<glm::vec3>& positions,
             std::vector<glm::vec3>& normals) {
  const deform::Model& model = c.model();
  const std::size_t n = model.mesh.point_count();
  std::vector<glm::vec3> morphed(n), morphed_normals(n);
  deform::MorphJob morph;
  morph.targets = model.morph_targets;
  morph.weights = c.morph_weights();
  morph.rest_positions = model.mesh.positions;
  morph.rest_normals = c.bind_normals();
  morph.out_positions = morphed;
  morph.out_normals = morphed_normals;
  REQUIRE(morph.validate());
  REQUIRE(morph.run());
  const std::size_t bones = model.skeleton.bone_count();
  std::vector<glm::mat4> world(bones), palette(bones);
  deform::LocalToWorldJob fk;
  fk.skeleton = &model.skeleton;
  fk.rotations = c.pose().rotations;
  fk.translations = c.pose().translations;
  fk.world = world;
  fk.palette = palette;
  REQUIRE(fk.run());
  std::vector<deform::DualQuat> dual_quats(bones);
  std::vector<glm::mat3> scales(bones);
  positions.assign(n, glm::vec3(0.0f));
  normals.assign(n, glm::vec3(0.0f));
  deform::SkinningJob job;
  job.method = method;
  job.matrices = palette;
  job.bone_indices = model.weights.bones;
  job.bone_weights = model.weights.weights;
  job.extra_vertices = model.weights.extra_points;
  job.extra_offsets = model.weights.extra_offsets;
  job.extra_bones = model.weights.extra_bones;
  job.extra_weights = model.weights.extra_weights;
  job.in_positions = deform::as_floats(std::span<const glm::vec3>(morphed));
  job.out_positions = deform::as_floats(std::span<glm::vec3>(positions));
  job.in_normals = deform::as_floats(std::span<const glm::vec3>(morphed_normals));
  job.out_normals = deform::as_floats(std::span<glm::vec3>(normals));
  if (method == deform::SkinningMethod::dqs) {
    bool has_scale = false;
    REQUIRE(deform::compute_dual_quat_palette(palette, dual_quats, scales, has_scale));
    job.dual_quats = dual_quats;
    if (has_scale) job.scales = scales;
  }
  REQUIRE(job.run());
}

// The transported normals per point, gathered back from the render vertices (every vertex of a point has the same).
std::vector<glm::vec3> point_normals(Character& c) {
  const std::span<const glm::vec3> vertex = c.normals();
  std::vector<glm::vec3> out(c.model().mesh.point_count());
  for (std::size_t v = 0; v < vertex.size(); ++v) out[c.model().mesh.vertex_point[v]] = vertex[v];
  return out;
}

}  // namespace

TEST_CASE("a morphed, skinned Character equals MorphJob then SkinningJob by hand, to the bit (LBS and DQS)") {
  Character c(morphed_builtin(7, 5));
  REQUIRE(c.morph_target_count() == 5);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> weight(-1.0f, 1.5f);
  std::vector<glm::vec3> positions, normals;
  for (int round = 0; round < 40; ++round) {
    CAPTURE(round);
    c.settings.skinning = round % 2 ? deform::SkinningMethod::dqs : deform::SkinningMethod::lbs;
    REQUIRE(c.set_pose(random_pose(rng, c.skeleton())));
    for (std::size_t k = 0; k < c.morph_target_count(); ++k) REQUIRE(c.set_morph_weight(k, weight(rng)));
    REQUIRE(c.update(0.0f));
    by_hand(c, c.settings.skinning, positions, normals);
    const std::vector<glm::vec3> got_normals = point_normals(c);
    std::size_t differ = 0;
    for (std::size_t p = 0; p < positions.size(); ++p) {
      if (std::memcmp(&positions[p], &c.positions()[p], sizeof(glm::vec3)) != 0) ++differ;
      if (std::memcmp(&normals[p], &got_normals[p], sizeof(glm::vec3)) != 0) ++differ;
    }
    CHECK(differ == 0);
    CHECK(c.morphed_bind_positions().data() != c.model().mesh.positions.data());
  }
}

TEST_CASE("morph then LBS against a plain double-precision reference over thousands of random cases") {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> weight(-1.0f, 1.0f);
  long cases = 0;
  double worst = 0.0;
  for (std::uint32_t seed = 0; seed < 4; ++seed) {
    Character c(morphed_builtin(100 + seed, 6));
    const deform::Model& model = c.model();
    for (int round = 0; round < 3; ++round) {
      REQUIRE(c.set_pose(random_pose(rng, c.skeleton())));
      for (std::size_t k = 0; k < c.morph_target_count(); ++k) REQUIRE(c.set_morph_weight(k, weight(rng)));
      REQUIRE(c.update(0.0f));
      const std::span<const glm::mat4> palette = c.palette();
      // Morph in double: rest + Σ w·Δ over the targets that move the point; then Σ weight · (M · p).
      std::vector<glm::dvec3> morphed(model.mesh.point_count());
      for (std::size_t p = 0; p < morphed.size(); ++p) morphed[p] = glm::dvec3(model.mesh.positions[p]);
      for (std::size_t k = 0; k < model.morph_targets.size(); ++k) {
        const deform::MorphTarget& t = model.morph_targets[k];
        for (std::size_t i = 0; i < t.points.size(); ++i)
          morphed[t.points[i]] += double(c.morph_weights()[k]) * glm::dvec3(t.position_deltas[i]);
      }
      for (std::size_t p = 0; p < morphed.size(); ++p, ++cases) {
        glm::dvec3 expected(0.0);
        double sum = 0.0;
        for (int j = 0; j < 4; ++j) {
          const double w = model.weights.weights[p][j];
          if (w == 0.0) continue;
          expected += w * glm::dvec3(glm::dmat4(palette[model.weights.bones[p][j]]) * glm::dvec4(morphed[p], 1.0));
          sum += w;
        }
        REQUIRE(model.weights.extra_points.empty());  // the built-in character has four influences at most
        if (sum == 0.0) continue;
        worst = std::max(worst, glm::length(expected - glm::dvec3(c.positions()[p])));
      }
    }
  }
  MESSAGE(cases << " points checked, worst " << worst);
  CHECK(cases > 10000);
  CHECK(worst < 1e-5);  // model units: the built-in character is 1.8 tall
}

TEST_CASE("no targets or every weight 0: the frame is the unmorphed one; the setters and their refusals") {
  Character plain(deform::builtin_character());
  CHECK(plain.morph_target_count() == 0);
  CHECK(plain.morph_weights().empty());
  CHECK_FALSE(plain.set_morph_weight(std::size_t{0}, 1.0f));
  CHECK_FALSE(plain.set_morph_weight("t0", 1.0f));
  CHECK(plain.set_morph_weights(std::span<const float>{}));
  Character c(morphed_builtin(3, 4));
  // Default weights from the model: target 0 is 0.25.
  REQUIRE(c.morph_weights().size() == 4);
  CHECK(c.morph_weights()[0] == 0.25f);
  CHECK(c.morph_weights()[1] == 0.0f);
  const std::vector<float> zeros(4, 0.0f);
  REQUIRE(c.set_morph_weights(zeros));
  std::mt19937 rng(5);
  const deform::Pose pose = random_pose(rng, c.skeleton());
  REQUIRE(c.set_pose(pose));
  REQUIRE(plain.set_pose(pose));
  REQUIRE(c.update(0.0f));
  REQUIRE(plain.update(0.0f));
  CHECK(c.morphed_bind_positions().data() == c.model().mesh.positions.data());  // the job was skipped
  CHECK(std::memcmp(c.positions().data(), plain.positions().data(), plain.positions().size() * sizeof(glm::vec3)) == 0);

  // By name: every target of that name; refusals change nothing.
  REQUIRE(c.set_morph_weight("twice", 0.5f));
  CHECK(c.morph_weights()[2] == 0.5f);
  CHECK(c.morph_weights()[3] == 0.5f);
  CHECK(c.set_morph_weight("nose", 1.0f).reason() == std::string("no morph target of that name"));
  CHECK(c.set_morph_weight(std::size_t{4}, 1.0f).reason() == std::string("morph target out of range"));
  CHECK_FALSE(c.set_morph_weight(std::size_t{1}, std::nanf("")));
  CHECK_FALSE(c.set_morph_weight("t1", INFINITY));
  const std::vector<float> three(3, 1.0f), bad = {1.0f, NAN, 0.0f, 0.0f};
  CHECK_FALSE(c.set_morph_weights(three));
  CHECK_FALSE(c.set_morph_weights(bad));
  CHECK(c.morph_weights()[0] == 0.0f);
  CHECK(c.morph_weights()[1] == 0.0f);
  c.reset_morph_weights();
  CHECK(c.morph_weights()[0] == 0.25f);
  CHECK(c.morph_weights()[2] == 0.0f);

  // From a clip: the animated targets take its weights, the others keep theirs; refusals write nothing.
  deform::Animation clip;
  clip.name = "face";
  clip.duration = 1.0f;
  deform::MorphChannel channel;
  channel.target = 1;
  channel.weight.times = {0.0f, 1.0f};
  channel.weight.values = {0.0f, 1.0f};
  clip.morph_channels.push_back(channel);
  REQUIRE(c.set_morph_weight(std::size_t{2}, 0.75f));
  REQUIRE(c.set_morph_weights(clip, 0.5f));
  CHECK(c.morph_weights()[1] == doctest::Approx(0.5f));
  CHECK(c.morph_weights()[2] == 0.75f);
  CHECK_FALSE(c.set_morph_weights(clip, NAN));
  clip.morph_channels[0].target = 9;
  CHECK_FALSE(c.set_morph_weights(clip, 0.25f));
  CHECK(c.morph_weights()[1] == doctest::Approx(0.5f));

  // A malformed target is refused at construction, naming the model and the target.
  deform::Model broken = morphed_builtin(3, 1);
  broken.morph_targets[0].points.push_back(std::uint32_t(broken.mesh.point_count()));
  broken.morph_targets[0].position_deltas.push_back(glm::vec3(0.0f));
  CHECK_THROWS_AS(Character(std::move(broken)), deform::Error);
}

TEST_CASE("instances share the targets and own their weights") {
  Character a(morphed_builtin(9, 3));
  REQUIRE(a.set_morph_weight(std::size_t{1}, 1.0f));
  REQUIRE(a.update(0.0f));
  Character b = a.instance();
  CHECK(&b.model().morph_targets == &a.model().morph_targets);  // the bind data, not a copy
  CHECK(b.morph_weights()[1] == 0.0f);                          // an instance starts from the defaults
  CHECK(b.morph_weights()[0] == 0.25f);
  REQUIRE(b.set_morph_weight(std::size_t{1}, 1.0f));
  REQUIRE(b.update(0.0f));
  CHECK(std::memcmp(a.positions().data(), b.positions().data(), a.positions().size() * sizeof(glm::vec3)) == 0);
  REQUIRE(b.set_morph_weight(std::size_t{1}, -1.0f));
  REQUIRE(b.update(0.0f));
  CHECK(a.morph_weights()[1] == 1.0f);
  CHECK(std::memcmp(a.positions().data(), b.positions().data(), a.positions().size() * sizeof(glm::vec3)) != 0);
}

#if defined(DEFORM_HAVE_IMPORT) && defined(DEFORM_CLI)
namespace {

using gltf_doc::Doc;

// A bar of 5 rows × 2 points (y from 0 to 2) skinned to two joints (hips, spine at y = 1), two morph targets named
// by extras.targetNames ("bulge": the top rows, "lean": every point) with default weights [0.25, 0], and a clip
// "move": the spine's rotation and both weights, LINEAR.
std::string morph_skin_gltf() {
  Doc doc;
  std::vector<float> positions, weights, bulge(30, 0.0f), lean;
  std::vector<std::uint8_t> joints;
  for (int r = 0; r < 5; ++r) {
    for (int s = 0; s < 2; ++s) {
      const float y = 0.5f * float(r);
      positions.insert(positions.end(), {s ? 0.2f : -0.2f, y, 0.0f});
      const float w = std::clamp(y - 0.5f, 0.0f, 1.0f);
      joints.insert(joints.end(), {0, 1, 0, 0});
      weights.insert(weights.end(), {1.0f - w, w, 0.0f, 0.0f});
      const int p = 2 * r + s;
      if (r >= 3) bulge[std::size_t(3 * p)] = s ? 0.3f : -0.3f, bulge[std::size_t(3 * p + 2)] = 0.2f;
      lean.insert(lean.end(), {0.05f * float(r), 0.0f, -0.1f});
    }
  }
  const int position = doc.accessor(positions, "VEC3", 5126, R"(, "min": [-0.2, 0, 0], "max": [0.2, 2, 0])");
  const int joint = doc.accessor(joints, "VEC4", 5121);
  const int weight = doc.accessor(weights, "VEC4", 5126);
  const int bulge_target = doc.accessor(bulge, "VEC3", 5126, R"(, "min": [-0.3, 0, 0], "max": [0.3, 0, 0.2])");
  const int lean_target = doc.accessor(lean, "VEC3", 5126, R"(, "min": [0, 0, -0.1], "max": [0.2, 0, -0.1])");
  std::vector<std::uint16_t> indices;
  for (std::uint16_t r = 0; r < 4; ++r) {
    const std::uint16_t a = std::uint16_t(2 * r);
    indices.insert(indices.end(),
                   {a, std::uint16_t(a + 1), std::uint16_t(a + 3), a, std::uint16_t(a + 3), std::uint16_t(a + 2)});
  }
  const int index = doc.accessor(indices, "SCALAR", 5123);
  const int ibm = doc.accessor(std::vector<float>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0,  0, 1,
                                                  1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1},
                               "MAT4", 5126);
  const int times = doc.accessor(std::vector<float>{0.0f, 0.6f, 1.0f}, "SCALAR", 5126, R"(, "min": [0], "max": [1])");
  const float s35 = std::sin(0.5f * 35.0f * 3.14159265f / 180.0f), c35 = std::cos(0.5f * 35.0f * 3.14159265f / 180.0f);
  const float s20 = std::sin(-0.5f * 20.0f * 3.14159265f / 180.0f),
              c20 = std::cos(-0.5f * 20.0f * 3.14159265f / 180.0f);
  const int rotation = doc.accessor(std::vector<float>{0, 0, 0, 1, 0, 0, s35, c35, 0, 0, s20, c20}, "VEC4", 5126);
  const int morph_weights = doc.accessor(std::vector<float>{0.0f, 0.0f, 1.0f, 0.5f, 0.2f, 1.0f}, "SCALAR", 5126);
  const auto n = [](int i) { return std::to_string(i); };
  const std::string body =
      R"("scene": 0, "scenes": [{"nodes": [0, 2]}], "nodes": [)"
      R"({"name": "hips", "children": [1]}, {"name": "spine", "translation": [0, 1, 0]},)"
      R"({"name": "body", "mesh": 0, "skin": 0}],)"
      R"("meshes": [{"name": "bar", "weights": [0.25, 0], "extras": {"targetNames": ["bulge", "lean"]},)"
      R"( "primitives": [{"attributes": {"POSITION": )" +
      n(position) + R"(, "JOINTS_0": )" + n(joint) + R"(, "WEIGHTS_0": )" + n(weight) + R"(}, "indices": )" + n(index) +
      R"(, "targets": [{"POSITION": )" + n(bulge_target) + R"(}, {"POSITION": )" + n(lean_target) +
      R"(}]}]}],)"
      R"("skins": [{"joints": [0, 1], "inverseBindMatrices": )" +
      n(ibm) +
      R"(}],)"
      R"("animations": [{"name": "move", "samplers": [{"input": )" +
      n(times) + R"(, "output": )" + n(rotation) + R"(}, {"input": )" + n(times) + R"(, "output": )" +
      n(morph_weights) +
      R"(}], "channels": [)"
      R"({"sampler": 0, "target": {"node": 1, "path": "rotation"}},)"
      R"({"sampler": 1, "target": {"node": 2, "path": "weights"}}]}])";
  return doc.json(body);
}

}  // namespace

TEST_CASE("a glTF morph + skin file through the Character gives what `deform skin --clip` gives") {
  // A folder of this run's own (several builds may run the suite at once on one machine).
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("deform_character_morph_test_" + std::to_string(std::random_device{}()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "morph_skin.gltf").string();
  std::ofstream(path, std::ios::binary) << morph_skin_gltf();
  deform::ImportedModel imported = deform::import_model(path);
  REQUIRE(imported.model.morph_targets.size() == 2);
  REQUIRE(imported.clips.size() == 1);
  const deform::Animation clip = imported.clips[0];
  Character c(std::move(imported.model));
  for (const float time : {0.0f, 0.3f, 0.77f}) {
    for (const bool override_lean : {false, true}) {
      CAPTURE(time);
      CAPTURE(override_lean);
      deform::Pose pose = c.skeleton().bind_pose();
      deform::SamplingJob sampling;
      sampling.animation = &clip;
      sampling.time = time;
      sampling.rotations = pose.rotations;
      sampling.translations = pose.translations;
      REQUIRE(sampling.run());
      REQUIRE(c.set_pose(pose));
      c.reset_morph_weights();
      REQUIRE(c.set_morph_weights(clip, time));
      if (override_lean) REQUIRE(c.set_morph_weight("lean", -0.4f));
      REQUIRE(c.update(0.0f));
      const std::string out = (dir / "skinned.obj").string();
      std::filesystem::remove(out);
      const std::string command = std::string("\"") + DEFORM_CLI + "\" skin \"" + path + "\" --clip move --time " +
                                  std::to_string(time) + (override_lean ? " --morph lean:-0.4" : "") + " --out \"" +
                                  out + "\" > \"" + (dir / "skin.json").string() + "\"";
      REQUIRE(std::system(command.c_str()) == 0);
      const deform::Mesh skinned = deform::read_obj(out);
      REQUIRE(skinned.point_count() == c.positions().size());
      float worst = 0.0f;
      for (std::size_t p = 0; p < skinned.point_count(); ++p)
        worst = std::max(worst, glm::length(skinned.positions[p] - c.positions()[p]));
      CHECK(worst < 1e-5f);  // the OBJ's decimal text; the bar is 2 units tall
      if (time > 0.0f) CHECK(c.morphed_bind_positions().data() != c.model().mesh.positions.data());
    }
  }
  std::filesystem::remove_all(dir);
}
#endif
