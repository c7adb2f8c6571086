// write_gltf: the files it writes (and only those), their structure (GLB chunks, accessors that decode to the
// model's data, sparse morph targets, the frame-selecting weights), and the arguments it refuses. The Khronos
// validator and the round trip through the importer are the cli_gltf test's.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/runtime/error.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct Folder {
  fs::path path;
  explicit Folder(const char* name) : path(fs::temp_directory_path() / name) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Folder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

std::uint32_t u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return std::uint32_t(b[at]) | std::uint32_t(b[at + 1]) << 8 | std::uint32_t(b[at + 2]) << 16 |
         std::uint32_t(b[at + 3]) << 24;
}

// A quad (two triangles, four points, one submesh) with a two-bone skeleton.
deform::Model quad() {
  deform::Model model;
  model.name = "quad";
  model.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  model.mesh.vertex_point = {0, 1, 2, 3};
  model.mesh.vertex_normals = std::vector<glm::vec3>(4, glm::vec3(0, 0, 2));  // written normalised
  model.mesh.triangles = {0, 1, 2, 0, 2, 3};
  model.mesh.submeshes = {{0, 2, -1}};
  deform::Bone root;
  root.name = "root";
  root.children = {1};
  deform::Bone tip;
  tip.name = "tip";
  tip.parent = 0;
  tip.bind_translation = {0, 1, 0};
  model.skeleton = deform::Skeleton({root, tip});
  model.weights.bones = std::vector<glm::u16vec4>(4, glm::u16vec4(0));
  model.weights.weights = std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 0));
  model.weights.bones[2] = {1, 0, 0, 0};
  return model;
}

std::vector<float> floats(const Json& doc, const std::vector<std::uint8_t>& bin, int accessor) {
  const Json& a = doc["accessors"][accessor];
  const Json& v = doc["bufferViews"][a["bufferView"].get<int>()];
  const std::size_t width = a["type"] == "VEC3" ? 3 : a["type"] == "VEC4" ? 4 : a["type"] == "MAT4" ? 16 : 1;
  std::vector<float> out(a["count"].get<std::size_t>() * width);
  std::memcpy(out.data(), bin.data() + v["byteOffset"].get<std::size_t>(), out.size() * sizeof(float));
  return out;
}

}  // namespace

