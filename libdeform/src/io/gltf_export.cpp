// glTF 2.0 writer (deform/io/gltf_export.hpp, docs/gltf-export.md).
#include "deform/io/gltf_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <iterator>
#include <utility>
#include <limits>

#include <nlohmann/json.hpp>

#include "deform/io/atomic_file.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"

namespace deform {
namespace {

using Json = nlohmann::json;

// glTF enumerations (glTF 2.0 specification, 5.1 and 5.11).
constexpr int float_type = 5126;
constexpr int unsigned_short_type = 5123;
constexpr int unsigned_int_type = 5125;
constexpr int array_buffer = 34962;
constexpr int element_array_buffer = 34963;

std::string lower_extension(const std::string& path) {
  std::string ext = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// A file name every reader finds as a relative URI: characters outside [A-Za-z0-9._-] become '_' (percent-encoding
// would be valid, but Assimp 5.2 does not decode it).
std::string uri_safe(std::string name) {
  for (char& ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) && c < 128) && c != '-' && c != '.' && c != '_') ch = '_';
  }
  return name;
}

// The binary buffer and the JSON arrays that describe it, built together.
class Builder {
 public:
  Json accessors = Json::array();
  Json buffer_views = Json::array();
  std::vector<std::uint8_t> bin;

  // A buffer view over `bytes` bytes of `data`, 4-byte aligned; `target` 0 for none.
  int view(const void* data, std::size_t bytes, int target) {
    while (bin.size() % 4) bin.push_back(0);
    Json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    const auto* p = static_cast<const std::uint8_t*>(data);
    bin.insert(bin.end(), p, p + bytes);
    buffer_views.push_back(std::move(v));
    return static_cast<int>(buffer_views.size() - 1);
  }

  // A float accessor of `count` elements of `components` floats (type "SCALAR", "VEC2", "VEC3", "VEC4", "MAT4").
  int floats(const std::vector<float>& values, int components, const char* type, int target, bool bounds) {
    const std::size_t count = values.size() / std::size_t(components);
    const int v = view(values.data(), values.size() * sizeof(float), target);
    Json a = {{"bufferView", v}, {"componentType", float_type}, {"count", count}, {"type", type}};
    if (bounds) add_bounds(a, values, components);
    return push(std::move(a));
  }

  static void add_bounds(Json& accessor, const std::vector<float>& values, int components) {
    std::vector<float> lo(std::size_t(components), std::numeric_limits<float>::infinity());
    std::vector<float> hi(std::size_t(components), -std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::size_t c = i % std::size_t(components);
      lo[c] = std::min(lo[c], values[i]);
      hi[c] = std::max(hi[c], values[i]);
    }
    if (values.empty()) std::fill(lo.begin(), lo.end(), 0.0f), std::fill(hi.begin(), hi.end(), 0.0f);
    accessor["min"] = lo;
    accessor["max"] = hi;
  }

  int push(Json accessor) {
    accessors.push_back(std::move(accessor));
    return static_cast<int>(accessors.size() - 1);
  }
};

// A unit normal (glTF requires NORMAL to be unit length); a zero or non-finite one becomes +Z.
glm::vec3 unit_or_z(glm::vec3 n) {
  const float length = glm::length(n);
  if (!(length > 1e-20f) || !std::isfinite(length)) return {0.0f, 0.0f, 1.0f};
  return n / length;
}

// A VEC3 morph-target accessor holding `displacement` sparsely: the elements with a component beyond `tolerance`. No
// element: no bufferView and no sparse block (the accessor reads as zeros). Returns the accessor and adds its stored
// count. The sparse parts of every morph target, gathered into two buffer views (indices, values) so that the JSON
// holds one small accessor per target and attribute, not two buffer views each.
struct SparseData {
  std::vector<std::uint32_t> indices;
  std::vector<float> values;
  std::vector<std::size_t> patch;  // accessors whose sparse block names the two views, filled in at the end
};

int sparse_vec3(Builder& b, SparseData& sparse, const std::vector<glm::vec3>& displacement, float tolerance,
                bool bounds, std::size_t& stored) {
  const std::size_t first_index = sparse.indices.size(), first_value = sparse.values.size();
  std::vector<float> range;
  for (std::size_t i = 0; i < displacement.size(); ++i) {
    const glm::vec3 d = displacement[i];
    if (std::abs(d.x) <= tolerance && std::abs(d.y) <= tolerance && std::abs(d.z) <= tolerance) continue;
    sparse.indices.push_back(static_cast<std::uint32_t>(i));
    sparse.values.insert(sparse.values.end(), {d.x, d.y, d.z});
  }
  const std::size_t count = sparse.indices.size() - first_index;
  Json a = {{"componentType", float_type}, {"count", displacement.size()}, {"type", "VEC3"}};
  if (bounds) {
    range.assign(sparse.values.begin() + std::ptrdiff_t(first_value), sparse.values.end());
    if (count < displacement.size()) range.insert(range.end(), {0.0f, 0.0f, 0.0f});  // the zeros
    Builder::add_bounds(a, range, 3);
  }
  if (count > 0) {
    a["sparse"] = {{"count", count},
                   {"indices",
                    {{"bufferView", 0},
                     {"byteOffset", first_index * sizeof(std::uint32_t)},
                     {"componentType", unsigned_int_type}}},
                   {"values", {{"bufferView", 0}, {"byteOffset", first_value * sizeof(float)}}}};
    sparse.patch.push_back(b.accessors.size());
  }
  stored += count;
  return b.push(std::move(a));
}

