// glTF 2.0 reader on tinygltf (import.hpp, docs/import.md). tinygltf parses the JSON and decodes the buffers; every
// index and byte range it hands over is checked here before it is used, because tinygltf checks few of them.
//
// tinygltf is compiled here, inside a namespace of our own, rather than linked from Debian's libtinygltf: that
// library's Model does not match its header's (freeing one crashes), this keeps stb_image (image decoding) and
// tinygltf's own file access out of the importer, and it cannot clash with another tinygltf in the same program.
// The standard headers tinygltf includes are included first, so that it sees them already defined.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
#define TINYGLTF_NO_INCLUDE_JSON
namespace deform_gltf_import {
#include <tiny_gltf.h>
}  // namespace deform_gltf_import
namespace tinygltf = deform_gltf_import::tinygltf;

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <unordered_map>

#include "deform/io/atomic_file.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "import_common.hpp"
#include "scene_assembly.hpp"
#include "utf8_path.hpp"
#include "finite.hpp"
namespace deform::import_detail {
namespace {

namespace fs = std::filesystem;

// Elements an accessor may hold: its bytes must lie in its buffer, so only a sparse accessor without a buffer view
// (all zeros plus a few substitutions) could ask for more; this caps what it makes us allocate.
constexpr std::size_t max_bufferless_elements = std::size_t{1} << 26;
constexpr int max_node_depth = 10000;

// Images are not decoded here: a file's image is referenced by its path, and an embedded one (a data: URI or a
// buffer view) is kept as its encoded bytes in `user` (an EmbeddedImages), for Material::diffuse_image.
using EmbeddedImages = std::map<int, std::vector<std::uint8_t>>;
bool keep_image(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                const unsigned char* bytes, int size, void* user) {
  if (image != nullptr && user != nullptr && bytes != nullptr && size > 0 &&
      (image->uri.empty() || image->uri.rfind("data:", 0) == 0))
    (*static_cast<EmbeddedImages*>(user))[index].assign(bytes, bytes + size);
  return true;
}

// The image formats an embedded texture may have: glTF's core allows PNG and JPEG (others come by extensions).
bool is_png_or_jpeg(const std::vector<std::uint8_t>& bytes) {
  static constexpr std::uint8_t png[] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  static constexpr std::uint8_t jpeg[] = {0xFF, 0xD8, 0xFF};
  return (bytes.size() >= sizeof png && std::equal(std::begin(png), std::end(png), bytes.begin())) ||
         (bytes.size() >= sizeof jpeg && std::equal(std::begin(jpeg), std::end(jpeg), bytes.begin()));
}

// tinygltf reads the files a .gltf names (buffers; images are never read, TINYGLTF_NO_EXTERNAL_IMAGE) through
// these. Only the files approved beforehand are read: `approved` maps the path tinygltf asks for (its folder joined
// with its decoding of the URI) to the canonical path resolve_referenced_file returned for that buffer. Anything
// else, such as tinygltf's second try in the current folder, is refused unread. Regular files only (not /dev/zero or
// a FIFO), at most 1 GiB each; nothing is ever written.
struct ApprovedFiles {
  std::map<std::string, std::string> approved;  // path tinygltf asks for -> canonical path to read
};
const std::string* approved_path(const std::string& path, void* user) {
  const auto* files = static_cast<const ApprovedFiles*>(user);
  if (files == nullptr) return nullptr;
  const auto found = files->approved.find(path);
  return found == files->approved.end() ? nullptr : &found->second;
}
bool file_exists(const std::string& path, void* user) {
  const std::string* real = approved_path(path, user);
  std::error_code error;
  return real != nullptr && fs::is_regular_file(utf8_path::from_utf8(*real), error);
}
std::string expand_path(const std::string& path, void*) { return path; }
bool read_whole_file(std::vector<unsigned char>* out, std::string* error, const std::string& path, void* user) {
  try {
    const std::string* real = approved_path(path, user);
    if (real == nullptr || !file_exists(path, user)) throw Error::in_file(path, "", "not a regular file");
    const std::vector<std::uint8_t> bytes = read_file_bytes(*real);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const std::exception& e) {
    if (error != nullptr) *error += e.what();
    return false;
  }
}

// Confines every external buffer the file names before tinygltf reads any (resolve_referenced_file): a buffer
// outside the model's folder and the policy's folders throws here, naming "buffers[i].uri", unread. `document` is
// the parsed glTF JSON (a .gltf file, or a .glb's JSON chunk); malformed JSON (discarded) approves nothing and is left
// to tinygltf to report. Images are confined after parsing, as tinygltf never reads them.
ApprovedFiles approve_buffers(const std::string& path, const std::string& base, const nlohmann::json& document,
                              const ReferencePolicy& policy) {
  ApprovedFiles files;
  if (!document.is_object() || !document.contains("buffers") || !document["buffers"].is_array()) return files;
  const nlohmann::json& buffers = document["buffers"];
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    if (!buffers[i].is_object() || !buffers[i].contains("uri") || !buffers[i]["uri"].is_string()) continue;
    const std::string& uri = buffers[i]["uri"].get_ref<const std::string&>();
    if (tinygltf::IsDataURI(uri)) continue;
    const std::string real =
        resolve_referenced_file(path, uri, "buffers[" + std::to_string(i) + "].uri", policy, ReferenceSyntax::uri);
    files.approved[tinygltf::JoinPath(base, tinygltf::dlib::urldecode(uri))] = real;
  }
  return files;
}

// Whether a parsed document is glTF 1.0: its asset.version says 1.x, or (1.0 makes `asset` optional) it has no
// version and keeps its meshes in an object by id, where 2.0 has an array.
bool is_gltf1(const nlohmann::json& document) {
  if (!document.is_object()) return false;
  const auto asset = document.find("asset");
  if (asset != document.end() && asset->is_object()) {
    const auto version = asset->find("version");
    if (version != asset->end() && version->is_string())
      return version->get_ref<const std::string&>().rfind("1", 0) == 0;
  }
  const auto meshes = document.find("meshes");
  return meshes != document.end() && meshes->is_object();
}

bool refuse_write(std::string* error, const std::string&, const std::vector<unsigned char>&, void*) {
  if (error != nullptr) *error += "the importer writes no file";
  return false;
}

// Whether a double converts to a finite float (a cast of a larger one is undefined behaviour).
bool fits_float(double v) { return std::fabs(v) <= 3.0e38; }  // false for NaN too
template <int N>
bool fits_float(const glm::vec<N, double>& v) {
  for (int i = 0; i < N; ++i)
    if (!fits_float(v[i])) return false;
  return true;
}
bool fits_float(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    if (!fits_float(m[c])) return false;
  return true;
}

// Accessor values beyond this magnitude are refused: every product the reader forms of two of them stays a double.
constexpr double max_accessor_value = 1e30;

struct Reader {
  const tinygltf::Model& gltf;
  const std::string& path;

  [[noreturn]] void fail(const std::string& element, const std::string& message) const {
    throw Error::in_file(path, element, message);
  }
  // `v` as floats, or an error naming `element` when it does not fit.
  glm::vec3 narrow(const glm::dvec3& v, const std::string& element) const {
    if (!fits_float(v)) fail(element, "a value is not finite or too large for a float");
    return glm::vec3(v);
  }
  glm::mat4 narrow(const glm::dmat4& m, const std::string& element) const {
    if (!fits_float(m)) fail(element, "a transform is not finite or too large for a float");
    return glm::mat4(m);
  }

  static std::size_t component_size(int type) {
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
      case TINYGLTF_COMPONENT_TYPE_SHORT:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
      default: return 0;
    }
  }
  static std::size_t component_count(int type) {
    switch (type) {
      case TINYGLTF_TYPE_SCALAR: return 1;
      case TINYGLTF_TYPE_VEC2: return 2;
      case TINYGLTF_TYPE_VEC3: return 3;
      case TINYGLTF_TYPE_VEC4: return 4;
      case TINYGLTF_TYPE_MAT4: return 16;
      default: return 0;  // MAT2 and MAT3 (column padding) are used by nothing read here
    }
  }