TEST_CASE(
    "write_gltf: a .glb holds the skinned mesh, its skeleton and clips in two chunks, and nothing else is written") {
  const Folder folder("deform_gltf_glb_test");
  deform::Animation clip;
  clip.name = "wave";
  clip.duration = 1.0f;
  deform::Channel channel;
  channel.bone = 1;
  channel.rotation.times = {0.0f, 1.0f};
  channel.rotation.values = {glm::quat(1, 0, 0, 0), glm::quat(0.7071068f, 0, 0, 0.7071068f)};
  clip.channels.push_back(channel);
  const std::vector<deform::Animation> clips = {clip};
  deform::GltfExportOptions options;
  options.clips = clips;
  const std::string path = (folder.path / "quad.GLB").string();
  const deform::GltfWritten written = deform::write_gltf(path, quad(), options);
  CHECK(written.bin.empty());
  CHECK(written.vertices == 4);
  CHECK(folder.files() == std::vector<std::string>{"quad.GLB"});

  const std::vector<std::uint8_t> glb = deform::read_file_bytes(path);
  REQUIRE(glb.size() == written.bytes);
  CHECK(u32(glb, 0) == 0x46546C67u);  // "glTF"
  CHECK(u32(glb, 4) == 2);
  CHECK(u32(glb, 8) == glb.size());
  const std::uint32_t json_length = u32(glb, 12);
  CHECK(json_length % 4 == 0);
  CHECK(u32(glb, 16) == 0x4E4F534Au);  // "JSON"
  const Json doc = Json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
  CHECK(u32(glb, 20 + json_length + 4) == 0x004E4942u);  // "BIN\0"
  const std::vector<std::uint8_t> bin(glb.begin() + 28 + json_length, glb.end());
  CHECK(bin.size() == doc["buffers"][0]["byteLength"].get<std::size_t>());

  CHECK(doc["asset"]["version"] == "2.0");
  REQUIRE(doc["nodes"].size() == 3);
  CHECK(doc["nodes"][0]["name"] == "root");
  CHECK(doc["nodes"][0]["children"] == Json::array({1}));
  CHECK(doc["nodes"][1]["translation"] == Json::array({0.0, 1.0, 0.0}));
  CHECK(doc["nodes"][2]["skin"] == 0);
  CHECK(doc["scenes"][0]["nodes"] == Json::array({0, 2}));
  CHECK(doc["skins"][0]["joints"] == Json::array({0, 1}));
  const Json& primitive = doc["meshes"][0]["primitives"][0];
  CHECK(floats(doc, bin, primitive["attributes"]["POSITION"].get<int>()) ==
        std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  CHECK(floats(doc, bin, primitive["attributes"]["NORMAL"].get<int>())[2] == 1.0f);
  const std::vector<float> inverse_binds = floats(doc, bin, doc["skins"][0]["inverseBindMatrices"].get<int>());
  CHECK(inverse_binds[16 + 13] == -1.0f);  // bone 1's inverse bind translates by -1 in y
  REQUIRE(doc["animations"].size() == 1);
  CHECK(doc["animations"][0]["name"] == "wave");
  CHECK(doc["animations"][0]["channels"][0]["target"] == Json{{"node", 1}, {"path", "rotation"}});
}

TEST_CASE(
    "write_gltf: a .gltf writes NAME.bin beside it; baked frames become sparse morph targets selected by weights") {
  const Folder folder("deform_gltf_bake_test");
  const deform::Model model = quad();
  deform::BakedFrames baked;
  baked.times = {0.0f, 0.5f, 1.0f};
  for (float s : {0.0f, 0.5f, 1.0f}) {
    std::vector<glm::vec3> p = model.mesh.positions;
    p[2].z += s;  // only point 2 moves
    baked.positions.push_back(p);
  }
  deform::GltfExportOptions options;
  options.baked = &baked;
  const std::string path = (folder.path / "bake.gltf").string();
  const deform::GltfWritten written = deform::write_gltf(path, model, options);
  CHECK(folder.files() == std::vector<std::string>{"bake.bin", "bake.gltf"});
  CHECK(written.morph_targets == 3);
  CHECK(written.sparse_values == 2);  // frames 1 and 2, one vertex each; frame 0 stores nothing
  const Json doc = Json::parse(deform::read_file_text(path));
  CHECK(doc["buffers"][0]["uri"] == "bake.bin");
  CHECK(!doc.contains("skins"));
  const Json& primitive = doc["meshes"][0]["primitives"][0];
  CHECK(!primitive["attributes"].contains("JOINTS_0"));
  REQUIRE(primitive["targets"].size() == 3);
  const Json& first = doc["accessors"][primitive["targets"][0]["POSITION"].get<int>()];
  CHECK(!first.contains("sparse"));
  CHECK(!first.contains("bufferView"));
  const Json& last = doc["accessors"][primitive["targets"][2]["POSITION"].get<int>()];
  CHECK(last["sparse"]["count"] == 1);
  CHECK(last["max"] == Json::array({0.0, 0.0, 1.0}));
  CHECK(doc["meshes"][0]["weights"] == Json::array({0.0, 0.0, 0.0}));
  const Json& sampler = doc["animations"][0]["samplers"][0];
  CHECK(sampler["interpolation"] == "LINEAR");
  const std::vector<std::uint8_t> bin = deform::read_file_bytes((folder.path / "bake.bin").string());
  CHECK(floats(doc, bin, sampler["output"].get<int>()) == std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1});
}