const char* interpolation_name(Interpolation i) {
  switch (i) {
    case Interpolation::step: return "STEP";
    case Interpolation::cubic_spline: return "CUBICSPLINE";
    case Interpolation::linear: break;
  }
  return "LINEAR";
}

// Sampler output values of a track: the values, or (in-tangent, value, out-tangent) per key for CUBICSPLINE, as
// glTF orders them. Rotations are written as unit (x, y, z, w) quaternions; tangents as they are.
std::vector<float> track_output(const Track<glm::vec3>& t) {
  std::vector<float> out;
  for (std::size_t k = 0; k < t.times.size(); ++k) {
    if (t.interpolation == Interpolation::cubic_spline)
      out.insert(out.end(), {t.in_tangents[k].x, t.in_tangents[k].y, t.in_tangents[k].z});
    out.insert(out.end(), {t.values[k].x, t.values[k].y, t.values[k].z});
    if (t.interpolation == Interpolation::cubic_spline)
      out.insert(out.end(), {t.out_tangents[k].x, t.out_tangents[k].y, t.out_tangents[k].z});
  }
  return out;
}
std::vector<float> track_output(const Track<glm::quat>& t) {
  std::vector<float> out;
  for (std::size_t k = 0; k < t.times.size(); ++k) {
    if (t.interpolation == Interpolation::cubic_spline) {
      const glm::quat q = t.in_tangents[k];
      out.insert(out.end(), {q.x, q.y, q.z, q.w});
    }
    glm::quat q = t.values[k];
    const float length = glm::length(q);
    q = length > 0.0f ? q / length : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    out.insert(out.end(), {q.x, q.y, q.z, q.w});
    if (t.interpolation == Interpolation::cubic_spline) {
      const glm::quat o = t.out_tangents[k];
      out.insert(out.end(), {o.x, o.y, o.z, o.w});
    }
  }
  return out;
}

// The MIME type of a PNG or JPEG file by its first bytes, or "" for anything else.
std::string image_type(const std::vector<std::uint8_t>& bytes) {
  static const std::uint8_t png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static const std::uint8_t jpeg[] = {0xff, 0xd8, 0xff};
  if (bytes.size() >= sizeof png && std::equal(std::begin(png), std::end(png), bytes.begin())) return "image/png";
  if (bytes.size() >= sizeof jpeg && std::equal(std::begin(jpeg), std::end(jpeg), bytes.begin())) return "image/jpeg";
  return {};
}

// Reads a texture that may be embedded: inside `root` once links are resolved, PNG or JPEG. Empty result = refused,
// `why` says why.
std::vector<std::uint8_t> texture_bytes(const std::string& texture, const std::string& root,
                                        const ReferencePolicy& policy, std::string& why, std::string& mime) {
  namespace fs = std::filesystem;
  fs::path named;
  try {
    named = utf8_path::from_utf8(texture);
  } catch (const Error&) {  // only on Windows, where a path is the wide name its UTF-8 spells
    return why = "its name is not UTF-8", std::vector<std::uint8_t>{};
  }
  std::error_code error;
  const fs::path real = fs::canonical(named, error);
  if (error || !fs::is_regular_file(real, error)) return why = "not found", std::vector<std::uint8_t>{};
  const std::string real_utf8 = utf8_path::to_utf8(real);
  const fs::path real_root = fs::canonical(utf8_path::from_utf8(root), error);
  if (error) return why = "the texture folder '" + root + "' does not exist", std::vector<std::uint8_t>{};
  const fs::path inside = real.lexically_relative(real_root);
  bool allowed = !inside.empty() && *inside.begin() != "..";
  for (const std::string& other : policy.allow_outside) allowed = allowed || lies_inside(real_utf8, other);
  if (!allowed) return why = "it lies outside the model's folder '" + root + "'", std::vector<std::uint8_t>{};
  // The signature from the first bytes alone: a large file that is not an image is never read whole.
  const std::string format = image_format(real_utf8);
  if (format != "png" && format != "jpeg") return why = "it is not a PNG or JPEG file", std::vector<std::uint8_t>{};
  std::vector<std::uint8_t> bytes = read_file_bytes(real_utf8);
  mime = image_type(bytes);
  if (mime.empty()) return why = "it is not a PNG or JPEG file", std::vector<std::uint8_t>{};
  return bytes;
}

Json material_json(const Material& m, int texture) {
  const auto unit = [](float x) { return std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 1.0f; };
  const float alpha = unit(m.opacity);
  // A textured material shows its texture (as OBJ viewers do with map_Kd); glTF multiplies the factor in.
  const glm::vec3 colour = texture >= 0 ? glm::vec3(1.0f) : m.diffuse;
  Json pbr = {{"baseColorFactor", {unit(colour.r), unit(colour.g), unit(colour.b), alpha}},
              {"metallicFactor", 0.0},
              {"roughnessFactor", 1.0}};
  if (texture >= 0) pbr["baseColorTexture"] = {{"index", texture}};
  Json out = {{"pbrMetallicRoughness", std::move(pbr)}, {"doubleSided", true}};
  if (!m.name.empty()) out["name"] = m.name;
  if (alpha < 1.0f) out["alphaMode"] = "BLEND";
  return out;
}