  // One component at `p` as a number: normalised integers map to [0, 1] or [-1, 1] (glTF 2.0 §3.11), others as is.
  static double component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        std::int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return normalized ? v / 4294967295.0 : v;
      }
      default: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
    }
  }

  // The bytes of buffer view `index` after checking that they lie inside their buffer.
  std::pair<const unsigned char*, std::size_t> view_bytes(int index, const std::string& element) const {
    if (index < 0 || static_cast<std::size_t>(index) >= gltf.bufferViews.size())
      fail(element, "bufferView " + std::to_string(index) + " does not exist");
    const tinygltf::BufferView& view = gltf.bufferViews[static_cast<std::size_t>(index)];
    const std::string view_element = "bufferViews[" + std::to_string(index) + "]";
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= gltf.buffers.size())
      fail(view_element, "buffer " + std::to_string(view.buffer) + " does not exist");
    const auto& data = gltf.buffers[static_cast<std::size_t>(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail(view_element, "bytes " + std::to_string(view.byteOffset) + " + " + std::to_string(view.byteLength) +
                             " lie outside buffer " + std::to_string(view.buffer) + " (" + std::to_string(data.size()) +
                             " bytes)");
    return {data.data() + view.byteOffset, view.byteLength};
  }

  // Accessor `index` as count × components numbers, sparse substitutions applied. `want` lists the accepted
  // component counts (element types); every byte read is checked against its buffer first.
  std::vector<double> read(int index, std::initializer_list<std::size_t> want, const std::string& use,
                           std::size_t* components_out = nullptr) const {
    if (index < 0 || static_cast<std::size_t>(index) >= gltf.accessors.size())
      fail(use, "accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = gltf.accessors[static_cast<std::size_t>(index)];
    const std::string element = "accessors[" + std::to_string(index) + "] (" + use + ")";
    const std::size_t components = component_count(a.type);
    const std::size_t size = component_size(a.componentType);
    if (components == 0 || std::find(want.begin(), want.end(), components) == want.end())
      fail(element, "element type " + std::to_string(a.type) + " is not what " + use + " needs");
    if (size == 0) fail(element, "componentType " + std::to_string(a.componentType) + " is not a glTF type");
    if (components_out != nullptr) *components_out = components;
    const std::size_t element_bytes = components * size;
    std::vector<double> out;
    if (a.bufferView >= 0) {
      const auto [bytes, length] = view_bytes(a.bufferView, element);
      const tinygltf::BufferView& view = gltf.bufferViews[static_cast<std::size_t>(a.bufferView)];
      const std::size_t stride = view.byteStride == 0 ? element_bytes : view.byteStride;
      if (stride < element_bytes) fail(element, "byteStride " + std::to_string(stride) + " is shorter than an element");
      if (a.count > 0) {
        const bool fits = a.byteOffset <= length && (a.count - 1) <= (length - a.byteOffset) / stride &&
                          (a.count - 1) * stride + element_bytes <= length - a.byteOffset;
        if (!fits)
          fail(element, std::to_string(a.count) + " elements from byte " + std::to_string(a.byteOffset) +
                            " run past the end of bufferView " + std::to_string(a.bufferView) + " (" +
                            std::to_string(length) + " bytes)");
      }
      out.resize(a.count * components);
      for (std::size_t i = 0; i < a.count; ++i) {
        const unsigned char* p = bytes + a.byteOffset + i * stride;
        for (std::size_t c = 0; c < components; ++c)
          out[i * components + c] = component(p + c * size, a.componentType, a.normalized);
      }
    } else {
      if (a.count > max_bufferless_elements)
        fail(element, std::to_string(a.count) + " elements without a bufferView (at most " +
                          std::to_string(max_bufferless_elements) + ")");
      out.assign(a.count * components, 0.0);
    }
    if (a.sparse.isSparse) {
      const std::string sparse = element + ".sparse";
      if (a.sparse.count < 0 || static_cast<std::size_t>(a.sparse.count) > a.count)
        fail(sparse,
             "count " + std::to_string(a.sparse.count) + " is not within the accessor's " + std::to_string(a.count));
      const auto n = static_cast<std::size_t>(a.sparse.count);
      const int index_type = a.sparse.indices.componentType;
      const std::size_t index_size = component_size(index_type);
      if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(sparse + ".indices", "componentType " + std::to_string(index_type) + " is not an unsigned integer");
      const auto [ibytes, ilength] = view_bytes(a.sparse.indices.bufferView, sparse + ".indices");
      const auto [vbytes, vlength] = view_bytes(a.sparse.values.bufferView, sparse + ".values");
      const auto ioffset = static_cast<std::size_t>(std::max(a.sparse.indices.byteOffset, 0));
      const auto voffset = static_cast<std::size_t>(std::max(a.sparse.values.byteOffset, 0));
      if (ioffset > ilength || n > (ilength - ioffset) / index_size)
        fail(sparse + ".indices", std::to_string(n) + " indices run past the end of their bufferView");
      if (voffset > vlength || n > (vlength - voffset) / element_bytes)
        fail(sparse + ".values", std::to_string(n) + " values run past the end of their bufferView");
      for (std::size_t k = 0; k < n; ++k) {
        const auto target = static_cast<std::size_t>(component(ibytes + ioffset + k * index_size, index_type, false));
        if (target >= a.count)
          fail(sparse + ".indices",
               "index " + std::to_string(target) + " is not below count " + std::to_string(a.count));
        for (std::size_t c = 0; c < components; ++c)
          out[target * components + c] =
              component(vbytes + voffset + k * element_bytes + c * size, a.componentType, a.normalized);
      }
    }
    for (double v : out)
      if (!(std::fabs(v) <= max_accessor_value)) fail(element, "holds a value that is not finite or beyond ±1e30");
    return out;
  }
};

glm::dmat4 to_dmat4(const std::vector<double>& m) {
  glm::dmat4 out(1.0);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[c][r] = m[static_cast<std::size_t>(c * 4 + r)];
  return out;
}

struct NodeInfo {
  std::int32_t parent = -1;
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
  glm::dvec3 scale{1.0};
  glm::dmat4 local{1.0};
  glm::dmat4 global{1.0};
  bool in_scene = false;
};

glm::dmat4 trs(glm::dvec3 t, glm::dquat r, glm::dvec3 s) {
  return glm::translate(glm::dmat4(1.0), t) * glm::mat4_cast(r) * glm::scale(glm::dmat4(1.0), s);
}

// A mesh placed by a node: the node, its mesh and its skin (-1: rigid on its node).
struct Instance {
  std::int32_t node;
  std::int32_t mesh;
  std::int32_t skin;
};

// Skins: joints by node index; bind world = inverse(inverseBindMatrices[j]) (identity when none are given).
struct SkinInfo {
  std::vector<std::int32_t> joints;
  std::vector<glm::dmat4> bind;
};

// One primitive's vertex attributes as the file holds them, every accessor checked against POSITION's count.
struct PrimitiveData {
  std::vector<double> positions, normals, uvs;
  std::size_t count = 0;
  std::vector<std::vector<double>> joint_sets, weight_sets;  // every JOINTS_n / WEIGHTS_n pair
  // Each target's POSITION and NORMAL displacements (sparse accessors applied by read), empty when absent.
  std::vector<std::vector<double>> target_positions, target_normals;
};

// The transforms a mesh instance's vertices and target deltas go through into the bind space.
struct InstanceFrame {
  glm::dmat4 to_world;
  glm::dmat3 normal_matrix;
  glm::dmat3 delta_matrix;
  std::uint16_t rigid_bone;
  std::size_t first_target;
};

// One clip as its channels are read.
struct ClipState {
  Animation clip;
  std::vector<std::int32_t> channel_of_bone;
  std::size_t dropped = 0, scaled_bones = 0;
  float duration = 0.0f;
};

// The glTF reader: each step reads one part of the file into the ImportedModel, in the order below (run()).
class GltfImport {
 public:
  GltfImport(const std::string& path, const ImportOptions& options) : path_(path), options_(options) {}
  ImportedModel run();

 private:
  void load();
  void confine_images();
  void read_nodes();
  void order_scene();
  void find_instances();
  void read_skins();
  void choose_bones();
  void bind_bones();
  void read_materials();
  void diffuse_texture(Material& material, int texture,
                       std::map<int, std::shared_ptr<const std::vector<std::uint8_t>>>& embedded_shared);
  void read_meshes();
  void add_morph_targets(const Instance& instance, InstanceFrame& frame);
  PrimitiveData read_attributes(const Instance& instance, const tinygltf::Primitive& primitive,
                                const std::string& element, std::size_t target_count) const;
  void add_vertices(const Instance& instance, const tinygltf::Primitive& primitive, const std::string& element,
                    const PrimitiveData& data, const InstanceFrame& frame);
  void add_triangles(const Instance& instance, const tinygltf::Primitive& primitive, const std::string& element,
                     int mode, std::size_t first_vertex, std::size_t count);
  void read_clips();
  void read_clip(std::size_t a, const RestLocals& rest, const std::vector<glm::dvec3>& translation_scale,
                 std::vector<std::string>& clip_names);
  void read_weights_channel(ClipState& state, const tinygltf::AnimationChannel& channel,
                            const tinygltf::AnimationSampler& sampler, const std::string& sampler_element,
                            Interpolation interpolation, const std::vector<double>& times);
  void read_bone_channel(ClipState& state, const tinygltf::AnimationChannel& channel,
                         const tinygltf::AnimationSampler& sampler, const std::string& sampler_element,
                         Interpolation interpolation, const std::vector<double>& times,
                         const std::vector<glm::dvec3>& translation_scale);

  const std::string& path_;
  const ImportOptions& options_;
  tinygltf::Model gltf_;
  const Reader reader_{gltf_, path_};
  EmbeddedImages embedded_images_;
  std::string base_;
  std::vector<std::string> image_paths_;  // canonical path of each image the file names by URI
  ImportedModel result_;
  std::vector<std::string>& warnings_ = result_.warnings;
  std::vector<NodeInfo> nodes_;
  std::vector<std::int32_t> roots_, order_;
  std::vector<Instance> instances_;
  bool rigged_ = false;
  std::vector<SkinInfo> skins_;
  std::vector<std::int32_t> bone_of_node_, node_of_bone_;
  std::vector<Bone> bones_;
  std::vector<glm::dmat4> bind_world_;
  // Per node holding a morphed mesh: its first target in model.morph_targets and its target count.
  std::vector<std::pair<std::size_t, std::size_t>> targets_of_node_;
  PointMerger points_{result_.model.mesh.positions, result_.model.weights};
  std::vector<glm::vec3> position_deltas_, normal_deltas_;  // one vertex's, per target of its primitive
  std::size_t unweighted_ = 0, skipped_primitives_ = 0;
  bool any_uvs_ = false;
};

ImportedModel GltfImport::run() {
  load();
  confine_images();
  result_.model.name = utf8_path::to_utf8(utf8_path::from_utf8(path_).stem());
  for (const std::string& required : gltf_.extensionsRequired) {
    const bool harmless = required == "KHR_mesh_quantization" || required == "KHR_texture_transform" ||
                          required.rfind("KHR_materials_", 0) == 0 || required == "KHR_texture_basisu" ||
                          required == "KHR_lights_punctual";
    if (!harmless) reader_.fail("extensionsRequired", required + " is not supported");
  }
  read_nodes();
  order_scene();
  find_instances();
  read_skins();
  choose_bones();
  bind_bones();
  read_materials();
  read_meshes();
  if (rigged_) read_clips();
  return std::move(result_);
}

// --- parse ---
void GltfImport::load() {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path_);
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image, &embedded_images_);
  ApprovedFiles approved;
  loader.SetFsCallbacks({file_exists, expand_path, read_whole_file, refuse_write, &approved});
  std::string error, warning;
  base_ = utf8_path::to_utf8(utf8_path::from_utf8(path_).parent_path());
  bool loaded = false;
  const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  const auto text = [&](std::size_t from, std::size_t length) {
    return std::string_view(reinterpret_cast<const char*>(bytes.data()) + from, length);
  };
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw Error::in_file(path_, "", "larger than 4 GiB");
  if (binary) {
    // The GLB header's lengths are checked here: tinygltf adds them in 32 bits.
    std::uint32_t header[5] = {};
    if (bytes.size() < 20) throw Error::in_file(path_, "GLB header", "shorter than 20 bytes");
    std::memcpy(header, bytes.data(), 20);
    if (header[1] != 2)
      throw Error::in_file(
          path_, "GLB header",
          "version " + std::to_string(header[1]) + ", not 2" +
              (header[1] == 1 ? " (glTF 1.0 is not read, only 2.0: convert the file to glTF 2.0)" : ""));
    if (header[2] > bytes.size() || header[2] < 20)
      throw Error::in_file(
          path_, "GLB header",
          "length " + std::to_string(header[2]) + " is not the file's " + std::to_string(bytes.size()) + " bytes");
    if (header[4] != 0x4E4F534Au || std::uint64_t{header[3]} + 20 > header[2])
      throw Error::in_file(
          path_, "GLB header",
          "the first chunk is not JSON within the file (" + std::to_string(header[3]) + " bytes claimed)");
    const std::string_view json = text(20, header[3]);
    approved = approve_buffers(path_, base_, nlohmann::json::parse(json.begin(), json.end(), nullptr, false),
                               options_.references);
    loaded = loader.LoadBinaryFromMemory(&gltf_, &error, &warning, bytes.data(),
                                         static_cast<unsigned int>(bytes.size()), base_);
  } else {
    const std::string_view json = text(0, bytes.size());
    const nlohmann::json document = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
    // tinygltf reads 2.0 only: a 1.0 file came through it as "no mesh" or "no asset". (Assimp reads 1.0's meshes,
    // not its skins, and its reader is not hardened against hostile files as this one is: not a route to take.)
    if (is_gltf1(document))
      throw Error::in_file(path_, "asset.version", "glTF 1.0 is not read, only 2.0: convert the file to glTF 2.0");
    approved = approve_buffers(path_, base_, document, options_.references);
    loaded = loader.LoadASCIIFromString(&gltf_, &error, &warning, reinterpret_cast<const char*>(bytes.data()),
                                        static_cast<unsigned int>(bytes.size()), base_);
  }
  if (!loaded) {
    while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
    std::replace(error.begin(), error.end(), '\n', ' ');
    throw Error::in_file(path_, "",
                         "not a valid glTF 2.0 file: " + (error.empty() ? std::string("unreadable") : error));
  }
}