TEST_CASE("write_gltf: a skinned model's morph targets, named, and each clip's morph channels as one weights channel") {
  const Folder folder("deform_gltf_morph_test");
  deform::Model model = quad();
  model.morph_targets.push_back({"lift", "", 0.25f, {2}, {{0.0f, 0.0f, 0.5f}}, {}});
  model.morph_targets.push_back({"widen", "", 0.0f, {1, 2}, {{0.5f, 0.0f, 0.0f}, {0.5f, 0.0f, 0.0f}}, {}});
  deform::Animation clip;
  clip.name = "lift";
  clip.duration = 1.0f;
  deform::MorphChannel lift;
  lift.target = 0;
  lift.weight.times = {0.0f, 1.0f};
  lift.weight.values = {0.0f, 1.0f};
  clip.morph_channels.push_back(lift);
  deform::Animation mixed = clip;  // a second, step channel: the union of keys, linear, with a warning
  mixed.name = "mixed";
  deform::MorphChannel widen;
  widen.target = 1;
  widen.weight.interpolation = deform::Interpolation::step;
  widen.weight.times = {0.5f};
  widen.weight.values = {1.0f};
  mixed.morph_channels.push_back(widen);
  const std::vector<deform::Animation> clips = {clip, mixed};
  deform::GltfExportOptions options;
  options.clips = clips;
  const std::string path = (folder.path / "morphs.gltf").string();
  const deform::GltfWritten written = deform::write_gltf(path, model, options);
  CHECK(written.morph_targets == 2);
  CHECK(written.sparse_values == 3);  // lift: point 2; widen: points 1 and 2
  REQUIRE(written.warnings.size() == 1);
  CHECK(written.warnings[0].find("'mixed'") != std::string::npos);
  const Json doc = Json::parse(deform::read_file_text(path));
  const std::vector<std::uint8_t> bin = deform::read_file_bytes((folder.path / "morphs.bin").string());
  const Json& mesh = doc["meshes"][0];
  CHECK(mesh["weights"] == Json::array({0.25, 0.0}));
  CHECK(mesh["extras"]["targetNames"] == Json::array({"lift", "widen"}));
  REQUIRE(mesh["primitives"][0]["targets"].size() == 2);
  CHECK(!mesh["primitives"][0]["targets"][0].contains("NORMAL"));  // no target moves normals
  const Json& lifted = doc["accessors"][mesh["primitives"][0]["targets"][0]["POSITION"].get<int>()];
  CHECK(lifted["sparse"]["count"] == 1);
  CHECK(lifted["max"] == Json::array({0.0, 0.0, 0.5}));
  REQUIRE(doc["animations"].size() == 2);
  for (int a = 0; a < 2; ++a) {
    const Json& animation = doc["animations"][a];
    REQUIRE(animation["channels"].size() == 1);
    CHECK(animation["channels"][0]["target"] == Json{{"node", 2}, {"path", "weights"}});  // the mesh node
    CHECK(animation["samplers"][0]["interpolation"] == "LINEAR");
  }
  const Json& one = doc["animations"][0]["samplers"][0];
  CHECK(floats(doc, bin, one["input"].get<int>()) == std::vector<float>{0, 1});
  CHECK(floats(doc, bin, one["output"].get<int>()) == std::vector<float>{0, 0, 1, 0});  // widen at its default
  const Json& two = doc["animations"][1]["samplers"][0];
  CHECK(floats(doc, bin, two["input"].get<int>()) == std::vector<float>{0, 0.5f, 1});
  CHECK(floats(doc, bin, two["output"].get<int>()) == std::vector<float>{0, 1, 0.5f, 1, 1, 1});
  // A channel naming a target the model lacks is refused, writing nothing.
  deform::Animation beyond = clip;
  beyond.morph_channels[0].target = 2;
  const std::vector<deform::Animation> bad = {beyond};
  options.clips = bad;
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "bad.glb").string(), model, options), deform::Error);
  CHECK(!fs::exists(folder.path / "bad.glb"));
}