void check_baked(const BakedFrames& baked, const Model& model) {
  const std::size_t frames = baked.times.size();
  if (frames == 0) throw Error::invalid_argument("baked", "no frames");
  if (baked.positions.size() != frames)
    throw Error::invalid_argument("baked.positions", "one entry per frame (" + std::to_string(frames) + ") expected");
  if (!baked.normals.empty() && baked.normals.size() != frames)
    throw Error::invalid_argument("baked.normals", "empty, or one entry per frame");
  for (std::size_t k = 0; k < frames; ++k) {
    if (!std::isfinite(baked.times[k]) || baked.times[k] < 0.0f || (k > 0 && !(baked.times[k] > baked.times[k - 1])))
      throw Error::invalid_argument("baked.times[" + std::to_string(k) + "]",
                                    "times must be finite, >= 0 and increasing");
    if (baked.positions[k].size() != model.mesh.point_count())
      throw Error::invalid_argument("baked.positions[" + std::to_string(k) + "]",
                                    "one position per mesh point expected");
    for (const glm::vec3& p : baked.positions[k])
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw Error::invalid_argument("baked.positions[" + std::to_string(k) + "]", "a position is not finite");
    if (!baked.normals.empty() && baked.normals[k].size() != model.mesh.vertex_count())
      throw Error::invalid_argument("baked.normals[" + std::to_string(k) + "]",
                                    "one normal per render vertex expected");
  }
}

// The checks write_gltf makes before it builds anything. Returns whether the file is binary (.glb).
bool check_export(const std::string& path, const Model& model, const GltfExportOptions& options) {
  const std::string ext = lower_extension(path);
  const bool binary = ext == ".glb";
  if (!binary && ext != ".gltf") throw Error::invalid_argument(path, "a glTF file name ends in .gltf or .glb");
  const Mesh& mesh = model.mesh;
  if (mesh.triangle_count() == 0) throw Error::invalid_argument(path, "the mesh has no triangles");
  if (mesh.vertex_count() > std::numeric_limits<std::uint32_t>::max())
    throw Error::invalid_argument(path, "more than 2^32 - 1 render vertices");
  const bool skinned = options.baked == nullptr;
  if (!skinned && !options.clips.empty())
    throw Error::invalid_argument("clips", "a baked file holds no skeleton: give clips or baked frames, not both");
  if (skinned && (model.weights.size() != mesh.point_count() || model.skeleton.bone_count() == 0))
    throw Error::invalid_argument(path, "the model's weights do not match its points, or it has no skeleton");
  if (!skinned) check_baked(*options.baked, model);
  const glm::vec3 up = options.up;
  if (!std::isfinite(up.x) || !std::isfinite(up.y) || !std::isfinite(up.z) || up == glm::vec3(0.0f))
    throw Error::invalid_argument("up", "the up direction is zero or not finite");
  if (skinned) {
    require_valid_morph_targets(model.morph_targets, mesh.point_count(), path);
    for (const Animation& clip : options.clips)
      for (const MorphChannel& channel : clip.morph_channels)
        if (channel.target < 0 || std::size_t(channel.target) >= model.morph_targets.size())
          throw Error::invalid_argument("clip '" + clip.name + "'",
                                        "a morph channel's target is not one of the "
                                        "model's " +
                                            std::to_string(model.morph_targets.size()) + " morph targets");
  }
  return binary;
}

// The shortest turn that takes `up` (finite, not zero: check_export) to +Y; half a turn about X when it is -Y; the
// identity, exactly, when it is +Y.
glm::quat turn_to_y_up(glm::vec3 up) {
  const glm::dvec3 u = glm::normalize(glm::dvec3(up)), y(0.0, 1.0, 0.0);
  const double cosine = glm::dot(u, y);
  if (cosine >= 1.0 - 1e-12) return {1.0f, 0.0f, 0.0f, 0.0f};
  if (cosine <= -1.0 + 1e-12) return {0.0f, 1.0f, 0.0f, 0.0f};
  const glm::dvec3 axis = glm::cross(u, y);  // (1 + u·y, u × y) is twice the half-angle quaternion, unnormalised
  return glm::quat(glm::normalize(glm::dquat(1.0 + cosine, axis.x, axis.y, axis.z)));
}

// What write_gltf writes for a model whose up is not +Y: the model, its clips and its baked frames turned about the
// origin. Points, normals and morph deltas turn; of the bones only the root does (bone 0: the others are relative to
// their parents), in its bind transform and its clip tracks.
struct TurnedExport {
  Model model;
  std::vector<Animation> clips;
  BakedFrames baked;
};

TurnedExport turned_export(const Model& source, const GltfExportOptions& options, glm::quat turn) {
  const auto turn_all = [turn](std::vector<glm::vec3>& vectors) {
    for (glm::vec3& v : vectors) v = turn * v;
  };
  TurnedExport out{
      source, {options.clips.begin(), options.clips.end()}, options.baked ? *options.baked : BakedFrames{}};
  Model& model = out.model;
  turn_all(model.mesh.positions);
  turn_all(model.mesh.vertex_normals);
  for (MorphTarget& target : model.morph_targets) turn_all(target.position_deltas), turn_all(target.normal_deltas);
  std::vector<Bone> bones(model.skeleton.bones().begin(), model.skeleton.bones().end());
  bones[0].bind_translation = turn * bones[0].bind_translation;
  bones[0].bind_rotation = euler_from_quat(turn * quat_from_euler(bones[0].bind_rotation));
  model.skeleton = Skeleton(std::move(bones));
  // A Hermite curve is linear in its values and tangents, so turning both turns every sample between the keys.
  for (Animation& clip : out.clips)
    for (Channel& channel : clip.channels) {
      if (channel.bone != 0) continue;
      turn_all(channel.translation.values), turn_all(channel.translation.in_tangents);
      turn_all(channel.translation.out_tangents);
      for (auto* keys : {&channel.rotation.values, &channel.rotation.in_tangents, &channel.rotation.out_tangents})
        for (glm::quat& q : *keys) q = turn * q;
    }
  for (auto& frame : out.baked.positions) turn_all(frame);
  for (auto& frame : out.baked.normals) turn_all(frame);
  return out;
}