// Every image the file names, used or not, is confined as its buffers are (tinygltf read none of them).
void GltfImport::confine_images() {
  image_paths_.resize(gltf_.images.size());
  for (std::size_t i = 0; i < gltf_.images.size(); ++i) {
    const std::string& uri = gltf_.images[i].uri;
    if (uri.empty() || tinygltf::IsDataURI(uri)) continue;
    image_paths_[i] = resolve_referenced_file(path_, uri, "images[" + std::to_string(i) + "].uri", options_.references,
                                              ReferenceSyntax::uri);
  }
}

// --- nodes: a forest (one parent each, no cycles), local and world transforms in double precision ---
void GltfImport::read_nodes() {
  const std::size_t node_count = gltf_.nodes.size();
  nodes_.resize(node_count);
  for (std::size_t i = 0; i < node_count; ++i) {
    const tinygltf::Node& n = gltf_.nodes[i];
    const std::string element = "nodes[" + std::to_string(i) + "]";
    for (int child : n.children) {
      if (child < 0 || static_cast<std::size_t>(child) >= node_count)
        reader_.fail(element + ".children", "node " + std::to_string(child) + " does not exist");
      NodeInfo& c = nodes_[static_cast<std::size_t>(child)];
      if (c.parent >= 0 || static_cast<std::size_t>(child) == i)
        reader_.fail(element + ".children", "node " + std::to_string(child) + " has more than one parent");
      c.parent = static_cast<std::int32_t>(i);
    }
    NodeInfo& info = nodes_[i];
    if (n.matrix.size() == 16) {
      info.local = to_dmat4(n.matrix);
      const Split s = split(reader_.narrow(info.local, element + ".matrix"));
      info.translation = glm::dvec3(info.local[3]);
      info.rotation = glm::dquat(s.rotation);
      info.scale = glm::dvec3(s.axis_scale);
    } else {
      if (n.translation.size() == 3) info.translation = {n.translation[0], n.translation[1], n.translation[2]};
      if (n.rotation.size() == 4)
        info.rotation = glm::normalize(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]));
      if (n.scale.size() == 3) info.scale = {n.scale[0], n.scale[1], n.scale[2]};
      info.local = trs(info.translation, info.rotation, info.scale);
    }
    if (!finite(reader_.narrow(info.local, element))) reader_.fail(element, "transform is not finite");
  }
}