TEST_CASE("write_gltf: a model whose up is not +Y is written turned so that it stands in glTF's +Y up") {
  const Folder folder("deform_gltf_up_test");
  deform::Model model = quad();
  model.morph_targets.push_back({"bulge", "quad", 0.0f, {2}, {{0, 0, 1}}, {}});
  deform::Animation clip;
  clip.name = "rise";
  clip.duration = 1.0f;
  deform::Channel channel;
  channel.bone = 0;  // the root's track turns with the model; a child's is relative to it and stays
  channel.translation.times = {0.0f, 1.0f};
  channel.translation.values = {{0, 0, 0}, {0, 0, 2}};
  clip.channels.push_back(channel);
  const std::vector<deform::Animation> clips = {clip};
  const auto written = [&](glm::vec3 up, const char* name) {
    deform::GltfExportOptions options;
    options.clips = clips;
    options.up = up;
    const std::string path = (folder.path / name).string();
    deform::write_gltf(path, model, options);
    const Json doc = Json::parse(deform::read_file_text(path));
    const std::string bin_name = std::string(name).substr(0, std::string(name).size() - 5) + ".bin";
    return std::pair(doc, deform::read_file_bytes((folder.path / bin_name).string()));
  };
  const auto [y_doc, y_bin] = written({0, 3, 0}, "y.gltf");  // its length does not matter
  const auto [default_doc, default_bin] = written({0, 1, 0}, "default.gltf");
  CHECK(y_bin == default_bin);
  CHECK(!y_doc["nodes"][0].contains("rotation"));

  // +Z up: (x, y, z) is written as (x, z, -y), the root bone turned by -90 degrees about X, the tip's node as it was.
  const auto [z_doc, z_bin] = written({0, 0, 1}, "z.gltf");
  const Json& primitive = z_doc["meshes"][0]["primitives"][0];
  const std::vector<float> positions = floats(z_doc, z_bin, primitive["attributes"]["POSITION"].get<int>());
  const std::vector<float> expected = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1};
  REQUIRE(positions.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) CHECK(positions[i] == doctest::Approx(expected[i]).epsilon(1e-6));
  const std::vector<float> normal = floats(z_doc, z_bin, primitive["attributes"]["NORMAL"].get<int>());
  CHECK(normal[1] == doctest::Approx(1.0f));  // +Z was the quad's facing: now +Y
  const Json& rotation = z_doc["nodes"][0]["rotation"];
  CHECK(rotation[0].get<float>() == doctest::Approx(-0.70710678f));
  CHECK(rotation[3].get<float>() == doctest::Approx(0.70710678f));
  CHECK(z_doc["nodes"][1]["translation"] == y_doc["nodes"][1]["translation"]);
  // The tip's inverse bind undoes its turned world transform (at (0, 0, -1), turned): its rotation part is the turn
  // undone, which takes +Y to +Z (column 1 is (0, 0, 1)), and it takes the tip's place to the origin.
  const std::vector<float> inverse_binds = floats(z_doc, z_bin, z_doc["skins"][0]["inverseBindMatrices"].get<int>());
  CHECK(inverse_binds[16 + 6] == doctest::Approx(1.0f));
  CHECK(inverse_binds[16 + 13] == doctest::Approx(-1.0f));
  // The morph delta +Z turns to +Y, the root's translation track from +Z to +Y.
  const Json& target = primitive["targets"][0];
  CHECK(z_doc["accessors"][target["POSITION"].get<int>()]["max"][1].get<float>() == doctest::Approx(1.0f));
  const Json& sampler = z_doc["animations"][0]["samplers"][0];
  const std::vector<float> track = floats(z_doc, z_bin, sampler["output"].get<int>());
  REQUIRE(track.size() == 6);
  CHECK(track[4] == doctest::Approx(2.0f));
  CHECK(track[5] == doctest::Approx(0.0f).epsilon(1e-6));

  // Baked frames turn too: point 2 rising along +Z in the data rises along +Y in the file.
  deform::BakedFrames baked;
  baked.times = {0.0f, 1.0f};
  baked.positions = {model.mesh.positions, model.mesh.positions};
  baked.positions[1][2].z += 1.0f;
  deform::GltfExportOptions bake_options;
  bake_options.baked = &baked;
  bake_options.up = {0, 0, 1};
  deform::write_gltf((folder.path / "bake.gltf").string(), model, bake_options);
  const Json bake_doc = Json::parse(deform::read_file_text((folder.path / "bake.gltf").string()));
  const Json& moved = bake_doc["meshes"][0]["primitives"][0]["targets"][1]["POSITION"];
  CHECK(bake_doc["accessors"][moved.get<int>()]["max"][1].get<float>() == doctest::Approx(1.0f));
  CHECK(bake_doc["accessors"][moved.get<int>()]["max"][2].get<float>() == doctest::Approx(0.0f).epsilon(1e-6));

  // -Y up: half a turn. Zero or not finite: refused, writing nothing.
  const auto [down_doc, down_bin] = written({0, -1, 0}, "down.gltf");
  const std::vector<float> down = floats(down_doc, down_bin, primitive["attributes"]["POSITION"].get<int>());
  CHECK(down[7] == doctest::Approx(-1.0f));  // point 2's y
  const std::vector<std::string> before = folder.files();
  deform::GltfExportOptions zero;
  zero.up = glm::vec3(0.0f);
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "zero.glb").string(), model, zero), deform::Error);
  zero.up = glm::vec3(0.0f, std::nanf(""), 1.0f);
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "nan.glb").string(), model, zero), deform::Error);
  CHECK(folder.files() == before);
}

