// The IQM reader (iqm_import.cpp) on assimp-testmodels' mrfixit.iqm, checked against the format's own definition
// evaluated here independently in double precision (iqm.txt: joint and pose channels, output = T · R · S · input,
// world = parent world · local, skin matrix = animated world · inverse bind world, weights / 255), and on hostile
// copies: truncated and corrupted files give a model or a deform::Error naming the file, never a crash.
#include <doctest/doctest.h>

#include "skin_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "deform/import/import.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path mrfixit = "/usr/share/assimp/models/IQM/mrfixit.iqm";

std::string require_model() {
  REQUIRE_MESSAGE(fs::exists(mrfixit), mrfixit.string() << " is missing: install Debian's assimp-testmodels");
  return mrfixit.string();
}

std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A trusting reader of a well-formed IQM file, written apart from the library's.
struct Iqm {
  std::vector<unsigned char> b;
  std::uint32_t u(std::size_t at) const {
    std::uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  }
  float f(std::size_t at) const {
    float v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  }
  std::uint32_t header(int i) const { return u(28 + 4 * static_cast<std::size_t>(i)); }
  std::uint32_t vertices() const { return header(5); }
  std::uint32_t joints() const { return header(10); }
  std::size_t array(std::uint32_t type) const {
    for (std::uint32_t a = 0; a < header(4); ++a)
      if (u(header(6) + 20 * a) == type) return u(header(6) + 20 * a + 16);
    FAIL("no vertex array of type " << type);
    return 0;
  }
  glm::dvec3 position(std::uint32_t v) const {
    const std::size_t at = array(0) + 12 * v;
    return {f(at), f(at + 4), f(at + 8)};
  }
  static glm::dmat4 trs(const double* c) {  // c: Tx Ty Tz Qx Qy Qz Qw Sx Sy Sz
    glm::dmat4 m = glm::mat4_cast(glm::normalize(glm::dquat(c[6], c[3], c[4], c[5])));
    for (int k = 0; k < 3; ++k) m[k] *= c[7 + k];
    m[3] = glm::dvec4(c[0], c[1], c[2], 1.0);
    return m;
  }
  std::int32_t parent(std::uint32_t j) const { return static_cast<std::int32_t>(u(header(11) + 48 * j + 4)); }
  std::vector<glm::dmat4> bind() const {
    std::vector<glm::dmat4> world(joints());
    for (std::uint32_t j = 0; j < joints(); ++j) {
      double c[10];
      for (int k = 0; k < 10; ++k) c[k] = f(header(11) + 48 * j + 8 + 4 * static_cast<std::size_t>(k));
      world[j] = (parent(j) < 0 ? glm::dmat4(1.0) : world[static_cast<std::size_t>(parent(j))]) * trs(c);
    }
    return world;
  }
  // World transforms at absolute frame `frame`.
  std::vector<glm::dmat4> posed(std::uint32_t frame) const {
    std::vector<glm::dmat4> world(joints());
    std::size_t at = header(18) + 2 * static_cast<std::size_t>(frame) * header(17);
    for (std::uint32_t j = 0; j < joints(); ++j) {
      const std::size_t pose = header(13) + 88 * j;
      double c[10];
      for (int k = 0; k < 10; ++k) {
        c[k] = f(pose + 8 + 4 * static_cast<std::size_t>(k));
        if ((u(pose + 4) >> k) & 1u) {
          std::uint16_t value;
          std::memcpy(&value, b.data() + at, 2);
          at += 2;
          c[k] += value * static_cast<double>(f(pose + 48 + 4 * static_cast<std::size_t>(k)));
        }
      }
      world[j] = (parent(j) < 0 ? glm::dmat4(1.0) : world[static_cast<std::size_t>(parent(j))]) * trs(c);
    }
    return world;
  }
  // Every vertex skinned with `world` against the bind.
  std::vector<glm::dvec3> skin(const std::vector<glm::dmat4>& world) const {
    const std::vector<glm::dmat4> bind_world = bind();
    std::vector<glm::dvec3> out;
    for (std::uint32_t v = 0; v < vertices(); ++v) {
      glm::dvec4 sum(0.0);
      double total = 0.0;
      for (std::uint32_t i = 0; i < 4; ++i) {
        const double w = b[array(5) + 4 * v + i] / 255.0;
        const std::uint32_t j = b[array(4) + 4 * v + i];
        if (w == 0.0) continue;
        sum += w * (world[j] * glm::inverse(bind_world[j]) * glm::dvec4(position(v), 1.0));
        total += w;
      }
      out.emplace_back(glm::dvec3(sum) / total);
    }
    return out;
  }
};