// Roots of the scene shown (the default scene, else the first, else every node without a parent), then the scene in
// pre-order (iterative: node chains may be deep) with world transforms; a node reached twice means a cycle.
void GltfImport::order_scene() {
  const std::size_t node_count = nodes_.size();
  if (!gltf_.scenes.empty()) {
    const int scene = gltf_.defaultScene >= 0 ? gltf_.defaultScene : 0;
    if (static_cast<std::size_t>(scene) >= gltf_.scenes.size())
      reader_.fail("scene", "scene " + std::to_string(scene) + " does not exist");
    for (int n : gltf_.scenes[static_cast<std::size_t>(scene)].nodes) {
      if (n < 0 || static_cast<std::size_t>(n) >= node_count)
        reader_.fail("scenes[" + std::to_string(scene) + "].nodes", "node " + std::to_string(n) + " does not exist");
      if (nodes_[static_cast<std::size_t>(n)].parent >= 0)
        reader_.fail("scenes[" + std::to_string(scene) + "].nodes", "node " + std::to_string(n) + " is not a root");
      roots_.push_back(n);
    }
  } else {
    for (std::size_t i = 0; i < node_count; ++i)
      if (nodes_[i].parent < 0) roots_.push_back(static_cast<std::int32_t>(i));
  }
  std::vector<std::pair<std::int32_t, int>> stack;
  for (auto r = roots_.rbegin(); r != roots_.rend(); ++r) stack.emplace_back(*r, 0);
  while (!stack.empty()) {
    const auto [n, depth] = stack.back();
    stack.pop_back();
    NodeInfo& info = nodes_[static_cast<std::size_t>(n)];
    if (info.in_scene) reader_.fail("nodes[" + std::to_string(n) + "]", "is part of a cycle");
    if (depth > max_node_depth)
      reader_.fail("nodes[" + std::to_string(n) + "]", "node tree deeper than " + std::to_string(max_node_depth));
    info.in_scene = true;
    info.global = info.parent < 0 ? info.local : nodes_[static_cast<std::size_t>(info.parent)].global * info.local;
    reader_.narrow(info.global, "nodes[" + std::to_string(n) + "] (world transform)");
    order_.push_back(n);
    const auto& children = gltf_.nodes[static_cast<std::size_t>(n)].children;
    for (auto c = children.rbegin(); c != children.rend(); ++c) stack.emplace_back(*c, depth + 1);
  }
}

// --- mesh instances, whether the model is rigged, and the listing of the file's skins (ImportedModel::skins):
// every skin, with the meshes instanced under it (an unnamed mesh by its JSON path) ---
void GltfImport::find_instances() {
  for (std::int32_t n : order_) {
    const tinygltf::Node& node = gltf_.nodes[static_cast<std::size_t>(n)];
    if (node.mesh < 0) continue;
    const std::string element = "nodes[" + std::to_string(n) + "]";
    if (static_cast<std::size_t>(node.mesh) >= gltf_.meshes.size())
      reader_.fail(element + ".mesh", "mesh " + std::to_string(node.mesh) + " does not exist");
    if (node.skin >= 0 && static_cast<std::size_t>(node.skin) >= gltf_.skins.size())
      reader_.fail(element + ".skin", "skin " + std::to_string(node.skin) + " does not exist");
    instances_.push_back({n, node.mesh, node.skin});
  }
  if (instances_.empty()) reader_.fail("", "the scene has no mesh");
  bool any_animation = false;
  for (const tinygltf::Animation& animation : gltf_.animations)
    for (const tinygltf::AnimationChannel& channel : animation.channels)
      any_animation =
          any_animation || (channel.target_node >= 0 && static_cast<std::size_t>(channel.target_node) < nodes_.size() &&
                            nodes_[static_cast<std::size_t>(channel.target_node)].in_scene);
  const bool any_skin =
      std::any_of(instances_.begin(), instances_.end(), [](const Instance& i) { return i.skin >= 0; });
  rigged_ = any_skin || any_animation;
  result_.rigged = rigged_;
  for (std::size_t s = 0; s < gltf_.skins.size(); ++s) {
    ImportedSkin listed;
    listed.name = gltf_.skins[s].name;
    listed.joints = gltf_.skins[s].joints.size();
    for (const Instance& i : instances_) {
      if (i.skin != static_cast<std::int32_t>(s)) continue;
      const std::string& name = gltf_.meshes[static_cast<std::size_t>(i.mesh)].name;
      std::string mesh = name.empty() ? "meshes[" + std::to_string(i.mesh) + "]" : name;
      if (std::find(listed.meshes.begin(), listed.meshes.end(), mesh) == listed.meshes.end())
        listed.meshes.push_back(std::move(mesh));
    }
    result_.skins.push_back(std::move(listed));
  }
}

// The skins the instances use: their joints (nodes of the scene, each once) and bind world transforms.
void GltfImport::read_skins() {
  skins_.resize(gltf_.skins.size());
  std::vector<bool> skin_used(gltf_.skins.size(), false);
  for (const Instance& i : instances_)
    if (i.skin >= 0) skin_used[static_cast<std::size_t>(i.skin)] = true;
  for (std::size_t s = 0; s < gltf_.skins.size(); ++s) {
    if (!skin_used[s]) continue;
    const tinygltf::Skin& skin = gltf_.skins[s];
    const std::string element = "skins[" + std::to_string(s) + "]";
    if (skin.joints.empty()) reader_.fail(element + ".joints", "is empty");
    std::set<std::int32_t> seen;
    for (int j : skin.joints) {
      if (j < 0 || static_cast<std::size_t>(j) >= nodes_.size())
        reader_.fail(element + ".joints", "node " + std::to_string(j) + " does not exist");
      if (!nodes_[static_cast<std::size_t>(j)].in_scene)
        reader_.fail(element + ".joints", "node " + std::to_string(j) + " is not in the scene");
      if (!seen.insert(j).second) reader_.fail(element + ".joints", "node " + std::to_string(j) + " is listed twice");
      skins_[s].joints.push_back(j);
    }
    skins_[s].bind.assign(skin.joints.size(), glm::dmat4(1.0));
    if (skin.inverseBindMatrices >= 0) {
      const std::vector<double> m = reader_.read(skin.inverseBindMatrices, {16}, element + ".inverseBindMatrices");
      if (m.size() < 16 * skin.joints.size())
        reader_.fail(element + ".inverseBindMatrices", "fewer matrices than joints");
      for (std::size_t j = 0; j < skin.joints.size(); ++j) {
        glm::dmat4 ibm;
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) ibm[c][r] = m[16 * j + static_cast<std::size_t>(c * 4 + r)];
        skins_[s].bind[j] = glm::inverse(ibm);
        if (!fits_float(skins_[s].bind[j]) || std::fabs(glm::determinant(ibm)) < 1e-30)
          reader_.fail(element + ".inverseBindMatrices", "matrix " + std::to_string(j) + " is singular or not finite");
      }
    }
  }
}