// One glTF export, built in steps: the per-vertex data, the materials and images, one primitive per submesh (with the
// baked frames as morph targets), the nodes, skin and animations, then the file. The buffer's bytes and the
// accessors' indices follow the order of the steps, which write_gltf keeps.
class GltfExport {
 public:
  GltfExport(const std::string& path, const Model& model, const GltfExportOptions& options)
      : path_(path),
        model_(model),
        mesh_(model.mesh),
        skeleton_(model.skeleton),
        options_(options),
        skinned_(options.baked == nullptr),
        vertices_(model.mesh.vertex_count()) {
    written_.gltf = path;
  }

  GltfWritten write(bool binary) {
    doc_["asset"] = {{"version", "2.0"}, {"generator", options_.generator}};
    gather_vertices();
    if (skinned_) gather_influences();
    if (!skinned_ && !model_.morph_targets.empty())
      written_.warnings.push_back(std::to_string(model_.morph_targets.size()) +
                                  " morph targets of the model are not written (only baked frames become targets)");
    Json materials = Json::array();
    Json images = Json::array(), textures = Json::array();
    add_materials(materials, images, textures);
    Json gltf_mesh = mesh_json();

    Json nodes = Json::array();
    Json animations = Json::array();
    if (skinned_) {
      add_skin(nodes);
      for (const Animation& clip : options_.clips) add_clip(clip, animations);
    } else {
      add_baked_animation(nodes, animations);
    }
    doc_["scene"] = 0;
    doc_["nodes"] = std::move(nodes);
    doc_["meshes"] = Json::array({std::move(gltf_mesh)});
    if (!materials.empty()) doc_["materials"] = std::move(materials);
    if (!images.empty()) doc_["images"] = std::move(images), doc_["textures"] = std::move(textures);
    if (!animations.empty()) doc_["animations"] = std::move(animations);
    while (b_.bin.size() % 4) b_.bin.push_back(0);
    doc_["accessors"] = std::move(b_.accessors);
    doc_["bufferViews"] = std::move(b_.buffer_views);
    if (binary) write_glb();
    else write_gltf_and_bin();
    return std::move(written_);
  }

 private:
  const std::string& path_;
  const Model& model_;
  const Mesh& mesh_;
  const Skeleton& skeleton_;
  const GltfExportOptions& options_;
  const bool skinned_;          // clips over a skeleton; otherwise baked frames as morph targets
  const std::size_t vertices_;  // render vertices
  GltfWritten written_;
  Builder b_;
  Json doc_;
  SparseData sparse_;
  std::size_t frame_count_ = 0;            // morph targets per primitive: baked frames, or the model's targets
  std::vector<glm::vec3> base_positions_;  // per render vertex
  std::vector<glm::vec3> base_normals_;    // per render vertex, unit
  // Influence set s of render vertex r is vertex_joints_[s][r] / vertex_weights_[s][r]: set 0 the point's four
  // slots, sets 1, 2, ... its extra influences four at a time (JOINTS_1 / WEIGHTS_1, ...), all normalised to sum 1
  // together. None for baked frames.
  std::vector<std::vector<glm::u16vec4>> vertex_joints_;
  std::vector<std::vector<glm::vec4>> vertex_weights_;

  // --- per-vertex data over all render vertices; each primitive takes the vertices its triangles use ---
  void gather_vertices() {
    base_positions_.resize(vertices_);
    for (std::size_t r = 0; r < vertices_; ++r) base_positions_[r] = mesh_.positions.at(mesh_.vertex_point[r]);
    base_normals_.assign(vertices_, glm::vec3(0.0f, 0.0f, 1.0f));
    for (std::size_t r = 0; r < vertices_ && r < mesh_.vertex_normals.size(); ++r)
      base_normals_[r] = unit_or_z(mesh_.vertex_normals[r]);
  }

  void gather_influences() {
    const SkinWeights& sw = model_.weights;
    std::size_t most_extras = 0;
    for (std::size_t j = 0; j + 1 < sw.extra_offsets.size(); ++j)
      most_extras = std::max<std::size_t>(most_extras, sw.extra_offsets[j + 1] - sw.extra_offsets[j]);
    const std::size_t sets = 1 + (most_extras + 3) / 4;
    vertex_joints_.assign(sets, std::vector<glm::u16vec4>(vertices_, glm::u16vec4(0)));
    vertex_weights_.assign(sets, std::vector<glm::vec4>(vertices_, glm::vec4(0.0f)));
    std::vector<std::pair<std::uint16_t, float>> list;
    for (std::size_t r = 0; r < vertices_; ++r) {
      const std::uint32_t p = mesh_.vertex_point[r];
      list.clear();
      for (int i = 0; i < 4; ++i) list.emplace_back(sw.bones[p][i], sw.weights[p][i]);
      const auto it = std::lower_bound(sw.extra_points.begin(), sw.extra_points.end(), p);
      if (it != sw.extra_points.end() && *it == p) {
        const auto j = static_cast<std::size_t>(it - sw.extra_points.begin());
        for (std::uint32_t e = sw.extra_offsets[j]; e < sw.extra_offsets[j + 1]; ++e)
          list.emplace_back(sw.extra_bones[e], sw.extra_weights[e]);
      }
      float sum = 0.0f;
      for (auto& [bone, w] : list) {
        if (!(w > 0.0f) || bone >= skeleton_.bone_count()) w = 0.0f, bone = 0;  // glTF: unused = (0, 0)
        sum += w;
      }
      if (!(sum > 0.0f)) list.assign(1, {0, 1.0f}), sum = 1.0f;
      for (std::size_t k = 0; k < list.size(); ++k) {
        vertex_joints_[k / 4][r][int(k % 4)] = list[k].first;
        vertex_weights_[k / 4][r][int(k % 4)] = list[k].second / sum;
      }
    }
  }