using import_test::skin;

// Largest distance over render vertices (IQM vertex r is render vertex r: mrfixit's meshes are in vertex order).
double worst(const deform::Model& model, const std::vector<glm::vec3>& points, const std::vector<glm::dvec3>& ref) {
  REQUIRE(model.mesh.vertex_count() == ref.size());
  double out = 0.0;
  for (std::size_t r = 0; r < ref.size(); ++r)
    out = std::max(out, glm::length(glm::dvec3(points[model.mesh.vertex_point[r]]) - ref[r]));
  return out;
}

}  // namespace

TEST_CASE("mrfixit.iqm imports with its 75 joints, skin and clip; the bind pose is the file's mesh") {
  const std::string path = require_model();
  const deform::ImportedModel imported = deform::import_model(path);
  for (const std::string& w : imported.warnings) MESSAGE(w);
  CHECK(imported.warnings.empty());
  const deform::Model& model = imported.model;
  CHECK(imported.rigged);
  CHECK(imported.up == glm::vec3(0.0f, 0.0f, 1.0f));
  // 75 joints, three of them roots (Root, ElbowRot.L, ElbowRot.R): an added bone `root` at the origin holds them.
  CHECK(model.skeleton.bone_count() == 76);
  CHECK(model.skeleton.bones()[0].name == "root");
  CHECK(model.skeleton.bones()[1].name == "Root");
  CHECK(model.mesh.vertex_count() == 1861);
  CHECK(model.mesh.triangle_count() == 2988);
  REQUIRE(model.mesh.materials.size() == 2);
  CHECK(fs::path(model.mesh.materials[0].diffuse_map).filename() == "Body.jpg");
  CHECK(fs::is_regular_file(model.mesh.materials[1].diffuse_map));
  REQUIRE(imported.clips.size() == 1);
  CHECK(imported.clips[0].name == "idle");
  CHECK(imported.clips[0].duration == doctest::Approx(100.0 / 24.0));  // 101 frames at 24 fps, not marked looping
  CHECK(imported.clips[0].channels.size() == 75);                      // one per joint

  const Iqm file{read_bytes(path)};
  std::vector<glm::dvec3> rest;
  for (std::uint32_t v = 0; v < file.vertices(); ++v) rest.push_back(file.position(v));
  const deform::Bounds bounds = deform::compute_bounds(model.mesh.positions);
  const double diagonal = glm::length(bounds.max - bounds.min);
  CHECK(worst(model, model.mesh.positions, rest) <= 1e-7 * diagonal);
  CHECK(worst(model, skin(model, model.skeleton.bind_pose()), rest) <= 1e-5 * diagonal);
  // The file's own rest: skinning the IQM bind with itself is the identity.
  CHECK(worst(model, model.mesh.positions, file.skin(file.bind())) <= 1e-5 * diagonal);
}

TEST_CASE("mrfixit.iqm: the clip at every frame time skins as the IQM frames define") {
  const std::string path = require_model();
  const deform::ImportedModel imported = deform::import_model(path);
  const deform::Model& model = imported.model;
  REQUIRE(imported.clips.size() == 1);
  deform::Animation clip = imported.clips[0];
  clip.loop = false;
  const Iqm file{read_bytes(path)};
  const deform::Bounds bounds = deform::compute_bounds(model.mesh.positions);
  const double diagonal = glm::length(bounds.max - bounds.min);
  double largest = 0.0, moved = 0.0;
  for (std::uint32_t frame = 0; frame < 101; ++frame) {
    deform::Pose pose = model.skeleton.bind_pose();
    deform::SamplingJob job;
    job.animation = &clip;
    job.time = static_cast<float>(frame / 24.0);
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    REQUIRE(job.run());
    const std::vector<glm::vec3> points = skin(model, pose);
    largest = std::max(largest, worst(model, points, file.skin(file.posed(frame))));
    moved = std::max(moved, worst(model, points, file.skin(file.bind())));
  }
  MESSAGE("mrfixit.iqm 'idle': largest distance to the IQM frames " << largest / diagonal << " of the diagonal");
  CHECK(largest <= 1e-5 * diagonal);
  CHECK(moved >= 1e-2 * diagonal);  // the clip does move the character
}