// --- bones: the nodes skinning needs (joints of the used skins, nodes of rigid meshes) and all their ancestors,
// in pre-order; several top-level nodes hang under an added bone "root" at the origin ---
void GltfImport::choose_bones() {
  const std::size_t node_count = nodes_.size();
  bone_of_node_.assign(node_count, -1);
  std::size_t shortened = 0;
  if (rigged_) {
    std::vector<bool> needed(node_count, false);
    for (const Instance& i : instances_)
      if (i.skin < 0) needed[static_cast<std::size_t>(i.node)] = true;
    for (std::size_t s = 0; s < skins_.size(); ++s)
      for (std::int32_t j : skins_[s].joints) needed[static_cast<std::size_t>(j)] = true;
    std::vector<std::int32_t> node_parents(node_count);
    for (std::size_t i = 0; i < node_count; ++i) node_parents[i] = nodes_[i].parent;
    const std::vector<bool> in_skeleton = skeleton_nodes(node_parents, needed);
    std::vector<std::string> names;
    std::vector<std::int32_t> parents;
    std::vector<std::int32_t> index_of_node(node_count, -1);
    for (std::int32_t n : order_) {
      if (!in_skeleton[static_cast<std::size_t>(n)]) continue;
      const std::string& raw = gltf_.nodes[static_cast<std::size_t>(n)].name;
      const std::int32_t parent = nodes_[static_cast<std::size_t>(n)].parent;
      index_of_node[static_cast<std::size_t>(n)] = static_cast<std::int32_t>(names.size());
      names.push_back(raw.empty() ? "node" + std::to_string(n) : raw);
      parents.push_back(parent >= 0 ? index_of_node[static_cast<std::size_t>(parent)] : -1);
    }
    ForestBones forest = bones_of_forest(names, parents, shortened);
    bones_ = std::move(forest.bones);
    if (forest.first == 1) node_of_bone_.push_back(-1);
    for (std::int32_t n : order_) {
      if (!in_skeleton[static_cast<std::size_t>(n)]) continue;
      bone_of_node_[static_cast<std::size_t>(n)] = static_cast<std::int32_t>(node_of_bone_.size());
      node_of_bone_.push_back(n);
    }
  } else {
    bones_ = bones_of_forest({}, {}, shortened).bones;  // static scene: one bone at the origin holds every point
    node_of_bone_.push_back(-1);
  }
  require_bone_count(bones_.size(), path_);
  warn_shortened_names(shortened, warnings_);
  std::map<std::string, std::size_t> uses;
  for (const Bone& b : bones_) ++uses[b.name];
  std::size_t repeated = 0;
  for (const auto& [name, count] : uses) repeated += count > 1 ? count : 0;
  if (repeated > 0)
    warnings_.push_back(std::to_string(repeated) +
                        " bones share their name with another (skins bind by node, so this is harmless; "
                        "look such bones up by '#id')");
}

// Bind world transforms (a joint's from its skin, every other bone's from the node tree), then the skeleton of
// their rigid parts. A bone's local translation in the skeleton is its node translation scaled by the parent's
// world axis scales (exact while the parent's scale is not animated and has no shear); its rotation is the node's.
void GltfImport::bind_bones() {
  bind_world_.assign(bones_.size(), glm::dmat4(1.0));
  std::vector<bool> has_bind(bones_.size(), false);
  std::size_t conflicting_binds = 0;
  for (std::size_t s = 0; s < skins_.size(); ++s)
    for (std::size_t j = 0; j < skins_[s].joints.size(); ++j) {
      const auto b = static_cast<std::size_t>(bone_of_node_[static_cast<std::size_t>(skins_[s].joints[j])]);
      if (!has_bind[b]) {
        bind_world_[b] = skins_[s].bind[j];
        has_bind[b] = true;
      } else {
        double difference = 0.0;
        for (int c = 0; c < 4; ++c)
          difference = std::max(difference, glm::length(skins_[s].bind[j][c] - bind_world_[b][c]));
        if (difference > 1e-5 * std::max(1.0, glm::length(glm::dvec3(bind_world_[b][3])))) ++conflicting_binds;
      }
    }
  for (std::size_t b = 0; b < bones_.size(); ++b)
    if (!has_bind[b] && node_of_bone_[b] >= 0)
      bind_world_[b] = nodes_[static_cast<std::size_t>(node_of_bone_[b])].global;
  if (conflicting_binds > 0)
    warnings_.push_back(std::to_string(conflicting_binds) +
                        " joints are bound differently by two skins: the first skin's bind is used, the other skin's "
                        "vertices on them are off by the difference");
  std::vector<Split> bind_split(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) bind_split[b] = split(glm::mat4(bind_world_[b]));
  std::size_t approximate = 0;
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    if (node_of_bone_[b] < 0) continue;
    const std::int32_t n = node_of_bone_[b];
    const Split rest = split(glm::mat4(nodes_[static_cast<std::size_t>(n)].global));
    bool exact = glm::length(rest.axis_scale - bind_split[b].axis_scale) <= 1e-4f * glm::length(rest.axis_scale);
    // A shear or mirror in this bone's world, or a non-uniform scale passed on to children, is not a rigid motion.
    const bool has_children = std::any_of(
        bones_.begin(), bones_.end(), [&](const Bone& other) { return other.parent == static_cast<std::int32_t>(b); });
    exact =
        exact && (rest.similarity || (!has_children && glm::determinant(glm::mat3(rest.rigid())) > 0.0f &&
                                      glm::determinant(glm::mat3(nodes_[static_cast<std::size_t>(n)].global)) > 0.0));
    if (!exact) ++approximate;
  }
  if (approximate > 0)
    warnings_.push_back(std::to_string(approximate) +
                        " bones have a scale a Skeleton cannot hold (non-uniform scale passed to children, shear, a "
                        "mirror, or a bind scale other than the node's): clips move them approximately, the bind pose "
                        "stays exact; ImportedModel::file_bind_world holds the exact bind");
  result_.model.skeleton = skeleton_from_binds(bones_, bind_split, path_);
  result_.file_bind_world.reserve(bind_world_.size());
  for (const glm::dmat4& m : bind_world_) result_.file_bind_world.emplace_back(m);
}

// --- materials ---
void GltfImport::read_materials() {
  std::vector<std::string> used;
  std::map<int, std::shared_ptr<const std::vector<std::uint8_t>>> embedded_shared;  // image -> its bytes
  for (std::size_t m = 0; m < gltf_.materials.size(); ++m) {
    const tinygltf::Material& source = gltf_.materials[m];
    Material material;
    material.name = unique_material_name(source.name, m, used);
    const auto& factor = source.pbrMetallicRoughness.baseColorFactor;
    if (factor.size() == 4 && std::all_of(factor.begin(), factor.end(), [](double v) { return std::isfinite(v); })) {
      material.diffuse = {std::clamp(factor[0], 0.0, 1.0), std::clamp(factor[1], 0.0, 1.0),
                          std::clamp(factor[2], 0.0, 1.0)};
      material.opacity = static_cast<float>(std::clamp(factor[3], 0.0, 1.0));
    }
    diffuse_texture(material, source.pbrMetallicRoughness.baseColorTexture.index, embedded_shared);
    result_.model.mesh.materials.push_back(std::move(material));
  }
}

// The base colour texture `texture` of `material`: an embedded PNG or JPEG image is shared by every material that
// uses it; a file is referenced by the path the file names (image_paths_ holds its canonical form).
void GltfImport::diffuse_texture(Material& material, int texture,
                                 std::map<int, std::shared_ptr<const std::vector<std::uint8_t>>>& embedded_shared) {
  if (texture < 0 || static_cast<std::size_t>(texture) >= gltf_.textures.size()) return;
  const int image = gltf_.textures[static_cast<std::size_t>(texture)].source;
  if (image < 0 || static_cast<std::size_t>(image) >= gltf_.images.size()) return;
  const tinygltf::Image& img = gltf_.images[static_cast<std::size_t>(image)];
  if (img.uri.empty() || img.uri.rfind("data:", 0) == 0) {
    auto found = embedded_images_.find(image);
    if (found != embedded_images_.end() && is_png_or_jpeg(found->second)) {  // moved out after first use
      embedded_shared[image] = std::make_shared<const std::vector<std::uint8_t>>(std::move(found->second));
      embedded_images_.erase(found);
    }
    if (embedded_shared.count(image) != 0) {  // one copy per image, however many materials use it
      material.diffuse_image = embedded_shared[image];
    } else {
      warnings_.push_back("material '" + material.name + "': embedded texture (image " + std::to_string(image) +
                          ") is not a PNG or JPEG image, left out");
    }
    return;
  }
  fs::path resolved = utf8_path::from_utf8(decode_uri_reference(img.uri));
  if (resolved.is_relative()) resolved = utf8_path::from_utf8(base_) / resolved;
  material.diffuse_map = utf8_path::to_utf8(resolved.lexically_normal());
  std::error_code ignored;
  if (!fs::is_regular_file(utf8_path::from_utf8(image_paths_[static_cast<std::size_t>(image)]), ignored))
    warnings_.push_back("material '" + material.name + "': texture '" + material.diffuse_map + "' not found");
}