  // --- materials, and the images they show: one glTF material per model material ---
  void add_materials(Json& materials, Json& images, Json& textures) {
    std::vector<std::pair<std::string, int>> embedded;                   // texture path -> texture index
    std::vector<std::pair<const std::vector<std::uint8_t>*, int>> kept;  // embedded image -> texture index
    std::map<std::string, std::string> refused;  // texture path -> why: each is checked, and read, once
    const auto add_image = [&](const std::vector<std::uint8_t>& bytes, const std::string& mime) {
      images.push_back({{"bufferView", b_.view(bytes.data(), bytes.size(), 0)}, {"mimeType", mime}});
      textures.push_back({{"source", images.size() - 1}});
      return static_cast<int>(textures.size() - 1);
    };
    for (const Material& m : mesh_.materials) {
      int texture = -1;
      if (m.diffuse_image && mesh_.vertex_uvs.size() == vertices_) {  // the model's own embedded image: kept as is
        for (const auto& [image, index] : kept)
          if (image == m.diffuse_image.get()) texture = index;
        const std::vector<std::uint8_t>& bytes = *m.diffuse_image;
        const std::string mime = image_type(bytes);
        if (texture < 0 && mime.empty()) {
          written_.warnings.push_back("material '" + m.name + "': embedded texture not kept (not a PNG or JPEG image)");
        } else if (texture < 0) {
          texture = add_image(bytes, mime);
          kept.emplace_back(m.diffuse_image.get(), texture);
        }
      } else if (!m.diffuse_map.empty() && !options_.texture_root.empty() && mesh_.vertex_uvs.size() == vertices_) {
        for (const auto& [file, index] : embedded)
          if (file == m.diffuse_map) texture = index;
        if (texture < 0) {
          std::string why, mime;
          std::vector<std::uint8_t> bytes;
          if (const auto known = refused.find(m.diffuse_map); known != refused.end()) why = known->second;
          else bytes = texture_bytes(m.diffuse_map, options_.texture_root, options_.references, why, mime);
          if (bytes.empty()) {
            refused.emplace(m.diffuse_map, why);
            written_.warnings.push_back("material '" + m.name + "': texture '" + m.diffuse_map + "' not embedded (" +
                                        why + ")");
          } else {
            texture = add_image(bytes, mime);
            embedded.emplace_back(m.diffuse_map, texture);
          }
        }
      }
      materials.push_back(material_json(m, texture));
    }
    written_.textures = images.size();
  }

  // --- the mesh: one primitive per non-empty submesh, each with its own vertices (the render vertices its triangles
  // use, in order), so that no reader has to split shared vertex buffers ---
  Json mesh_json() {
    std::vector<Submesh> submeshes = mesh_.submeshes;
    if (submeshes.empty()) submeshes.push_back({0, static_cast<std::uint32_t>(mesh_.triangle_count()), -1});
    std::vector<std::uint32_t> local(vertices_, 0);
    Json primitives = Json::array();
    for (const Submesh& s : submeshes)
      if (s.triangle_count > 0) primitives.push_back(primitive(s, local));
    written_.morph_targets = frame_count_;
    if (!sparse_.patch.empty()) {
      const int index_view = b_.view(sparse_.indices.data(), sparse_.indices.size() * sizeof(std::uint32_t), 0);
      const int value_view = b_.view(sparse_.values.data(), sparse_.values.size() * sizeof(float), 0);
      for (const std::size_t a : sparse_.patch) {
        b_.accessors[a]["sparse"]["indices"]["bufferView"] = index_view;
        b_.accessors[a]["sparse"]["values"]["bufferView"] = value_view;
      }
    }
    Json gltf_mesh = {{"primitives", std::move(primitives)}};
    if (!model_.name.empty()) gltf_mesh["name"] = model_.name;
    if (frame_count_ > 0 && !skinned_) gltf_mesh["weights"] = std::vector<float>(frame_count_, 0.0f);
    if (frame_count_ > 0 && skinned_) {  // the model's targets: their default weights, and their names where
      std::vector<float> defaults;       // three.js, Blender and libdeform's importer look for them
      Json names = Json::array();
      for (const MorphTarget& t : model_.morph_targets) defaults.push_back(t.default_weight), names.push_back(t.name);
      gltf_mesh["weights"] = std::move(defaults);
      gltf_mesh["extras"] = {{"targetNames", std::move(names)}};
    }
    return gltf_mesh;
  }