TEST_CASE("write_gltf: refuses what it cannot write, writing nothing") {
  const Folder folder("deform_gltf_refusal_test");
  const deform::Model model = quad();
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "quad.obj").string(), model), deform::Error);
  deform::Model no_triangles = model;
  no_triangles.mesh.triangles.clear();
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "a.glb").string(), no_triangles), deform::Error);
  deform::Model bad_weights = model;
  bad_weights.weights.bones.pop_back();
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "b.glb").string(), bad_weights), deform::Error);
  deform::BakedFrames baked;
  baked.times = {0.0f, 0.0f};  // not increasing
  baked.positions = {model.mesh.positions, model.mesh.positions};
  deform::GltfExportOptions options;
  options.baked = &baked;
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "c.glb").string(), model, options), deform::Error);
  baked.times = {0.0f, 1.0f};
  baked.positions[1].pop_back();  // a frame with a point missing
  CHECK_THROWS_AS(deform::write_gltf((folder.path / "d.glb").string(), model, options), deform::Error);
  CHECK(folder.files().empty());
}

TEST_CASE("write_gltf: the built-in character's texture is embedded only from inside texture_root") {
  const Folder folder("deform_gltf_texture_test");
  const deform::Model model = deform::builtin_character();  // its material names "builtin.png"
  deform::GltfExportOptions options;
  options.texture_root = DEFORM_SOURCE_DIR "/samples";  // the PNG is in samples/data, but the name is relative
  const deform::GltfWritten missing = deform::write_gltf((folder.path / "a.glb").string(), model, options);
  CHECK(missing.textures == 0);
  CHECK(missing.warnings.size() == 1);
  deform::Model textured = model;
  for (deform::Material& m : textured.mesh.materials)
    if (!m.diffuse_map.empty()) m.diffuse_map = DEFORM_SOURCE_DIR "/samples/data/" + m.diffuse_map;
  const deform::GltfWritten embedded = deform::write_gltf((folder.path / "b.glb").string(), textured, options);
  CHECK(embedded.textures == 1);
  CHECK(embedded.warnings.empty());
  options.texture_root = DEFORM_SOURCE_DIR "/tests";  // the texture lies outside this folder
  const deform::GltfWritten outside = deform::write_gltf((folder.path / "c.glb").string(), textured, options);
  CHECK(outside.textures == 0);
  CHECK(outside.warnings.size() == 1);
}

TEST_CASE("write_gltf: a texture the model holds in memory is embedded as it is, with no texture folder") {
  const Folder folder("deform_gltf_image_test");
  deform::Model model = deform::builtin_character();  // "builtin.png", no folder: no file to read
  const auto png = std::make_shared<const std::vector<std::uint8_t>>(
      deform::read_file_bytes(DEFORM_SOURCE_DIR "/samples/data/builtin.png"));
  model.mesh.materials[0].diffuse_map.clear();
  model.mesh.materials[0].diffuse_image = png;  // no texture_root: the bytes are the model's
  const deform::GltfWritten embedded = deform::write_gltf((folder.path / "a.glb").string(), model);
  CHECK(embedded.textures == 1);
  CHECK(embedded.warnings.empty());
  model.mesh.materials[0].diffuse_image =
      std::make_shared<const std::vector<std::uint8_t>>(std::vector<std::uint8_t>{'G', 'I', 'F', '8'});
  const deform::GltfWritten refused = deform::write_gltf((folder.path / "b.glb").string(), model);
  CHECK(refused.textures == 0);
  REQUIRE(refused.warnings.size() == 1);
  CHECK(refused.warnings[0].find("not a PNG or JPEG") != std::string::npos);
}