// --- mesh: one submesh per primitive instance; points merged by (exact bind position, influences) ---
void GltfImport::read_meshes() {
  Mesh& mesh = result_.model.mesh;
  targets_of_node_.assign(nodes_.size(), {0, 0});
  for (const Instance& instance : instances_)
    for (const tinygltf::Primitive& p : gltf_.meshes[static_cast<std::size_t>(instance.mesh)].primitives)
      any_uvs_ = any_uvs_ || p.attributes.count("TEXCOORD_0") > 0;
  for (const Instance& instance : instances_) {
    const tinygltf::Mesh& source = gltf_.meshes[static_cast<std::size_t>(instance.mesh)];
    const NodeInfo& node = nodes_[static_cast<std::size_t>(instance.node)];
    InstanceFrame frame;
    // A skinned mesh ignores its node's transform (glTF 2.0 §3.7.3.3): its vertices are in the skin's bind space.
    frame.to_world = instance.skin >= 0 ? glm::dmat4(1.0) : node.global;
    frame.normal_matrix = glm::transpose(glm::inverse(glm::dmat3(frame.to_world)));
    frame.rigid_bone = rigged_ && instance.skin < 0
                           ? static_cast<std::uint16_t>(bone_of_node_[static_cast<std::size_t>(instance.node)])
                           : 0;
    add_morph_targets(instance, frame);
    frame.delta_matrix = glm::dmat3(frame.to_world);
    const std::size_t target_count = targets_of_node_[static_cast<std::size_t>(instance.node)].second;
    for (std::size_t pi = 0; pi < source.primitives.size(); ++pi) {
      const tinygltf::Primitive& primitive = source.primitives[pi];
      const std::string element =
          "meshes[" + std::to_string(instance.mesh) + "].primitives[" + std::to_string(pi) + "]";
      const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++skipped_primitives_;
        continue;
      }
      const PrimitiveData data = read_attributes(instance, primitive, element, target_count);
      const std::size_t first_vertex = mesh.vertex_point.size();
      if (first_vertex + data.count > 0xFFFFFFFFull) reader_.fail(element, "too many vertices");
      add_vertices(instance, primitive, element, data, frame);
      add_triangles(instance, primitive, element, mode, first_vertex, data.count);
    }
  }
  // A target without normal deltas anywhere keeps none (MorphJob then leaves normals to the rest).
  for (MorphTarget& target : result_.model.morph_targets)
    if (std::all_of(target.normal_deltas.begin(), target.normal_deltas.end(),
                    [](glm::vec3 d) { return d == glm::vec3(0.0f); }))
      target.normal_deltas.clear();
  close_triangle_faces(mesh, path_);
  if (unweighted_ > 0)
    warnings_.push_back(std::to_string(unweighted_) +
                        " skinned vertices have no weight: bound rigidly to their skin's first joint");
  if (skipped_primitives_ > 0)
    warnings_.push_back(std::to_string(skipped_primitives_) + " primitives of points or lines skipped");
}

// Morph targets: every primitive of a mesh has the same number (glTF 2.0 §3.7.2.2); this instance's targets are
// appended to the model's, named by mesh.extras.targetNames, weighted by node.weights or else mesh.weights.
void GltfImport::add_morph_targets(const Instance& instance, InstanceFrame& frame) {
  const tinygltf::Mesh& source = gltf_.meshes[static_cast<std::size_t>(instance.mesh)];
  std::vector<MorphTarget>& morph_targets = result_.model.morph_targets;
  std::size_t target_count = 0;
  for (const tinygltf::Primitive& primitive : source.primitives)
    target_count = std::max(target_count, primitive.targets.size());
  frame.first_target = morph_targets.size();
  if (target_count == 0) return;
  const tinygltf::Node& gnode = gltf_.nodes[static_cast<std::size_t>(instance.node)];
  const std::vector<double>& defaults = !gnode.weights.empty() ? gnode.weights : source.weights;
  const tinygltf::Value names = source.extras.IsObject() ? source.extras.Get("targetNames") : tinygltf::Value();
  for (std::size_t k = 0; k < target_count; ++k) {
    MorphTarget target;
    target.mesh = source.name;
    if (names.IsArray() && k < names.ArrayLen() && names.Get(static_cast<int>(k)).IsString())
      target.name = names.Get(static_cast<int>(k)).Get<std::string>();
    else target.name = "target" + std::to_string(k);
    if (k < defaults.size()) {
      if (!std::isfinite(defaults[k]))
        reader_.fail("meshes[" + std::to_string(instance.mesh) + "].weights",
                     "weight " + std::to_string(k) + " is not finite");
      target.default_weight = static_cast<float>(defaults[k]);
    }
    morph_targets.push_back(std::move(target));
  }
  targets_of_node_[static_cast<std::size_t>(instance.node)] = {frame.first_target, target_count};
}

PrimitiveData GltfImport::read_attributes(const Instance& instance, const tinygltf::Primitive& primitive,
                                          const std::string& element, std::size_t target_count) const {
  PrimitiveData data;
  const auto position_attribute = primitive.attributes.find("POSITION");
  if (position_attribute == primitive.attributes.end()) reader_.fail(element + ".attributes", "has no POSITION");
  data.positions = reader_.read(position_attribute->second, {3}, element + " POSITION");
  const std::size_t count = data.count = data.positions.size() / 3;
  auto optional = [&](const char* name, std::size_t components) {
    const auto found = primitive.attributes.find(name);
    if (found == primitive.attributes.end()) return std::vector<double>();
    std::vector<double> values = reader_.read(found->second, {components}, element + " " + name);
    if (values.size() != count * components)
      reader_.fail(element + ".attributes." + name, "has not as many elements as POSITION");
    return values;
  };
  data.normals = optional("NORMAL", 3);
  data.uvs = optional("TEXCOORD_0", 2);
  if (instance.skin >= 0) {
    for (int set = 0;; ++set) {
      const std::string joints_name = "JOINTS_" + std::to_string(set), weights_name = "WEIGHTS_" + std::to_string(set);
      const bool has_joints = primitive.attributes.count(joints_name) > 0;
      const bool has_weights = primitive.attributes.count(weights_name) > 0;
      if (!has_joints && !has_weights) break;
      if (has_joints != has_weights)
        reader_.fail(element + ".attributes", joints_name + " and " + weights_name + " must come together");
      data.joint_sets.push_back(optional(joints_name.c_str(), 4));
      data.weight_sets.push_back(optional(weights_name.c_str(), 4));
    }
  }
  if (!primitive.targets.empty() && primitive.targets.size() != target_count)
    reader_.fail(element + ".targets", "has " + std::to_string(primitive.targets.size()) +
                                           " targets where another primitive of the mesh has " +
                                           std::to_string(target_count));
  data.target_positions.resize(primitive.targets.size());
  data.target_normals.resize(primitive.targets.size());
  for (std::size_t k = 0; k < primitive.targets.size(); ++k) {
    const std::string target_element = element + ".targets[" + std::to_string(k) + "]";
    for (const auto& [name, accessor] : primitive.targets[k]) {
      if (name != "POSITION" && name != "NORMAL") continue;  // TANGENT and others do not move points
      std::vector<double> values = reader_.read(accessor, {3}, target_element + " " + name);
      if (values.size() != count * 3) reader_.fail(target_element + "." + name, "has not as many elements as POSITION");
      for (const double d : values)
        if (!std::isfinite(d)) reader_.fail(target_element + "." + name, "a displacement is not finite");
      (name == "POSITION" ? data.target_positions[k] : data.target_normals[k]) = std::move(values);
    }
  }
  return data;
}