  // One submesh's primitive; `local` (per render vertex, its index in the primitive) is scratch shared by all.
  Json primitive(const Submesh& s, std::vector<std::uint32_t>& local) {
    const std::size_t first = std::size_t(s.first_triangle) * 3, count = std::size_t(s.triangle_count) * 3;
    if (first + count > mesh_.triangles.size())
      throw Error::invalid_argument(path_, "a submesh runs past the triangles");
    std::vector<std::uint8_t> is_used(vertices_, 0);
    for (std::size_t i = first; i < first + count; ++i) {
      if (mesh_.triangles[i] >= vertices_) throw Error::invalid_argument(path_, "a triangle names no render vertex");
      is_used[mesh_.triangles[i]] = 1;
    }
    std::vector<std::uint32_t> used;
    for (std::size_t r = 0; r < vertices_; ++r)
      if (is_used[r]) local[r] = static_cast<std::uint32_t>(used.size()), used.push_back(static_cast<std::uint32_t>(r));
    written_.vertices += used.size();
    std::vector<std::uint32_t> indices(count);
    for (std::size_t i = 0; i < count; ++i) indices[i] = local[mesh_.triangles[first + i]];

    Json attributes = vertex_attributes(used);
    const int iv = b_.view(indices.data(), indices.size() * sizeof(std::uint32_t), element_array_buffer);
    Json primitive = {
        {"attributes", std::move(attributes)},
        {"indices",
         b_.push({{"bufferView", iv}, {"componentType", unsigned_int_type}, {"count", count}, {"type", "SCALAR"}})},
        {"mode", 4}};
    if (s.material >= 0 && std::size_t(s.material) < mesh_.materials.size()) primitive["material"] = s.material;
    if (!skinned_ || !model_.morph_targets.empty()) {  // baked frames (one target per frame), or the model's targets
      Json targets = skinned_ ? model_targets(used) : frame_targets(used);
      frame_count_ = targets.size();
      primitive["targets"] = std::move(targets);
    }
    return primitive;
  }

  // The attributes of the render vertices `used`: POSITION, NORMAL, TEXCOORD_0 and the influence sets.
  Json vertex_attributes(const std::vector<std::uint32_t>& used) {
    const auto gather = [&used](const std::vector<glm::vec3>& all) {
      std::vector<float> out;
      out.reserve(used.size() * 3);
      for (const std::uint32_t r : used) out.insert(out.end(), {all[r].x, all[r].y, all[r].z});
      return out;
    };
    Json attributes;
    attributes["POSITION"] = b_.floats(gather(base_positions_), 3, "VEC3", array_buffer, true);
    attributes["NORMAL"] = b_.floats(gather(base_normals_), 3, "VEC3", array_buffer, false);
    if (mesh_.vertex_uvs.size() == vertices_) {
      std::vector<float> uvs;
      uvs.reserve(used.size() * 2);
      for (const std::uint32_t r : used)
        uvs.insert(uvs.end(), {mesh_.vertex_uvs[r].x, 1.0f - mesh_.vertex_uvs[r].y});  // glTF's v runs down
      attributes["TEXCOORD_0"] = b_.floats(uvs, 2, "VEC2", array_buffer, false);
    }
    for (std::size_t set = 0; set < vertex_joints_.size(); ++set) {
      std::vector<std::uint16_t> joint_data;
      std::vector<float> weight_data;
      joint_data.reserve(used.size() * 4);
      weight_data.reserve(used.size() * 4);
      for (const std::uint32_t r : used) {
        const glm::u16vec4 j = vertex_joints_[set][r];
        const glm::vec4 w = vertex_weights_[set][r];
        joint_data.insert(joint_data.end(), {j[0], j[1], j[2], j[3]});
        weight_data.insert(weight_data.end(), {w[0], w[1], w[2], w[3]});
      }
      const int jv = b_.view(joint_data.data(), joint_data.size() * sizeof(std::uint16_t), array_buffer);
      attributes["JOINTS_" + std::to_string(set)] = b_.push(
          {{"bufferView", jv}, {"componentType", unsigned_short_type}, {"count", used.size()}, {"type", "VEC4"}});
      attributes["WEIGHTS_" + std::to_string(set)] = b_.floats(weight_data, 4, "VEC4", array_buffer, false);
    }
    return attributes;
  }

  // Per frame, the displacement of each render vertex of `used` from the rest shape: of its position, or its normal.
  std::vector<glm::vec3> displacements(std::size_t k, const std::vector<std::uint32_t>& used, bool normals) const {
    const BakedFrames& baked = *options_.baked;
    std::vector<glm::vec3> d(used.size());
    for (std::size_t i = 0; i < used.size(); ++i) {
      const std::uint32_t r = used[i];
      d[i] = normals ? unit_or_z(baked.normals[k][r]) - base_normals_[r]
                     : baked.positions[k][mesh_.vertex_point[r]] - base_positions_[r];
    }
    return d;
  }

  // The baked frames as the morph targets of the render vertices `used`, held sparsely (sparse_vec3).
  Json frame_targets(const std::vector<std::uint32_t>& used) {
    const BakedFrames& baked = *options_.baked;
    Json targets = Json::array();
    for (std::size_t k = 0; k < baked.times.size(); ++k) {
      Json target = {{"POSITION", sparse_vec3(b_, sparse_, displacements(k, used, false), baked.position_tolerance,
                                              true, written_.sparse_values)}};
      if (!baked.normals.empty())
        target["NORMAL"] = sparse_vec3(b_, sparse_, displacements(k, used, true), baked.normal_tolerance, false,
                                       written_.sparse_values);
      targets.push_back(std::move(target));
    }
    return targets;
  }

