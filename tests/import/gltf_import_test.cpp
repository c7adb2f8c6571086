// The glTF 2.0 reader (gltf_import.cpp) on files written here: skins bound by node (two same-named rigs apart),
// samplers kept as the file gives them, quantised and sparse accessors, the warnings for what is not read, and
// malformed files as errors naming the file and the JSON path or accessor.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "deform/import/import.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "gltf_doc.hpp"

namespace fs = std::filesystem;

namespace {

using gltf_doc::Doc;

std::string write(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("deform_gltf_test_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

std::string import_error(const std::string& path) {
  try {
    deform::import_model(path);
  } catch (const deform::Error& e) {
    return e.what();
  }
  return "no error";
}

// A quad strip at x0 over y in [0, 2], 3 rows; joints 0 (bottom) and 1 (top) of its skin.
struct Strip {
  int positions, joints, weights, indices;
};
Strip strip(Doc& doc, float x0) {
  std::vector<float> p;
  std::vector<std::uint16_t> j;
  std::vector<float> w;
  for (int r = 0; r < 3; ++r)
    for (float dx : {-0.5f, 0.5f}) {
      p.insert(p.end(), {x0 + dx, float(r), 0.0f});
      j.insert(j.end(), {0, 1, 0, 0});
      w.insert(w.end(), {1.0f - float(r) / 2.0f, float(r) / 2.0f, 0.0f, 0.0f});
    }
  const std::vector<std::uint16_t> i = {0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4};
  return {doc.accessor(p, "VEC3", 5126,
                       R"(, "min": [)" + std::to_string(x0 - 0.5f) + R"(, 0, 0], "max": [)" +
                           std::to_string(x0 + 0.5f) + ", 2, 0]"),
          doc.accessor(j, "VEC4", 5123), doc.accessor(w, "VEC4", 5126), doc.accessor(i, "SCALAR", 5123)};
}
std::string primitive(const Strip& s) {
  return R"({"attributes": {"POSITION": )" + std::to_string(s.positions) + R"(, "JOINTS_0": )" +
         std::to_string(s.joints) + R"(, "WEIGHTS_0": )" + std::to_string(s.weights) + R"(}, "indices": )" +
         std::to_string(s.indices) + "}";
}
std::vector<float> translation_ibm(float x, float y) { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -x, -y, 0, 1}; }

}  // namespace

TEST_CASE("two rigs with the same joint names each skin their own mesh with their own bind") {
  Doc doc;
  const Strip a = strip(doc, 0.0f), b = strip(doc, 5.0f);
  std::vector<float> ibm_a = translation_ibm(0, 0), ibm_a1 = translation_ibm(0, 1);
  ibm_a.insert(ibm_a.end(), ibm_a1.begin(), ibm_a1.end());
  std::vector<float> ibm_b = translation_ibm(5, 0), ibm_b1 = translation_ibm(5, 1);
  ibm_b.insert(ibm_b.end(), ibm_b1.begin(), ibm_b1.end());
  const int ia = doc.accessor(ibm_a, "MAT4", 5126), ib = doc.accessor(ibm_b, "MAT4", 5126);
  const int times = doc.accessor(std::vector<float>{0.0f, 0.5f, 1.0f}, "SCALAR", 5126, R"(, "min": [0], "max": [1])");
  const float h = std::sin(0.35f), c = std::cos(0.35f);  // 40° about z
  const int step = doc.accessor(std::vector<float>{0, 0, 0, 1, 0, 0, h, c, 0, 0, 0, 1}, "VEC4", 5126);
  const std::string body =
      R"("scene": 0, "scenes": [{"nodes": [0, 2, 4, 5]}], "nodes": [)"
      R"({"name": "Hips", "children": [1]}, {"name": "Spine", "translation": [0, 1, 0]},)"
      R"({"name": "Hips", "translation": [5, 0, 0], "children": [3]}, {"name": "Spine", "translation": [0, 1, 0]},)"
      R"({"name": "a", "mesh": 0, "skin": 0}, {"name": "b", "mesh": 1, "skin": 1}],)"
      R"("meshes": [{"primitives": [)" +
      primitive(a) + R"(]}, {"primitives": [)" + primitive(b) +
      R"(]}],)"
      R"("skins": [{"joints": [0, 1], "inverseBindMatrices": )" +
      std::to_string(ia) + R"(}, {"joints": [2, 3], "inverseBindMatrices": )" + std::to_string(ib) +
      R"(}],)"
      R"("animations": [{"name": "wave", "samplers": [{"input": )" +
      std::to_string(times) + R"(, "output": )" + std::to_string(step) +
      R"(, "interpolation": "STEP"}],)"
      R"("channels": [{"sampler": 0, "target": {"node": 3, "path": "rotation"}}]}])";
  const deform::ImportedModel imported = deform::import_model(write("two_rigs.gltf", doc.json(body)));
  const deform::Skeleton& skeleton = imported.model.skeleton;
  REQUIRE(skeleton.bone_count() == 5);  // an added root over the two Hips
  CHECK(imported.rigged);
  // Every point is weighted only to bones of its own rig: their bind x is the point's strip's.
  for (std::size_t p = 0; p < imported.model.mesh.point_count(); ++p) {
    const float strip_x = imported.model.mesh.positions[p].x < 2.5f ? 0.0f : 5.0f;
    for (int k = 0; k < 4; ++k) {
      if (imported.model.weights.weights[p][k] == 0.0f) continue;
      const glm::mat4& bind = imported.file_bind_world[imported.model.weights.bones[p][k]];
      CHECK(bind[3].x == doctest::Approx(strip_x));
    }
  }
  // The STEP sampler stays a step: at 0.4 s the spine holds its first key.
  REQUIRE(imported.clips.size() == 1);
  const deform::Animation& clip = imported.clips[0];
  bool found = false;
  for (const deform::Channel& channel : clip.channels) {
    if (channel.rotation.times.size() != 3) continue;
    found = true;
    CHECK(channel.rotation.interpolation == deform::Interpolation::step);
    const glm::quat q = deform::sample_track(channel.rotation, 0.4f, glm::quat(1, 0, 0, 0));
    CHECK(std::fabs(q.w) == doctest::Approx(1.0f));
  }
  CHECK(found);
  bool repeated_names_warned = false;
  for (const std::string& w : imported.warnings)
    repeated_names_warned |= w.find("share their name") != std::string::npos;
  CHECK(repeated_names_warned);
}

TEST_CASE("quantised positions, sparse accessors, cubic splines; every influence and the morph targets are kept") {
  Doc doc;
  // Normalised shorts (16384 / 32767 ≈ 0.5), 6 bytes per element padded to 8 as the spec requires (byteStride 8).
  int positions = 0;
  {
    const std::int16_t padded[12] = {-16384, 0, 0, 0, 16384, 0, 0, 0, 0, 16384, 0, 0};
    const std::size_t offset = doc.data.size();
    doc.data.resize(offset + sizeof padded);
    std::memcpy(doc.data.data() + offset, padded, sizeof padded);
    doc.views.push_back(R"({"buffer": 0, "byteOffset": )" + std::to_string(offset) +
                        R"(, "byteLength": 24, "byteStride": 8})");
    doc.accessors.push_back(R"({"bufferView": )" + std::to_string(doc.views.size() - 1) +
                            R"(, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC3",)"
                            R"( "min": [-0.5, 0, 0], "max": [0.5, 0.5, 0]})");
    positions = static_cast<int>(doc.accessors.size() - 1);
  }
  // Six influences on each vertex over six joints: two JOINTS/WEIGHTS sets.
  const int joints0 = doc.accessor(std::vector<std::uint8_t>{0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3}, "VEC4", 5121);
  const int joints1 = doc.accessor(std::vector<std::uint8_t>{4, 5, 0, 0, 4, 5, 0, 0, 4, 5, 0, 0}, "VEC4", 5121);
  const std::vector<float> w0 = {0.3f, 0.2f, 0.15f, 0.15f, 0.3f, 0.2f, 0.15f, 0.15f, 0.3f, 0.2f, 0.15f, 0.15f};
  const std::vector<float> w1 = {0.1f, 0.1f, 0, 0, 0.1f, 0.1f, 0, 0, 0.1f, 0.1f, 0, 0};
  const int weights0 = doc.accessor(w0, "VEC4", 5126), weights1 = doc.accessor(w1, "VEC4", 5126);
  const int target = doc.accessor(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3", 5126,
                                  R"(, "min": [0, 0, 1], "max": [0, 0, 1])");
  // A sparse translation output: zeros with key 1 replaced by (0, 2, 0).
  const int sparse_index = doc.accessor(std::vector<std::uint16_t>{1, 0}, "SCALAR", 5123);
  const int sparse_value = doc.accessor(std::vector<float>{0, 2, 0}, "VEC3", 5126);
  const int times = doc.accessor(std::vector<float>{0, 1}, "SCALAR", 5126, R"(, "min": [0], "max": [1])");
  doc.accessors.push_back(R"({"componentType": 5126, "count": 2, "type": "VEC3", "sparse": {"count": 1,)"
                          R"( "indices": {"bufferView": )" +
                          std::to_string(sparse_index) + R"(, "componentType": 5123}, "values": {"bufferView": )" +
                          std::to_string(sparse_value) + "}}}");
  const int sparse_output = static_cast<int>(doc.accessors.size() - 1);
  // A cubic spline rotation: (in-tangent, value, out-tangent) per key.
  const int cubic = doc.accessor(std::vector<float>{0, 0, 0.5f, 0, 0, 0, 0,          1,          0, 0, 0.5f, 0,
                                                    0, 0, 0.1f, 0, 0, 0, 0.3826834f, 0.9238795f, 0, 0, 0.1f, 0},
                                 "VEC4", 5126);
  std::vector<float> ibms;
  for (int j = 0; j < 6; ++j) {
    const std::vector<float> m = translation_ibm(0, 0.1f * float(j));
    ibms.insert(ibms.end(), m.begin(), m.end());
  }
  const int ibm = doc.accessor(ibms, "MAT4", 5126);
  const std::string body =
      R"("scene": 0, "scenes": [{"nodes": [0, 6]}], "extensionsUsed": ["KHR_mesh_quantization"],)"
      R"("extensionsRequired": ["KHR_mesh_quantization"], "nodes": [)"
      R"({"name": "j0", "children": [1]}, {"name": "j1", "translation": [0, 0.1, 0], "children": [2]},)"
      R"({"name": "j2", "translation": [0, 0.1, 0], "children": [3]}, {"name": "j3", "translation": [0, 0.1, 0], "children": [4]},)"
      R"({"name": "j4", "translation": [0, 0.1, 0], "children": [5]}, {"name": "j5", "translation": [0, 0.1, 0]},)"
      R"({"name": "body", "mesh": 0, "skin": 0}],)"
      R"("meshes": [{"name": "blob", "primitives": [{"attributes": {"POSITION": )" +
      std::to_string(positions) + R"(, "JOINTS_0": )" + std::to_string(joints0) + R"(, "WEIGHTS_0": )" +
      std::to_string(weights0) + R"(, "JOINTS_1": )" + std::to_string(joints1) + R"(, "WEIGHTS_1": )" +
      std::to_string(weights1) + R"(}, "targets": [{"POSITION": )" + std::to_string(target) +
      R"(}]}]}],)"
      R"("skins": [{"joints": [0, 1, 2, 3, 4, 5], "inverseBindMatrices": )" +
      std::to_string(ibm) +
      R"(}],)"
      R"("animations": [{"samplers": [{"input": )" +
      std::to_string(times) + R"(, "output": )" + std::to_string(sparse_output) + R"(}, {"input": )" +
      std::to_string(times) + R"(, "output": )" + std::to_string(cubic) +
      R"(, "interpolation": "CUBICSPLINE"}], "channels": [)"
      R"({"sampler": 0, "target": {"node": 0, "path": "translation"}},)"
      R"({"sampler": 1, "target": {"node": 1, "path": "rotation"}}]}])";
  const deform::ImportedModel imported = deform::import_model(write("quantised.gltf", doc.json(body)));
  REQUIRE(imported.model.mesh.point_count() == 3);
  CHECK(imported.model.mesh.positions[0].x == doctest::Approx(-16384.0f / 32767.0f));
  CHECK(imported.model.mesh.positions[2].y == doctest::Approx(16384.0f / 32767.0f));
  const deform::SkinWeights& sw = imported.model.weights;
  REQUIRE(sw.extra_points == std::vector<std::uint32_t>{0, 1, 2});
  REQUIRE(sw.extra_offsets == std::vector<std::uint32_t>{0, 2, 4, 6});
  for (std::size_t p = 0; p < 3; ++p) {
    const glm::vec4 w = sw.weights[p];
    // Six influences summing to 1: 0.3, 0.2, 0.15, 0.15 in the slots, 0.1 and 0.1 (joints 4, 5) as extras.
    CHECK(w.x + w.y + w.z + w.w + sw.extra_weights[2 * p] + sw.extra_weights[2 * p + 1] == doctest::Approx(1.0f));
    CHECK(w.x == doctest::Approx(0.3f));
    CHECK(sw.extra_weights[2 * p] == doctest::Approx(0.1f));
    CHECK(deform::influence_count(sw, p) == 6);
  }
  CHECK(sw.extra_bones[0] == imported.model.skeleton.find("j4"));
  CHECK(sw.extra_bones[1] == imported.model.skeleton.find("j5"));
  // The morph target: +1 in z on every point, named target0 (no extras.targetNames), default weight 0.
  REQUIRE(imported.model.morph_targets.size() == 1);
  const deform::MorphTarget& morph = imported.model.morph_targets[0];
  CHECK(morph.name == "target0");
  CHECK(morph.mesh == "blob");
  CHECK(morph.default_weight == 0.0f);
  CHECK(morph.points == std::vector<std::uint32_t>{0, 1, 2});
  CHECK(morph.position_deltas[1] == glm::vec3(0.0f, 0.0f, 1.0f));
  CHECK(morph.normal_deltas.empty());
  REQUIRE(imported.clips.size() == 1);
  for (const deform::Channel& channel : imported.clips[0].channels) {
    if (channel.bone == imported.model.skeleton.find("j0")) {
      REQUIRE(channel.translation.values.size() == 2);
      CHECK(channel.translation.values[1].y == doctest::Approx(2.0f));
    }
    if (channel.bone == imported.model.skeleton.find("j1")) {
      CHECK(channel.rotation.interpolation == deform::Interpolation::cubic_spline);
      REQUIRE(channel.rotation.in_tangents.size() == 2);
      CHECK(channel.rotation.in_tangents[1].z == doctest::Approx(0.1f));
      CHECK(channel.rotation.values[1].z == doctest::Approx(0.3826834f));
    }
  }
  std::string warnings;
  for (const std::string& w : imported.warnings) warnings += w + "\n";
  CAPTURE(warnings);
  CHECK(warnings.find("influences") == std::string::npos);
  CHECK(warnings.find("morph") == std::string::npos);
  // The isolated import carries the extras and the targets over the wire unchanged.
  const deform::ImportedModel isolated = deform::import_model_isolated(write("quantised.gltf", doc.json(body)));
  CHECK(isolated.model.weights == imported.model.weights);
  CHECK(isolated.model.morph_targets == imported.model.morph_targets);
  // The skins' listing, over the wire too: the one skin, its six joints, the mesh "blob".
  REQUIRE(imported.skins.size() == 1);
  CHECK(imported.skins[0].joints == 6);
  CHECK(imported.skins[0].meshes == std::vector<std::string>{"blob"});
  CHECK(isolated.skins == imported.skins);
}