// The primitive's render vertices: each with its point (merged by position and influences, every influence kept),
// the point's morph deltas when the point is new, and the vertex's normal and UV.
void GltfImport::add_vertices(const Instance& instance, const tinygltf::Primitive& primitive,
                              const std::string& element, const PrimitiveData& data, const InstanceFrame& frame) {
  Mesh& mesh = result_.model.mesh;
  const SkinInfo* skin = instance.skin >= 0 ? &skins_[static_cast<std::size_t>(instance.skin)] : nullptr;
  std::vector<std::pair<std::uint16_t, double>> influences_of;
  std::vector<Influence> influences;
  for (std::size_t v = 0; v < data.count; ++v) {
    influences_of.clear();
    for (std::size_t set = 0; set < data.joint_sets.size(); ++set)
      for (std::size_t k = 0; k < 4; ++k) {
        const double w = data.weight_sets[set][4 * v + k];
        if (!(w > 0.0)) continue;
        const double joint = data.joint_sets[set][4 * v + k];
        if (joint < 0.0 || joint >= static_cast<double>(skin->joints.size()))
          reader_.fail(element + ".attributes.JOINTS_" + std::to_string(set),
                       "vertex " + std::to_string(v) + " names joint " + std::to_string(joint) + " of " +
                           std::to_string(skin->joints.size()));
        const auto bone = static_cast<std::uint16_t>(
            bone_of_node_[static_cast<std::size_t>(skin->joints[static_cast<std::size_t>(joint)])]);
        auto same =
            std::find_if(influences_of.begin(), influences_of.end(), [&](const auto& i) { return i.first == bone; });
        if (same != influences_of.end()) same->second += w;
        else influences_of.emplace_back(bone, w);
      }
    std::sort(influences_of.begin(), influences_of.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    influences.clear();
    if (influences_of.empty()) {
      if (skin != nullptr) ++unweighted_;
      // glTF leaves such a vertex undefined; three.js and others leave it where the skin's space puts it.
      influences.push_back({skin != nullptr
                                ? static_cast<std::uint16_t>(bone_of_node_[static_cast<std::size_t>(skin->joints[0])])
                                : frame.rigid_bone,
                            1.0f});
    } else {
      double total = 0.0;
      for (const auto& i : influences_of) total += i.second;
      for (const auto& [bone, w] : influences_of) influences.push_back({bone, static_cast<float>(w / total)});
    }
    const glm::dvec3 raw{data.positions[3 * v], data.positions[3 * v + 1], data.positions[3 * v + 2]};
    const glm::vec3 position = reader_.narrow(glm::dvec3(frame.to_world * glm::dvec4(raw, 1.0)),
                                              element + " POSITION: vertex " + std::to_string(v));
    // Each target's displacement of this vertex: the points merge only where every target moves them alike.
    position_deltas_.clear();
    normal_deltas_.clear();
    for (std::size_t k = 0; k < primitive.targets.size(); ++k) {
      const auto& tp = data.target_positions[k];
      const auto& tn = data.target_normals[k];
      glm::dvec3 dp(0.0), dn(0.0);
      if (!tp.empty()) dp = frame.delta_matrix * glm::dvec3(tp[3 * v], tp[3 * v + 1], tp[3 * v + 2]);
      if (!tn.empty()) dn = frame.normal_matrix * glm::dvec3(tn[3 * v], tn[3 * v + 1], tn[3 * v + 2]);
      position_deltas_.push_back(reader_.narrow(dp, element + " target " + std::to_string(k)));
      normal_deltas_.push_back(reader_.narrow(dn, element + " target " + std::to_string(k)));
    }
    const auto [point, inserted] =
        points_.add(position, influences, position_deltas_, static_cast<std::uint32_t>(frame.first_target));
    for (std::size_t k = 0; inserted && k < primitive.targets.size(); ++k) {
      if (position_deltas_[k] == glm::vec3(0.0f) && normal_deltas_[k] == glm::vec3(0.0f))
        continue;  // sparse: only the points it moves
      MorphTarget& target = result_.model.morph_targets[frame.first_target + k];
      target.points.push_back(point);
      target.position_deltas.push_back(position_deltas_[k]);
      target.normal_deltas.push_back(normal_deltas_[k]);
    }
    mesh.vertex_point.push_back(point);
    const auto& normals = data.normals;
    glm::dvec3 normal = normals.empty()
                            ? glm::dvec3(0.0)
                            : frame.normal_matrix * glm::dvec3(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
    const double length = glm::length(normal);
    normal = std::isfinite(length) && length > 0.0 ? normal / length : glm::dvec3(0.0, 0.0, 1.0);
    mesh.vertex_normals.emplace_back(normal);
    if (any_uvs_)
      mesh.vertex_uvs.emplace_back(data.uvs.empty() ? 0.0f : static_cast<float>(data.uvs[2 * v]),  // glTF's v runs
                                   data.uvs.empty() ? 0.0f : 1.0f - static_cast<float>(data.uvs[2 * v + 1]));  // down
  }
}

// The primitive's triangles (strips and fans unrolled; degenerate ones kept as the file has them) as one submesh.
void GltfImport::add_triangles(const Instance& instance, const tinygltf::Primitive& primitive,
                               const std::string& element, int mode, std::size_t first_vertex, std::size_t count) {
  Mesh& mesh = result_.model.mesh;
  std::vector<std::uint32_t> indices;
  if (primitive.indices >= 0) {
    const std::vector<double> raw = reader_.read(primitive.indices, {1}, element + " indices");
    indices.reserve(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] >= static_cast<double>(count))
        reader_.fail(element + ".indices", "index " + std::to_string(i) + " (" + std::to_string(raw[i]) +
                                               ") is not below the vertex count " + std::to_string(count));
      indices.push_back(static_cast<std::uint32_t>(raw[i]));
    }
  } else {
    indices.resize(count);
    for (std::size_t i = 0; i < count; ++i) indices[i] = static_cast<std::uint32_t>(i);
  }
  Submesh submesh;
  submesh.first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
  submesh.material = primitive.material >= 0 && static_cast<std::size_t>(primitive.material) < mesh.materials.size()
                         ? primitive.material
                         : -1;
  auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    for (std::uint32_t corner : {a, b, c}) mesh.triangles.push_back(static_cast<std::uint32_t>(first_vertex + corner));
  };
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    for (std::size_t i = 0; i + 2 < indices.size(); i += 3) triangle(indices[i], indices[i + 1], indices[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (std::size_t i = 0; i + 2 < indices.size(); ++i)
      if (i % 2 == 0) triangle(indices[i], indices[i + 1], indices[i + 2]);
      else triangle(indices[i + 2], indices[i + 1], indices[i]);  // odd triangles reversed to keep the winding
  } else {
    for (std::size_t i = 1; i + 1 < indices.size(); ++i) triangle(indices[0], indices[i], indices[i + 1]);
  }
  submesh.triangle_count = static_cast<std::uint32_t>(mesh.triangle_count()) - submesh.first_triangle;
  mesh.submeshes.push_back(std::move(submesh));
  result_.submesh_names.push_back({gltf_.nodes[static_cast<std::size_t>(instance.node)].name,
                                   gltf_.meshes[static_cast<std::size_t>(instance.mesh)].name});
}

// --- clips. Skeleton space: T(axis_scale(parent rest world) · t) · R(q); a root bone's parent is the origin ---
void GltfImport::read_clips() {
  std::vector<glm::dvec3> translation_scale(bones_.size(), glm::dvec3(1.0));
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    if (node_of_bone_[b] < 0) continue;
    const std::int32_t parent = nodes_[static_cast<std::size_t>(node_of_bone_[b])].parent;
    if (parent >= 0)
      translation_scale[b] = glm::dvec3(split(glm::mat4(nodes_[static_cast<std::size_t>(parent)].global)).axis_scale);
  }
  std::vector<std::pair<glm::vec3, glm::quat>> local(bones_.size());
  std::vector<bool> has_rest(bones_.size(), false);
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    if (node_of_bone_[b] < 0) continue;
    const NodeInfo& n = nodes_[static_cast<std::size_t>(node_of_bone_[b])];
    local[b] = {reader_.narrow(translation_scale[b] * n.translation, "nodes[" + std::to_string(node_of_bone_[b]) + "]"),
                glm::quat(glm::normalize(n.rotation))};
    has_rest[b] = true;
  }
  const RestLocals rest = rest_locals(result_.model.skeleton, result_.model.mesh.positions, std::move(local), has_rest);
  std::vector<std::string> clip_names;
  for (std::size_t a = 0; a < gltf_.animations.size(); ++a) read_clip(a, rest, translation_scale, clip_names);
}