TEST_CASE("write_gltf: a texture is checked from its first bytes, once; allowed folders widen texture_root") {
  const Folder folder("deform_gltf_texture_once_test");
  deform::Model model = deform::builtin_character();
  // A sparse file past the 1 GiB read limit that is not an image, named by 300 materials: reading it whole would
  // fail the export (and 300 reads would take minutes).
  fs::create_directories(folder.path / "source");
  const fs::path large = folder.path / "source" / "large.png";
  { std::ofstream(large, std::ios::binary) << "not an image"; }
  fs::resize_file(large, (std::uintmax_t{1} << 30) + 1);
  REQUIRE(!model.mesh.materials.empty());
  model.mesh.materials.resize(300, model.mesh.materials[0]);
  for (std::size_t m = 0; m < 300; ++m) {
    model.mesh.materials[m].name = "m" + std::to_string(m);
    model.mesh.materials[m].diffuse_map = large.string();
  }
  deform::GltfExportOptions options;
  options.texture_root = (folder.path / "source").string();
  const deform::GltfWritten written = deform::write_gltf((folder.path / "a.glb").string(), model, options);
  CHECK(written.textures == 0);
  REQUIRE(!written.warnings.empty());
  CHECK(written.warnings[0].find("not a PNG or JPEG") != std::string::npos);
  // The built-in PNG from a folder outside texture_root: embedded only where that folder is allowed.
  deform::Model textured = deform::builtin_character();
  for (deform::Material& m : textured.mesh.materials)
    if (!m.diffuse_map.empty()) m.diffuse_map = DEFORM_SOURCE_DIR "/samples/data/" + m.diffuse_map;
  CHECK(deform::write_gltf((folder.path / "b.glb").string(), textured, options).textures == 0);
  options.references.allow_outside = {DEFORM_SOURCE_DIR "/samples/data"};
  CHECK(deform::write_gltf((folder.path / "c.glb").string(), textured, options).textures == 1);
}

TEST_CASE("write_gltf: influences past the fourth go to JOINTS_1 / WEIGHTS_1, beside the model's morph targets") {
  const Folder folder("deform_gltf_extra_test");
  deform::Model model = quad();
  std::vector<deform::Bone> bones(6);
  for (int b = 0; b < 6; ++b) {
    bones[std::size_t(b)].name = "b" + std::to_string(b);
    bones[std::size_t(b)].parent = b - 1;
    if (b > 0) bones[std::size_t(b)].bind_translation = {0, 0.2f, 0};
    if (b < 5) bones[std::size_t(b)].children = {b + 1};
  }
  model.skeleton = deform::Skeleton(bones);
  model.weights = {};
  const std::uint16_t six[] = {0, 1, 2, 3, 4, 5};
  const float w6[] = {6, 5, 4, 3, 2, 1};
  const std::uint16_t one[] = {2};
  const float w1[] = {1};
  deform::append_influences(model.weights, one, w1);
  deform::append_influences(model.weights, six, w6);
  deform::append_influences(model.weights, one, w1);
  deform::append_influences(model.weights, one, w1);
  model.morph_targets.push_back({"smile", "quad", 0.0f, {1}, {glm::vec3(0, 0, 1)}, {}});
  const std::string path = (folder.path / "extra.gltf").string();
  const deform::GltfWritten written = deform::write_gltf(path, model);
  CHECK(written.warnings.empty());
  CHECK(written.morph_targets == 1);
  const Json doc = Json::parse(deform::read_file_text(path));
  const std::vector<std::uint8_t> bin = deform::read_file_bytes((folder.path / "extra.bin").string());
  const Json& attributes = doc["meshes"][0]["primitives"][0]["attributes"];
  REQUIRE(attributes.contains("WEIGHTS_1"));
  CHECK(!attributes.contains("WEIGHTS_2"));
  const std::vector<float> w0 = floats(doc, bin, attributes["WEIGHTS_0"].get<int>());
  const std::vector<float> w1s = floats(doc, bin, attributes["WEIGHTS_1"].get<int>());
  // Vertex 1: 6/21 ... 1/21 over both sets; the others have all their weight on one bone and nothing in set 1.
  CHECK(w0[4] == doctest::Approx(6.0 / 21));
  CHECK(w1s[4] == doctest::Approx(2.0 / 21));
  CHECK(w1s[5] == doctest::Approx(1.0 / 21));
  CHECK(w1s[6] == 0.0f);
  CHECK(w1s[0] == 0.0f);
  CHECK(w0[0] == 1.0f);
  const Json& joints1 = doc["accessors"][attributes["JOINTS_1"].get<int>()];
  const Json& view = doc["bufferViews"][joints1["bufferView"].get<int>()];
  std::uint16_t j[8];
  std::memcpy(j, bin.data() + view["byteOffset"].get<std::size_t>(), sizeof j);
  CHECK(j[4] == 4);
  CHECK(j[5] == 5);
}