TEST_CASE("malformed glTF files are errors naming the file and the JSON path or accessor") {
  const std::string triangle = R"("scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],)"
                               R"("meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}])";
  struct Case {
    const char* name;
    std::string json;
    const char* expected;
  };
  const std::string buffer36 = R"("buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)"
                               R"(AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}])";
  const std::string view =
      R"("bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 12, "byteLength": 6}],)";
  auto doc = [&](const std::string& accessors, const std::string& extra = "") {
    return R"({"asset": {"version": "2.0"}, )" + triangle + ", " + view + R"("accessors": [)" + accessors + "], " +
           buffer36 + extra + "}";
  };
  const std::string good_positions = R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"})";
  // The triangle with one morph target whose POSITION displacements are accessor 2.
  auto morph_doc = [&](const std::string& target) {
    std::string morphed = triangle;
    const std::string plain = R"("indices": 1})";
    morphed.replace(morphed.find(plain), plain.size(), R"("indices": 1, "targets": [{"POSITION": 2}]})");
    return R"({"asset": {"version": "2.0"}, )" + morphed + ", " + view + R"("accessors": [)" + good_positions +
           R"(, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}, )" + target + "], " + buffer36 +
           "}";
  };
  const Case cases[] = {
      {"morph_count.gltf", morph_doc(R"({"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"})"),
       "meshes[0].primitives[0].targets[0].POSITION: has not as many elements as POSITION"},
      {"morph_type.gltf", morph_doc(R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"})"),
       "accessors[2] (meshes[0].primitives[0].targets[0] POSITION): element type"},
      {"morph_ok.gltf", morph_doc(R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"})"),
       "meshes[0].primitives[0].indices: index 1"},  // a well-formed target: the import goes on to the indices
      {"past_view.gltf",
       doc(R"({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},)"
           R"({"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "accessors[0] (meshes[0].primitives[0] POSITION): 4 elements from byte 0 run past the end of bufferView 0"},
      {"huge_count.gltf",
       doc(R"({"bufferView": 0, "componentType": 5126, "count": 4611686018427387904,)"
           R"( "type": "VEC3"}, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "run past the end of bufferView 0"},
      {"bufferless.gltf",
       doc(R"({"componentType": 5126, "count": 4611686018427387904, "type": "VEC3"},)"
           R"({"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "elements without a bufferView"},
      {"index.gltf",
       doc(good_positions + R"(, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "meshes[0].primitives[0].indices: index 1 (16256"},
      {"no_accessor.gltf",
       doc(good_positions + R"(, {"bufferView": 7, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "accessor[1] invalid bufferView"},  // tinygltf's own check
      {"wrong_type.gltf",
       doc(R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"},)"
           R"({"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"})"),
       "accessors[0] (meshes[0].primitives[0] POSITION): element type"},
      {"view_outside.gltf",
       R"({"asset": {"version": "2.0"}, )" + triangle +
           R"(, "bufferViews": [{"buffer": 0, "byteOffset": 30, "byteLength": 36}], "accessors": [)" + good_positions +
           "], " + buffer36 + "}",
       "out of bounds"},  // tinygltf's own check
      {"two_parents.gltf", R"({"asset": {"version": "2.0"}, "nodes": [{"children": [2]}, {"children": [2]}, {}]})",
       "nodes[1].children: node 2 has more than one parent"},
      {"cycle.gltf", R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"children": [0]}]})",
       "nodes[0].children: node 0 has more than one parent"},
      {"extension.gltf", R"({"asset": {"version": "2.0"}, "extensionsRequired": ["KHR_draco_mesh_compression"]})",
       "extensionsRequired: KHR_draco_mesh_compression is not supported"},
      {"not_json.gltf", "{ this is not glTF", "not a valid glTF 2.0 file"},
      // glTF 1.0 (tinygltf read it as a scene with "no mesh", or "no asset"): said for what it is.
      {"version1.gltf", R"({"asset": {"version": "1.0"}, "meshes": {"box": {"primitives": []}}})",
       "asset.version: glTF 1.0 is not read, only 2.0"},
      {"version1_no_asset.gltf", R"({"meshes": {"box": {"primitives": []}}, "scene": "defaultScene"})",
       "asset.version: glTF 1.0 is not read, only 2.0"},
  };
  for (const Case& c : cases) {
    const std::string path = write(c.name, c.json);
    const std::string message = import_error(path);
    CAPTURE(message);
    CHECK(message.find(path) == 0);
    CHECK(message.find(c.expected) != std::string::npos);
  }
  // A .glb whose JSON chunk claims more bytes than the file has.
  const std::uint32_t header[5] = {0x46546C67u, 2u, 40u, 0xFFFFFFE0u, 0x4E4F534Au};
  std::string glb(reinterpret_cast<const char*>(header), sizeof header);
  glb += std::string(20, ' ');
  const std::string path = write("chunk.glb", glb);
  CHECK(import_error(path).find("GLB header") != std::string::npos);
  const std::uint32_t version1[5] = {0x46546C67u, 1u, 40u, 20u, 0u};
  const std::string glb1 = write(
      "version1.glb", std::string(reinterpret_cast<const char*>(version1), sizeof version1) + std::string(20, ' '));
  CHECK(import_error(glb1).find("GLB header: version 1, not 2 (glTF 1.0 is not read") != std::string::npos);
}

TEST_CASE("embedded PNG and JPEG textures are kept as their bytes: imported, exported natively and as glTF") {
  // A 1×1 PNG and the first bytes of a JPEG: the importer keeps images without decoding them.
  const std::vector<std::uint8_t> png = {
      0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A, 0x00, 0x00, 0x00, 0x0D, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
      0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x02, 0x00, 0x00, 0x00, 0x90, 0x77, 0x53, 0xDE, 0x00, 0x00, 0x00,
      0x0C, 0x49, 0x44, 0x41, 0x54, 0x08, 0xD7, 0x63, 0xF8, 0xCF, 0xC0, 0x00, 0x00, 0x03, 0x01, 0x01, 0x00, 0x18,
      0xDD, 0x8D, 0xB0, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4E, 0x44, 0xAE, 0x42, 0x60, 0x82};
  const std::vector<std::uint8_t> jpeg = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x10, 'J', 'F', 'I', 'F', 0x00};
  const std::vector<std::uint8_t> gif = {'G', 'I', 'F', '8', '9', 'a', 0x01, 0x00, 0x01, 0x00};
  Doc doc;
  const Strip s = strip(doc, 0.0f);
  std::vector<float> uv;
  for (int r = 0; r < 3; ++r) uv.insert(uv.end(), {0.0f, 0.25f * float(r), 1.0f, 0.25f * float(r)});
  const int uvs = doc.accessor(uv, "VEC2", 5126);
  doc.accessor(png, "SCALAR", 5121);  // its buffer view holds the PNG (the accessor itself is unused)
  const std::size_t png_view = doc.views.size() - 1;
  doc.accessor(gif, "SCALAR", 5121);
  const std::size_t gif_view = doc.views.size() - 1;
  std::vector<float> ibm = translation_ibm(0, 0), ibm1 = translation_ibm(0, 1);
  ibm.insert(ibm.end(), ibm1.begin(), ibm1.end());
  const int ibms = doc.accessor(ibm, "MAT4", 5126);
  std::string with_uvs = primitive(s);
  with_uvs.insert(with_uvs.find('{', 1) + 1, R"("TEXCOORD_0": )" + std::to_string(uvs) + ", ");
  // Four primitives over the same strip, one per material: buffer-view PNG (twice: one image, shared), data-URI
  // JPEG, and a GIF, which glTF 2.0 does not allow.
  std::string primitives;
  for (int m = 0; m < 4; ++m) {
    std::string p = with_uvs;
    p.insert(p.size() - 1, R"(, "material": )" + std::to_string(m));
    primitives += (m ? ", " : "") + p;
  }
  const std::string body = R"("scene": 0, "scenes": [{"nodes": [0, 2]}], "nodes": [)"
                           R"({"name": "Hips", "children": [1]}, {"name": "Spine", "translation": [0, 1, 0]},)"
                           R"({"name": "skin", "mesh": 0, "skin": 0}], "meshes": [{"primitives": [)" +
                           primitives +
                           R"(]}],)"
                           R"("skins": [{"joints": [0, 1], "inverseBindMatrices": )" +
                           std::to_string(ibms) +
                           R"(}],)"
                           R"("materials": [{"name": "a", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},)"
                           R"({"name": "b", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},)"
                           R"({"name": "c", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},)"
                           R"({"name": "d", "pbrMetallicRoughness": {"baseColorTexture": {"index": 2}}}],)"
                           R"("textures": [{"source": 0}, {"source": 1}, {"source": 2}],)"
                           R"("images": [{"bufferView": )" +
                           std::to_string(png_view) +
                           R"(, "mimeType": "image/png"},)"
                           R"({"uri": "data:image/jpeg;base64,)" +
                           gltf_doc::base64(jpeg) +
                           R"("},)"
                           R"({"bufferView": )" +
                           std::to_string(gif_view) + R"(, "mimeType": "image/png"}])";
  const std::string path = write("embedded_textures.gltf", doc.json(body));
  for (const bool isolated : {false, true}) {
    CAPTURE(isolated);
    const deform::ImportedModel imported = isolated ? deform::import_model_isolated(path) : deform::import_model(path);
    const std::vector<deform::Material>& materials = imported.model.mesh.materials;
    REQUIRE(materials.size() == 4);
    REQUIRE(materials[0].diffuse_image);
    REQUIRE(materials[1].diffuse_image);
    REQUIRE(materials[2].diffuse_image);
    CHECK(*materials[0].diffuse_image == png);
    CHECK(*materials[1].diffuse_image == png);
    if (!isolated) CHECK(materials[0].diffuse_image == materials[1].diffuse_image);  // one copy, shared
    CHECK(*materials[2].diffuse_image == jpeg);
    CHECK(!materials[3].diffuse_image);
    CHECK(materials[0].diffuse_map.empty());
    bool gif_warned = false;
    for (const std::string& w : imported.warnings) gif_warned |= w.find("'d'") != std::string::npos;
    CHECK(gif_warned);
    // UVs in OBJ's convention: glTF's v = 0.5 (running down) is 0.5, 0.25 is 0.75.
    REQUIRE(imported.model.mesh.vertex_uvs.size() >= 6);
    CHECK(imported.model.mesh.vertex_uvs[2].y == doctest::Approx(0.75f));
  }

  // Native export: each image becomes one file beside the OBJ, named by map_Kd, with the same bytes.
  const deform::ImportedModel imported = deform::import_model(path);
  const fs::path folder = fs::temp_directory_path() / "deform_gltf_test_embedded_export";
  fs::remove_all(folder);
  const deform::ExportedFiles files = deform::export_native(imported.model, folder.string());
  REQUIRE(files.textures.size() == 2);
  const auto bytes_of = [](const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
  };
  CHECK(bytes_of(files.textures[0]) == png);
  CHECK(fs::path(files.textures[0]).extension() == ".png");
  CHECK(bytes_of(files.textures[1]) == jpeg);
  CHECK(fs::path(files.textures[1]).extension() == ".jpg");
  std::ifstream mtl(files.mtl);
  const std::string mtl_text((std::istreambuf_iterator<char>(mtl)), {});
  CHECK(mtl_text.find("map_Kd " + fs::path(files.textures[0]).filename().string()) != std::string::npos);
  fs::remove_all(folder);

  // glTF export keeps them as they are: written, read back, the same bytes on the same materials.
  const std::string glb = (fs::temp_directory_path() / "deform_gltf_test_embedded_back.glb").string();
  const deform::GltfWritten written = deform::write_gltf(glb, imported.model);
  CHECK(written.textures == 2);
  const deform::ImportedModel back = deform::import_model(glb);
  REQUIRE(back.model.mesh.materials.size() == 4);
  REQUIRE(back.model.mesh.materials[0].diffuse_image);
  CHECK(*back.model.mesh.materials[0].diffuse_image == png);
  REQUIRE(back.model.mesh.materials[2].diffuse_image);
  CHECK(*back.model.mesh.materials[2].diffuse_image == jpeg);
  const auto sorted_v = [](const std::vector<glm::vec2>& coordinates) {  // v flipped on the way out and back in
    std::vector<float> v;
    for (const glm::vec2& c : coordinates) v.push_back(c.y);
    std::sort(v.begin(), v.end());
    return v;
  };
  CHECK(sorted_v(back.model.mesh.vertex_uvs) == sorted_v(imported.model.mesh.vertex_uvs));
  fs::remove(glb);
}