void GltfImport::read_clip(std::size_t a, const RestLocals& rest, const std::vector<glm::dvec3>& translation_scale,
                           std::vector<std::string>& clip_names) {
  const tinygltf::Animation& source = gltf_.animations[a];
  const std::string animation_element = "animations[" + std::to_string(a) + "]";
  ClipState state;
  Animation& clip = state.clip;
  clip.name = unique_clip_name(source.name, a, clip_names);
  clip.loop = options_.loop_clips;
  state.channel_of_bone.assign(bones_.size(), -1);
  for (std::size_t c = 0; c < source.channels.size(); ++c) {
    const tinygltf::AnimationChannel& channel = source.channels[c];
    const std::string element = animation_element + ".channels[" + std::to_string(c) + "]";
    if (channel.target_node < 0 || static_cast<std::size_t>(channel.target_node) >= nodes_.size())
      reader_.fail(element + ".target.node", "node " + std::to_string(channel.target_node) + " does not exist");
    if (channel.sampler < 0 || static_cast<std::size_t>(channel.sampler) >= source.samplers.size())
      reader_.fail(element + ".sampler", "sampler " + std::to_string(channel.sampler) + " does not exist");
    const tinygltf::AnimationSampler& sampler = source.samplers[static_cast<std::size_t>(channel.sampler)];
    const std::string sampler_element = animation_element + ".samplers[" + std::to_string(channel.sampler) + "]";
    const std::string& target = channel.target_path;
    if (target != "translation" && target != "rotation" && target != "scale" && target != "weights")
      reader_.fail(element + ".target.path", "'" + target + "' is not a glTF target");
    Interpolation interpolation = Interpolation::linear;
    if (sampler.interpolation == "STEP") interpolation = Interpolation::step;
    else if (sampler.interpolation == "CUBICSPLINE") interpolation = Interpolation::cubic_spline;
    else if (sampler.interpolation != "LINEAR")
      reader_.fail(sampler_element + ".interpolation", "'" + sampler.interpolation + "' is not a glTF interpolation");
    const std::vector<double> times = reader_.read(sampler.input, {1}, sampler_element + ".input");
    if (!times.empty()) state.duration = std::max(state.duration, static_cast<float>(times.back()));
    if (target == "weights") read_weights_channel(state, channel, sampler, sampler_element, interpolation, times);
    else read_bone_channel(state, channel, sampler, sampler_element, interpolation, times, translation_scale);
  }
  std::vector<bool> has_channel(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) has_channel[b] = state.channel_of_bone[b] >= 0;
  hold_rest(clip, rest, has_channel);
  clip.duration = state.duration;
  if (!std::isfinite(clip.duration) || clip.duration < 0.0f)
    reader_.fail(animation_element, "key times are not finite or negative");
  add_clip(std::move(clip), state.dropped, state.scaled_bones, bones_.size(), path_, result_.clips, warnings_);
}

// A `weights` channel: one float per target per key; a cubic spline has, per key, the in-tangents of every target,
// then the values, then the out-tangents (glTF 2.0 appendix C). A second channel for a node: the first wins.
void GltfImport::read_weights_channel(ClipState& state, const tinygltf::AnimationChannel& channel,
                                      const tinygltf::AnimationSampler& sampler, const std::string& sampler_element,
                                      Interpolation interpolation, const std::vector<double>& times) {
  // (Plain variables, not a structured binding: Clang 14 cannot capture one in the lambda below.)
  const std::size_t first = targets_of_node_[static_cast<std::size_t>(channel.target_node)].first;
  const std::size_t n = targets_of_node_[static_cast<std::size_t>(channel.target_node)].second;
  if (n == 0) return;  // the node has no morphed mesh in the scene
  const std::vector<double> values = reader_.read(sampler.output, {1}, sampler_element + ".output");
  const std::size_t per_key = interpolation == Interpolation::cubic_spline ? 3 : 1;
  if (values.size() != times.size() * n * per_key)
    reader_.fail(sampler_element + ".output", std::to_string(values.size()) + " weights for " +
                                                  std::to_string(times.size()) + " key times of " + std::to_string(n) +
                                                  " morph targets");
  for (const double w : values)
    if (!std::isfinite(w)) reader_.fail(sampler_element + ".output", "a weight is not finite");
  std::vector<MorphChannel>& morph_channels = state.clip.morph_channels;
  for (std::size_t t = 0; t < n; ++t) {
    const auto global = static_cast<std::int32_t>(first + t);
    auto existing = std::find_if(morph_channels.begin(), morph_channels.end(),
                                 [&](const MorphChannel& m) { return m.target == global; });
    if (existing != morph_channels.end()) continue;
    MorphChannel out;
    out.target = global;
    out.weight.interpolation = interpolation;
    double last = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < times.size(); ++k) {
      if (!(times[k] > last)) {
        ++state.dropped;
        continue;
      }
      last = times[k];
      out.weight.times.push_back(static_cast<float>(times[k]));
      auto at = [&](std::size_t part) { return static_cast<float>(values[(k * per_key + part) * n + t]); };
      if (per_key == 3) {
        out.weight.in_tangents.push_back(at(0));
        out.weight.values.push_back(at(1));
        out.weight.out_tangents.push_back(at(2));
      } else {
        out.weight.values.push_back(at(0));
      }
    }
    morph_channels.push_back(std::move(out));
  }
}

// A translation, rotation or scale channel of a node the skeleton holds, into the bone's channel (several glTF
// channels of one node share it); keys at or before their predecessor's time are dropped.
void GltfImport::read_bone_channel(ClipState& state, const tinygltf::AnimationChannel& channel,
                                   const tinygltf::AnimationSampler& sampler, const std::string& sampler_element,
                                   Interpolation interpolation, const std::vector<double>& times,
                                   const std::vector<glm::dvec3>& translation_scale) {
  const std::int32_t bone = bone_of_node_[static_cast<std::size_t>(channel.target_node)];
  if (bone < 0) return;  // the node moves nothing the skeleton holds
  const auto b = static_cast<std::size_t>(bone);
  const std::string& target = channel.target_path;
  const std::size_t width = target == "rotation" ? 4 : 3;
  std::size_t components = 0;
  const std::vector<double> values = reader_.read(sampler.output, {width}, sampler_element + ".output", &components);
  const std::size_t per_key = interpolation == Interpolation::cubic_spline ? 3 : 1;
  if (values.size() != times.size() * width * per_key)
    reader_.fail(sampler_element + ".output", std::to_string(values.size() / width) + " elements for " +
                                                  std::to_string(times.size()) + " key times");
  Animation& clip = state.clip;
  if (state.channel_of_bone[b] < 0) {
    state.channel_of_bone[b] = static_cast<std::int32_t>(clip.channels.size());
    Channel fresh;
    fresh.bone = bone;
    clip.channels.push_back(std::move(fresh));
  }
  Channel& out = clip.channels[static_cast<std::size_t>(state.channel_of_bone[b])];
  const NodeInfo& node = nodes_[static_cast<std::size_t>(channel.target_node)];
  // Element k of key i: in-tangent, value, out-tangent for a cubic spline, else the value.
  auto element_at = [&](std::size_t key, std::size_t part) { return &values[(key * per_key + part) * width]; };
  auto fill = [&](auto& track, auto convert) {
    track.interpolation = interpolation;
    double last = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < times.size(); ++k) {
      if (!(times[k] > last)) {
        ++state.dropped;
        continue;
      }
      last = times[k];
      track.times.push_back(static_cast<float>(times[k]));
      if (per_key == 3) {
        track.in_tangents.push_back(convert(element_at(k, 0), false));
        track.values.push_back(convert(element_at(k, 1), true));
        track.out_tangents.push_back(convert(element_at(k, 2), false));
      } else {
        track.values.push_back(convert(element_at(k, 0), true));
      }
    }
  };
  if (target == "translation") {
    fill(out.translation, [&](const double* v, bool) {
      return reader_.narrow(translation_scale[b] * glm::dvec3(v[0], v[1], v[2]), sampler_element + ".output");
    });
  } else if (target == "rotation") {
    fill(out.rotation, [&](const double* v, bool value) {
      const glm::dquat q(v[3], v[0], v[1], v[2]);
      return glm::quat(value && glm::length(q) > 0.0 ? glm::normalize(q) : q);
    });
  } else {
    fill(out.scale, [&](const double* v, bool) {
      return reader_.narrow(glm::dvec3(v[0], v[1], v[2]) / node.scale, sampler_element + ".output");
    });
    const bool constant_one = std::all_of(out.scale.values.begin(), out.scale.values.end(),
                                          [](glm::vec3 s) { return glm::length(s - glm::vec3(1.0f)) <= 1e-4f; });
    if (!constant_one) ++state.scaled_bones;
  }
}

}  // namespace

bool is_gltf_path(const std::string& path) {
  std::string extension = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".gltf" || extension == ".glb";
}

ImportedModel import_gltf(const std::string& path, const ImportOptions& options) {
  return GltfImport(path, options).run();
}

}  // namespace deform::import_detail