TEST_CASE("isolated import of mrfixit.iqm gives the same model") {
  const std::string path = require_model();
  const deform::ImportedModel local = deform::import_model(path);
  const deform::ImportedModel isolated = deform::import_model_isolated(path);
  CHECK(isolated.model.mesh.positions == local.model.mesh.positions);
  CHECK(isolated.model.weights == local.model.weights);
  CHECK(isolated.model.skeleton.bone_count() == local.model.skeleton.bone_count());
  REQUIRE(isolated.clips.size() == 1);
  CHECK(isolated.clips[0].duration == local.clips[0].duration);
  CHECK(isolated.up == local.up);
}

TEST_CASE("hostile IQM files: truncated, corrupted or lying headers give a model or an error naming the file") {
  const std::string path = require_model();
  const std::vector<unsigned char> original = read_bytes(path);
  const fs::path folder = fs::temp_directory_path() / ("deform_iqm_hostile_" + std::to_string(std::random_device{}()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const fs::path copy = folder / "model.iqm";
  auto attempt = [&](const std::vector<unsigned char>& bytes) -> std::string {
    std::ofstream(copy, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    try {
      const deform::ImportedModel imported = deform::import_model(copy.string());
      REQUIRE(imported.model.weights.size() == imported.model.mesh.point_count());
      for (const deform::Animation& clip : imported.clips) clip.require_valid(imported.model.skeleton.bone_count());
      return {};
    } catch (const deform::Error& e) {
      REQUIRE(e.file() == copy.string());
      return e.what();
    }
  };

  // Truncated: at every header field and at 200 places through the file.
  std::vector<std::size_t> cuts;
  for (std::size_t at = 0; at <= 124; at += 4) cuts.push_back(at);
  for (std::size_t k = 1; k < 200; ++k) cuts.push_back(original.size() * k / 200);
  for (const std::size_t cut : cuts) {
    CAPTURE(cut);
    const std::string message = attempt({original.begin(), original.begin() + static_cast<std::ptrdiff_t>(cut)});
    CHECK_FALSE(message.empty());
  }

  // Specific lies, each with the element and byte named.
  auto with_u32 = [&](std::size_t at, std::uint32_t value) {
    std::vector<unsigned char> bytes = original;
    std::memcpy(bytes.data() + at, &value, 4);
    return bytes;
  };
  CHECK(attempt(with_u32(0, 0x41414141)).find("not an IQM file") != std::string::npos);
  CHECK(attempt(with_u32(16, 3)).find("version 3") != std::string::npos);
  CHECK(attempt(with_u32(28 + 4 * 11, 0xFFFFFF00u)).find("joints at byte 4294967040") != std::string::npos);
  CHECK(attempt(with_u32(28 + 4 * 10, 0x40000000u)).find("joints") != std::string::npos);  // count overflows
  CHECK(attempt(with_u32(28 + 4 * 17, 7)).find("channel masks select") != std::string::npos);
  const std::uint32_t joints = [&] {
    std::uint32_t v;
    std::memcpy(&v, original.data() + 28 + 44, 4);
    return v;
  }();
  CHECK(attempt(with_u32(joints + 48 * 5 + 4, 9)).find("joints[5] at byte") != std::string::npos);  // parent after

  // Seeded random corruption: 1 to 16 bytes overwritten, half of them in the header and the records.
  std::mt19937 random(20261124);
  std::size_t errors = 0, models = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<unsigned char> bytes = original;
    const int changes = 1 + static_cast<int>(random() % 16);
    for (int c = 0; c < changes; ++c) {
      const std::size_t limit = random() % 2 ? 1036 + 6 * 20 : bytes.size();
      bytes[random() % limit] = static_cast<unsigned char>(random());
    }
    if (attempt(bytes).empty()) {
      ++models;
    } else {
      ++errors;
    }
  }
  MESSAGE("3000 corrupted copies: " << models << " models, " << errors << " errors");
  CHECK(models + errors == 3000);
  fs::remove_all(folder);
}

TEST_CASE("a looping IQM clip wraps from its last frame to its first; several root joints get an added root") {
  // tests/fuzz/corpus/iqm_import/two_joints.iqm: a bar of 4 vertices on joints `base` and `tip` (tip's last vertex
  // 128/127 between them), clip `bend`: 3 frames at 10 fps, marked looping, tip's rotation x and w animated.
  const fs::path seed = fs::path(DEFORM_SOURCE_DIR) / "tests/fuzz/corpus/iqm_import/two_joints.iqm";
  const deform::ImportedModel imported = deform::import_model(seed.string());
  REQUIRE(imported.rigged);
  REQUIRE(imported.model.skeleton.bone_count() == 2);
  CHECK(imported.model.skeleton.bones()[1].name == "tip");
  REQUIRE(imported.clips.size() == 1);
  const deform::Animation& clip = imported.clips[0];
  CHECK(clip.name == "bend");
  CHECK(clip.duration == doctest::Approx(0.3));  // 3 frames and the wrap back to the first
  auto tip_rotation = [&](float t) {
    deform::Pose pose = imported.model.skeleton.bind_pose();
    deform::SamplingJob job;
    job.animation = &clip;
    job.time = t;
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    REQUIRE(job.run());
    return pose.rotations[1];
  };
  // Frame 1: x = 32768 · 0.5 / 65535, w = 0.9 + 32768 · 0.1 / 65535, normalised.
  const glm::quat frame1 =
      glm::normalize(glm::quat(0.9f + 32768.0f * 0.1f / 65535.0f, 32768.0f * 0.5f / 65535.0f, 0.0f, 0.0f));
  CHECK(std::fabs(glm::dot(tip_rotation(0.1f), frame1)) == doctest::Approx(1.0).epsilon(1e-6));
  deform::Animation once = clip;
  once.loop = false;
  const glm::quat start = tip_rotation(0.0f);
  deform::Pose end_pose = imported.model.skeleton.bind_pose();
  deform::SamplingJob end;
  end.animation = &once;
  end.time = 0.3f;
  end.rotations = end_pose.rotations;
  end.translations = end_pose.translations;
  REQUIRE(end.run());
  CHECK(std::fabs(glm::dot(end_pose.rotations[1], start)) == doctest::Approx(1.0).epsilon(1e-6));
  // The split vertex: 128 / 255 and 127 / 255.
  bool split = false;
  for (const glm::vec4& w : imported.model.weights.weights)
    split = split || (std::fabs(w.x - 128.0f / 255.0f) < 1e-6f && std::fabs(w.y - 127.0f / 255.0f) < 1e-6f);
  CHECK(split);

  // Make `tip` a second root (its joint's and its pose's parent -1): an added bone `root` holds both.
  std::vector<unsigned char> bytes = read_bytes(seed);
  std::uint32_t joints;
  std::memcpy(&joints, bytes.data() + 28 + 44, 4);
  const std::int32_t none = -1;
  std::memcpy(bytes.data() + joints + 48 + 4, &none, 4);
  const fs::path two_roots =
      fs::temp_directory_path() / ("deform_iqm_two_roots_" + std::to_string(std::random_device{}()) + ".iqm");
  std::ofstream(two_roots, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  const deform::ImportedModel rooted = deform::import_model(two_roots.string());
  REQUIRE(rooted.model.skeleton.bone_count() == 3);
  CHECK(rooted.model.skeleton.bones()[0].name == "root");
  CHECK(rooted.model.skeleton.bones()[1].parent == 0);
  CHECK(rooted.model.skeleton.bones()[2].parent == 0);
  // The pose record still names `base` as tip's parent: the joints' hierarchy is used, with a warning.
  CHECK(std::any_of(rooted.warnings.begin(), rooted.warnings.end(),
                    [](const std::string& w) { return w.find("another parent") != std::string::npos; }));
  fs::remove(two_roots);
}

TEST_CASE("an IQM material naming a texture outside the model's folder is refused unless that folder is allowed") {
  std::vector<unsigned char> bytes = read_bytes(require_model());
  const std::string body = "Body.jpg", outside = "../s.jpg";  // same length: every offset stays
  const auto found = std::search(bytes.begin(), bytes.end(), body.begin(), body.end());
  REQUIRE(found != bytes.end());
  std::copy(outside.begin(), outside.end(), found);
  const fs::path root = fs::temp_directory_path() / ("deform_iqm_confined_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "m");
  const fs::path model = root / "m" / "fixit.iqm";
  std::ofstream(model, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  CHECK_THROWS_WITH_AS(deform::import_model(model.string()), doctest::Contains(".material"), deform::Error);
  deform::ImportOptions options;
  options.references.allow_outside = {root.string()};
  const deform::ImportedModel imported = deform::import_model(model.string(), options);
  CHECK(imported.model.mesh.materials.size() == 2);
  CHECK(imported.warnings.size() >= 1);  // both textures are missing: warnings, as before
  fs::remove_all(root);
}