TEST_CASE("a point split along a seam stays one point when morph targets move it, and only with equal deltas") {
  // A quad of four points whose render vertices split points 1 and 2 along a UV seam (six render vertices), skinned
  // to one bone; target "lift" moves point 2, the same on both sides of the seam. Written as glTF (each seam copy a
  // vertex of its own) and read back: four points, as without targets, and one sparse entry.
  deform::Model model;
  model.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  model.mesh.vertex_point = {0, 1, 2, 1, 2, 3};
  model.mesh.vertex_uvs = {{0, 0}, {0.5f, 0}, {0.5f, 1}, {0.6f, 0}, {0.6f, 1}, {1, 1}};
  model.mesh.vertex_normals = std::vector<glm::vec3>(6, glm::vec3(0, 0, 1));
  model.mesh.triangles = {0, 1, 2, 3, 4, 5};
  deform::Bone root;
  root.name = "root";
  model.skeleton = deform::Skeleton({root});
  model.weights.bones = std::vector<glm::u16vec4>(4, glm::u16vec4(0));
  model.weights.weights = std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 0));
  model.morph_targets.push_back({"lift", "", 0.0f, {2}, {{0, 0, 0.5f}}, {}});
  const std::string path = (fs::temp_directory_path() / "deform_gltf_test_seam_morph.glb").string();
  (void)deform::write_gltf(path, model);
  const deform::ImportedModel back = deform::import_model(path);
  CHECK(back.model.mesh.positions.size() == 4);
  CHECK(back.model.mesh.vertex_count() == 6);
  REQUIRE(back.model.morph_targets.size() == 1);
  REQUIRE(back.model.morph_targets[0].points.size() == 1);
  CHECK(back.model.mesh.positions[back.model.morph_targets[0].points[0]] == glm::vec3(1, 1, 0));
  // Moved differently on the two sides, the copies of point 2 cannot be one point: each keeps its own delta.
  model.mesh.positions.push_back({1, 1, 0});  // point 4: point 2's seam copy, moved by its own delta
  model.mesh.vertex_point = {0, 1, 2, 1, 4, 3};
  model.weights.bones.push_back(glm::u16vec4(0));
  model.weights.weights.push_back(glm::vec4(1, 0, 0, 0));
  model.morph_targets[0] = {"lift", "", 0.0f, {2, 4}, {{0, 0, 0.5f}, {0, 0, 0.25f}}, {}};
  (void)deform::write_gltf(path, model);
  const deform::ImportedModel apart = deform::import_model(path);
  CHECK(apart.model.mesh.positions.size() == 5);
  REQUIRE(apart.model.morph_targets[0].points.size() == 2);
  fs::remove(path);
}