  // The model's morph targets as the morph targets of the render vertices `used`: each point's bind-space deltas,
  // held sparsely (the points a target leaves alone are not stored). NORMAL targets when any target moves normals.
  Json model_targets(const std::vector<std::uint32_t>& used) {
    const bool normals = std::any_of(model_.morph_targets.begin(), model_.morph_targets.end(),
                                     [](const MorphTarget& t) { return !t.normal_deltas.empty(); });
    std::vector<glm::vec3> per_point(mesh_.point_count()), displacement(used.size());
    Json targets = Json::array();
    for (const MorphTarget& t : model_.morph_targets) {
      Json target;
      for (const bool normal : {false, true}) {
        if (normal && !normals) break;
        const std::vector<glm::vec3>& deltas = normal ? t.normal_deltas : t.position_deltas;
        std::fill(per_point.begin(), per_point.end(), glm::vec3(0.0f));
        for (std::size_t k = 0; k < deltas.size(); ++k) per_point[t.points[k]] = deltas[k];
        for (std::size_t i = 0; i < used.size(); ++i) displacement[i] = per_point[mesh_.vertex_point[used[i]]];
        target[normal ? "NORMAL" : "POSITION"] =
            sparse_vec3(b_, sparse_, displacement, 0.0f, !normal, written_.sparse_values);
      }
      targets.push_back(std::move(target));
    }
    return targets;
  }

  std::string mesh_name() const { return model_.name.empty() ? "mesh" : model_.name; }

  // --- nodes: the bones (node i = bone i) then the mesh; the skin ---
  void add_skin(Json& nodes) {
    for (std::size_t i = 0; i < skeleton_.bone_count(); ++i) {
      const Bone& bone = skeleton_.bone(static_cast<std::int32_t>(i));
      Json node = {{"name", skeleton_.key(static_cast<std::int32_t>(i))}};
      if (bone.bind_translation != glm::vec3(0.0f))
        node["translation"] = {bone.bind_translation.x, bone.bind_translation.y, bone.bind_translation.z};
      if (bone.bind_rotation != glm::vec3(0.0f)) {
        const glm::quat q = glm::normalize(quat_from_euler(bone.bind_rotation));
        node["rotation"] = {q.x, q.y, q.z, q.w};
      }
      if (!bone.children.empty()) node["children"] = bone.children;
      nodes.push_back(std::move(node));
    }
    std::vector<float> inverse_binds;
    inverse_binds.reserve(skeleton_.bone_count() * 16);
    for (glm::mat4 m : skeleton_.inverse_bind_world()) {
      m[0][3] = m[1][3] = m[2][3] = 0.0f, m[3][3] = 1.0f;  // affine: glTF requires the last row (0, 0, 0, 1) exactly
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) inverse_binds.push_back(m[c][r]);
    }
    std::vector<int> joints(skeleton_.bone_count());
    for (std::size_t i = 0; i < joints.size(); ++i) joints[i] = static_cast<int>(i);
    doc_["skins"] = Json::array({{{"joints", joints},
                                  {"skeleton", 0},
                                  {"inverseBindMatrices", b_.floats(inverse_binds, 16, "MAT4", 0, false)}}});
    nodes.push_back({{"name", mesh_name()}, {"mesh", 0}, {"skin", 0}});
    doc_["scenes"] = Json::array({{{"nodes", {0, static_cast<int>(skeleton_.bone_count())}}}});
  }

  // --- animations: a clip's translation and rotation tracks; left out, with a warning, when it has none ---
  void add_clip(const Animation& clip, Json& animations) {
    clip.require_valid(skeleton_.bone_count(), "clip '" + clip.name + "'");
    Json samplers = Json::array(), channels = Json::array();
    const auto add = [&](const auto& track, std::int32_t bone, const char* property, int components, const char* type) {
      if (track.empty()) return;
      if (track.times.front() < 0.0f) {
        written_.warnings.push_back("clip '" + clip.name + "': the " + property + " track of bone '" +
                                    skeleton_.key(bone) + "' has keys before t = 0, which glTF cannot hold: left out");
        return;
      }
      const int input = b_.floats(track.times, 1, "SCALAR", 0, true);
      const int output = b_.floats(track_output(track), components, type, 0, false);
      samplers.push_back(
          {{"input", input}, {"output", output}, {"interpolation", interpolation_name(track.interpolation)}});
      channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", bone}, {"path", property}}}});
    };
    for (const Channel& channel : clip.channels) {
      add(channel.translation, channel.bone, "translation", 3, "VEC3");
      add(channel.rotation, channel.bone, "rotation", 4, "VEC4");
    }
    add_weights_channel(clip, samplers, channels);
    if (channels.empty()) {
      written_.warnings.push_back("clip '" + clip.name +
                                  "' animates no translation, rotation or morph weight: left out");
      return;
    }
    Json animation = {{"channels", std::move(channels)}, {"samplers", std::move(samplers)}};
    if (!clip.name.empty()) animation["name"] = clip.name;
    animations.push_back(std::move(animation));
  }

  // A clip's morph channels as the mesh node's one `weights` channel, which glTF requires to hold every target's
  // weight at each key: the keys are the union of the channels' keys, a target without a channel holds its default.
  // Linear (or step) tracks are exact on that union; a cubic spline, or a mix of kinds, is written as its values at
  // the union's keys, linearly in between, with a warning.
  void add_weights_channel(const Animation& clip, Json& samplers, Json& channels) {
    if (clip.morph_channels.empty()) return;
    std::vector<float> times;
    bool all_step = true, all_linear = true;
    for (const MorphChannel& c : clip.morph_channels) {
      times.insert(times.end(), c.weight.times.begin(), c.weight.times.end());
      all_step = all_step && c.weight.interpolation == Interpolation::step;
      all_linear = all_linear && c.weight.interpolation == Interpolation::linear;
    }
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end()), times.end());
    if (times.empty()) return;
    if (times.front() < 0.0f) {
      written_.warnings.push_back("clip '" + clip.name +
                                  "': its morph weights have keys before t = 0, which glTF "
                                  "cannot hold: left out");
      return;
    }
    if (!all_step && !all_linear)
      written_.warnings.push_back("clip '" + clip.name +
                                  "': its morph weights are written as their values at every "
                                  "key, linear in between (glTF holds one interpolation for all targets)");
    const std::size_t targets = model_.morph_targets.size();
    std::vector<float> weights(times.size() * targets);
    for (std::size_t k = 0; k < times.size(); ++k)
      for (std::size_t t = 0; t < targets; ++t) weights[k * targets + t] = model_.morph_targets[t].default_weight;
    for (const MorphChannel& c : clip.morph_channels)
      for (std::size_t k = 0; k < times.size(); ++k)
        weights[k * targets + std::size_t(c.target)] =
            sample_track(c.weight, times[k], model_.morph_targets[std::size_t(c.target)].default_weight);
    const int input = b_.floats(times, 1, "SCALAR", 0, true);
    const int output = b_.floats(weights, 1, "SCALAR", 0, false);
    samplers.push_back({{"input", input}, {"output", output}, {"interpolation", all_step ? "STEP" : "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1},
                        {"target", {{"node", static_cast<int>(skeleton_.bone_count())}, {"path", "weights"}}}});
  }

  // --- baked frames: the mesh's node alone, and one animation of its morph weights ---
  void add_baked_animation(Json& nodes, Json& animations) {
    nodes.push_back({{"name", mesh_name()}, {"mesh", 0}});
    doc_["scenes"] = Json::array({{{"nodes", {0}}}});
    // Weights: frame k's key is target k at 1, the others 0; LINEAR between keys blends frames k and k + 1.
    const BakedFrames& baked = *options_.baked;
    const std::size_t frames = baked.times.size();
    std::vector<float> weights(frames * frames, 0.0f);
    for (std::size_t k = 0; k < frames; ++k) weights[k * frames + k] = 1.0f;
    const int input = b_.floats(baked.times, 1, "SCALAR", 0, true);
    const int output = b_.floats(weights, 1, "SCALAR", 0, false);
    Json animation = {{"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}},
                      {"samplers", {{{"input", input}, {"output", output}, {"interpolation", "LINEAR"}}}}};
    if (!baked.name.empty()) animation["name"] = baked.name;
    animations.push_back(std::move(animation));
  }

  // --- the files ---

  // Invalid UTF-8 in a name (from a model file) becomes U+FFFD: glTF JSON must be UTF-8.
  static std::string dump(const Json& j) { return j.dump(-1, ' ', false, Json::error_handler_t::replace); }

  // One .glb: the header, the JSON chunk, the BIN chunk; written atomically.
  void write_glb() {
    doc_["buffers"] = Json::array({{{"byteLength", b_.bin.size()}}});
    std::string json = dump(doc_);
    while (json.size() % 4) json += ' ';
    const std::uint64_t total = 12 + 8 + json.size() + 8 + b_.bin.size();
    if (total > std::numeric_limits<std::uint32_t>::max())
      throw Error::invalid_argument(path_, "the file would exceed 4 GiB");
    std::vector<std::uint8_t> glb;
    glb.reserve(total);
    const auto u32 = [&glb](std::uint32_t v) {
      for (int i = 0; i < 4; ++i) glb.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    };
    u32(0x46546C67u), u32(2), u32(static_cast<std::uint32_t>(total));  // "glTF", version 2, length
    u32(static_cast<std::uint32_t>(json.size())), u32(0x4E4F534Au);    // "JSON"
    glb.insert(glb.end(), json.begin(), json.end());
    u32(static_cast<std::uint32_t>(b_.bin.size())), u32(0x004E4942u);  // "BIN\0"
    glb.insert(glb.end(), b_.bin.begin(), b_.bin.end());
    write_file_atomic(path_, glb);
    written_.bytes = glb.size();
  }

  // A .gltf and its .bin beside it (the stem, URI-safe): both files or neither, so that a .gltf that cannot be
  // written (a folder by that name, a full disk) leaves the previous .bin as it was.
  void write_gltf_and_bin() {
    const std::filesystem::path gltf_path = utf8_path::from_utf8(path_);
    const std::string bin_name = uri_safe(utf8_path::to_utf8(gltf_path.stem())) + ".bin";
    written_.bin = utf8_path::to_utf8(gltf_path.parent_path() / bin_name);  // bin_name is ASCII
    doc_["buffers"] = Json::array({{{"byteLength", b_.bin.size()}, {"uri", bin_name}}});
    const std::string json = dump(doc_);
    FileTransaction files;
    files.stage(written_.bin, b_.bin);
    files.stage(path_, json);
    files.commit();
    written_.bytes = b_.bin.size() + json.size();
  }
};

}  // namespace

GltfWritten write_gltf(const std::string& path, const Model& model, const GltfExportOptions& options) {
  const bool binary = check_export(path, model, options);
  const glm::quat turn = turn_to_y_up(options.up);
  if (turn == glm::quat(1.0f, 0.0f, 0.0f, 0.0f)) return GltfExport(path, model, options).write(binary);
  const TurnedExport turned = turned_export(model, options, turn);
  GltfExportOptions turned_options = options;
  turned_options.clips = turned.clips;
  if (options.baked) turned_options.baked = &turned.baked;
  return GltfExport(path, turned.model, turned_options).write(binary);
}

}  // namespace deform
