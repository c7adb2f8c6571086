// Inter-Quake Model (.iqm, version 2) reader. Assimp 5.2's IQM importer reads the meshes but drops the joints, the
// skin and the animations (a rigged character arrives as a static mesh, without a word), so libdeform reads the
// format itself. The format is public (iqm.txt in the IQM SDK): a 124-byte header of little-endian uint32 counts and
// byte offsets into the same file, then arrays of fixed-size records. Every offset and count is checked against the
// file size in 64-bit arithmetic before a byte is read; an error names the file, the element and its byte offset.
// docs/import.md states the conversions.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <iterator>
#include <map>
#include <span>
#include <unordered_map>

#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "import_common.hpp"
#include "utf8_path.hpp"
#include "finite.hpp"
namespace deform::import_detail {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t header_bytes = 124;  // magic[16] + 27 uint32

enum VertexArrayType : std::uint32_t { position = 0, texcoord = 1, normal = 2, blend_indexes = 4, blend_weights = 5 };
enum Format : std::uint32_t {
  is_byte = 0,
  is_ubyte = 1,
  is_short = 2,
  is_ushort = 3,
  is_int = 4,
  is_uint = 5,
  is_half = 6,
  is_float = 7,
  is_double = 8
};
constexpr std::uint32_t anim_loop = 1;

std::uint64_t format_bytes(std::uint32_t format) {
  switch (format) {
    case is_byte:
    case is_ubyte: return 1;
    case is_short:
    case is_ushort:
    case is_half: return 2;
    case is_int:
    case is_uint:
    case is_float: return 4;
    case is_double: return 8;
    default: return 0;
  }
}

// The file's bytes and the checks every read goes through.
class Reader {
 public:
  Reader(std::string path, std::vector<unsigned char> bytes) : path_(std::move(path)), bytes_(std::move(bytes)) {}

  [[noreturn]] void fail(std::uint64_t offset, const std::string& element, const std::string& what) const {
    throw Error::in_file(path_, element + " at byte " + std::to_string(offset), what);
  }

  // Checks that `count` records of `size` bytes from `offset` lie inside the file (no overflow: the product is only
  // formed once count is known to be at most the file size over `size`).
  void range(std::uint64_t offset, std::uint64_t count, std::uint64_t size, const std::string& element) const {
    const std::uint64_t file = bytes_.size();
    if (count == 0) return;
    if (offset > file || count > (file - offset) / size)
      fail(offset, element,
           std::to_string(count) + " records of " + std::to_string(size) + " bytes run past the end of the file (" +
               std::to_string(file) + " bytes)");
  }

  std::uint32_t u32(std::uint64_t offset, const std::string& element) const {
    range(offset, 1, 4, element);
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | bytes_[offset + static_cast<std::uint64_t>(i)];
    return v;
  }
  std::int32_t i32(std::uint64_t offset, const std::string& element) const {
    return static_cast<std::int32_t>(u32(offset, element));
  }
  float f32(std::uint64_t offset, const std::string& element) const {
    const float v = std::bit_cast<float>(u32(offset, element));
    if (!std::isfinite(v)) fail(offset, element, "a number is not finite");
    return v;
  }
  // One vertex-array component as a double; the caller has checked the array's range.
  double component(std::uint64_t offset, std::uint32_t format) const {
    const unsigned char* p = bytes_.data() + offset;
    auto little = [&](int n) {
      std::uint64_t v = 0;
      for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
      return v;
    };
    switch (format) {
      case is_byte: return static_cast<std::int8_t>(p[0]);
      case is_ubyte: return p[0];
      case is_short: return static_cast<std::int16_t>(little(2));
      case is_ushort: return static_cast<double>(little(2));
      case is_int: return static_cast<std::int32_t>(little(4));
      case is_uint: return static_cast<double>(little(4));
      case is_half: {
        const auto h = static_cast<std::uint32_t>(little(2));
        const int exponent = static_cast<int>((h >> 10) & 0x1f);
        const double mantissa = h & 0x3ff;
        const double magnitude = exponent == 0    ? std::ldexp(mantissa, -24)
                                 : exponent == 31 ? (mantissa == 0 ? HUGE_VAL : NAN)
                                                  : std::ldexp(mantissa + 1024.0, exponent - 25);
        return (h & 0x8000) ? -magnitude : magnitude;
      }
      case is_float: return std::bit_cast<float>(static_cast<std::uint32_t>(little(4)));
      case is_double: return std::bit_cast<double>(little(8));
      default: return 0.0;
    }
  }
  std::uint16_t u16(std::uint64_t offset) const {
    return static_cast<std::uint16_t>(bytes_[offset] | (bytes_[offset + 1] << 8));
  }

  // A 0-terminated string at `at` in the text block [text, text + size).
  std::string text(std::uint64_t text, std::uint64_t size, std::uint32_t at, std::uint64_t record,
                   const std::string& element) const {
    if (size == 0 && at == 0) return {};
    if (at >= size) fail(record, element, "name offset " + std::to_string(at) + " lies outside the text block");
    const auto begin = bytes_.begin() + static_cast<std::ptrdiff_t>(text + at);
    const auto end = bytes_.begin() + static_cast<std::ptrdiff_t>(text + size);
    const auto zero = std::find(begin, end, 0);
    if (zero == end) fail(record, element, "name at text offset " + std::to_string(at) + " is not 0-terminated");
    return std::string(begin, zero);
  }

  std::uint64_t size() const { return bytes_.size(); }
  const unsigned char* data() const { return bytes_.data(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<unsigned char> bytes_;
};

struct Header {
  std::uint32_t num_text, ofs_text, num_meshes, ofs_meshes, num_vertexarrays, num_vertexes, ofs_vertexarrays,
      num_triangles, ofs_triangles, num_joints, ofs_joints, num_poses, ofs_poses, num_anims, ofs_anims, num_frames,
      num_framechannels, ofs_frames;
};

// A joint or pose transform: output = T · R · S · input (iqm.txt: "(input*scale)*rotation + translation").
struct Trs {
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
  glm::dvec3 scale{1.0};
  glm::dmat4 matrix() const {
    glm::dmat4 m = glm::mat4_cast(rotation);
    for (int c = 0; c < 3; ++c) m[c] *= scale[c];
    m[3] = glm::dvec4(translation, 1.0);
    return m;
  }
};

struct VertexArray {
  std::uint32_t format = 0, size = 0;
  std::uint64_t offset = 0;
  bool present = false;
};

}  // namespace

bool is_iqm_path(const std::string& path) {
  std::string extension = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".iqm";
}

ImportedModel import_iqm(const std::string& path, const ImportOptions& options) {
  std::vector<unsigned char> bytes;
  {
    std::ifstream in(utf8_path::from_utf8(path), std::ios::binary);
    if (!in) throw Error::in_file(path, "", "cannot be opened");
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error::in_file(path, "", "cannot be read");
  }
  Reader file(path, std::move(bytes));
  const std::string hdr = "header";
  file.range(0, 1, header_bytes, hdr);
  if (std::memcmp(file.data(), "INTERQUAKEMODEL\0", 16) != 0)
    file.fail(0, hdr, "not an IQM file (no INTERQUAKEMODEL magic)");
  if (const std::uint32_t version = file.u32(16, hdr); version != 2)
    file.fail(16, hdr, "IQM version " + std::to_string(version) + " (only version 2 is read)");
  if (const std::uint32_t declared = file.u32(20, hdr); declared > file.size())
    file.fail(20, hdr,
              "truncated: the header gives " + std::to_string(declared) + " bytes, the file has " +
                  std::to_string(file.size()));
  auto field = [&](int index) { return file.u32(28 + 4 * static_cast<std::uint64_t>(index), hdr); };
  Header h{};
  h.num_text = field(0), h.ofs_text = field(1), h.num_meshes = field(2), h.ofs_meshes = field(3);
  h.num_vertexarrays = field(4), h.num_vertexes = field(5), h.ofs_vertexarrays = field(6);
  h.num_triangles = field(7), h.ofs_triangles = field(8);
  h.num_joints = field(10), h.ofs_joints = field(11), h.num_poses = field(12), h.ofs_poses = field(13);
  h.num_anims = field(14), h.ofs_anims = field(15), h.num_frames = field(16), h.num_framechannels = field(17);
  h.ofs_frames = field(18);

  file.range(h.ofs_text, h.num_text, 1, "text");
  file.range(h.ofs_meshes, h.num_meshes, 24, "meshes");
  file.range(h.ofs_vertexarrays, h.num_vertexarrays, 20, "vertexarrays");
  file.range(h.ofs_triangles, h.num_triangles, 12, "triangles");
  file.range(h.ofs_joints, h.num_joints, 48, "joints");
  file.range(h.ofs_poses, h.num_poses, 88, "poses");
  file.range(h.ofs_anims, h.num_anims, 20, "anims");
  file.range(h.ofs_frames, h.num_frames, std::uint64_t{2} * std::max<std::uint64_t>(h.num_framechannels, 1), "frames");
  auto text = [&](std::uint32_t at, std::uint64_t record, const std::string& element) {
    return file.text(h.ofs_text, h.num_text, at, record, element);
  };
  if (h.num_meshes == 0 || h.num_triangles == 0 || h.num_vertexes == 0)
    throw Error::in_file(path, "", "the scene has no triangles");
  if (h.num_joints > 65535) file.fail(68, hdr, std::to_string(h.num_joints) + " joints (at most 65535)");

  ImportedModel result;
  std::vector<std::string>& warnings = result.warnings;
  result.model.name = utf8_path::to_utf8(utf8_path::from_utf8(path).stem());
  result.up = glm::vec3(0.0f, 0.0f, 1.0f);  // Quake's convention, which IQM files follow: +Z up

  // --- vertex arrays ---
  std::array<VertexArray, 6> arrays{};
  for (std::uint32_t a = 0; a < h.num_vertexarrays; ++a) {
    const std::uint64_t record = h.ofs_vertexarrays + std::uint64_t{20} * a;
    const std::string element = "vertexarrays[" + std::to_string(a) + "]";
    const std::uint32_t type = file.u32(record, element), format = file.u32(record + 8, element),
                        size = file.u32(record + 12, element), offset = file.u32(record + 16, element);
    if (type == 3) continue;  // tangents: a Mesh holds none (normals are kept; tangents follow from them and the UVs)
    if (type >= arrays.size()) {  // colours and custom arrays: a Mesh has no place for them
      warnings.push_back(element + (type == 6 ? ": vertex colours" : ": a custom vertex array") +
                         " not read (a Mesh holds positions, normals and UVs)");
      continue;
    }
    const std::uint64_t component = format_bytes(format);
    if (component == 0) file.fail(record + 8, element, "unknown component format " + std::to_string(format));
    const std::uint32_t needed = type == texcoord ? 2 : type == position || type == normal ? 3 : 4;
    if (size < needed || size > 16)
      file.fail(record + 12, element,
                std::to_string(size) + " components per vertex (this array needs " + std::to_string(needed) + ")");
    file.range(offset, h.num_vertexes, component * size, element + " data");
    arrays[type] = {format, size, offset, true};
  }
  if (!arrays[position].present) throw Error::in_file(path, "vertexarrays", "no POSITION array");
  auto read = [&](VertexArray a, std::uint32_t vertex, std::uint32_t c) {
    return file.component(a.offset + (std::uint64_t{vertex} * a.size + c) * format_bytes(a.format), a.format);
  };
  const bool skinned = h.num_joints > 0 && arrays[blend_indexes].present && arrays[blend_weights].present;
  if (h.num_joints > 0 && !skinned)
    warnings.push_back(std::to_string(h.num_joints) +
                       " joints but no BLENDINDEXES/BLENDWEIGHTS arrays: every vertex bound to the first joint");

  // --- skeleton: the joints, parents before children; several roots are held by an added bone `root` ---
  std::vector<Trs> joint_local(h.num_joints);
  std::vector<std::int32_t> joint_parent(h.num_joints, -1);
  std::vector<std::string> joint_name(h.num_joints);
  std::size_t roots = 0;
  for (std::uint32_t j = 0; j < h.num_joints; ++j) {
    const std::uint64_t record = h.ofs_joints + std::uint64_t{48} * j;
    const std::string element = "joints[" + std::to_string(j) + "]";
    joint_name[j] = text(file.u32(record, element), record, element);
    joint_parent[j] = file.i32(record + 4, element);
    if (joint_parent[j] >= static_cast<std::int32_t>(j))
      file.fail(record + 4, element, "parent " + std::to_string(joint_parent[j]) + " does not precede the joint");
    if (joint_parent[j] < 0) {
      joint_parent[j] = -1;
      ++roots;
    }
    Trs& t = joint_local[j];
    for (int c = 0; c < 3; ++c) t.translation[c] = file.f32(record + 8 + 4 * static_cast<std::uint64_t>(c), element);
    t.rotation = glm::dquat(file.f32(record + 32, element), file.f32(record + 20, element),
                            file.f32(record + 24, element), file.f32(record + 28, element));
    for (int c = 0; c < 3; ++c) t.scale[c] = file.f32(record + 36 + 4 * static_cast<std::uint64_t>(c), element);
    const double length = glm::length(t.rotation);
    if (!(length > 1e-6)) file.fail(record + 20, element, "rotation quaternion has length 0");
    t.rotation /= length;
  }
  const bool rigged = h.num_joints > 0;
  result.rigged = rigged;
  const std::uint32_t first = roots > 1 ? 1 : 0;  // bone id of joint j is first + j
  std::vector<Bone> bones;
  std::vector<glm::dmat4> bind_world;
  std::size_t shortened = 0;
  if (!rigged || first == 1) {
    Bone root;
    root.name = "root";
    bones.push_back(root);
    bind_world.emplace_back(1.0);
  }
  for (std::uint32_t j = 0; j < h.num_joints; ++j) {
    Bone bone;
    bone.name = fit_name(joint_name[j], shortened);
    bone.parent = joint_parent[j] < 0 ? (first == 1 ? 0 : -1) : static_cast<std::int32_t>(first) + joint_parent[j];
    const glm::dmat4 parent =
        joint_parent[j] < 0 ? glm::dmat4(1.0) : bind_world[static_cast<std::size_t>(first) + joint_parent[j]];
    bind_world.push_back(parent * joint_local[j].matrix());
    bones.push_back(std::move(bone));
  }
  if (shortened > 0)
    warnings.push_back(std::to_string(shortened) + " bone names longer than 79 bytes shortened to fit .sk");
  std::vector<Split> bind_split(bones.size());
  std::size_t not_similar = 0;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const glm::mat4 world(bind_world[b]);
    if (!finite(world))
      throw Error::in_file(path, "joints", "bind transform of joint '" + bones[b].name + "' overflows");
    bind_split[b] = split(world);
    if (!bind_split[b].similarity) ++not_similar;
    result.file_bind_world.push_back(world);
  }
  if (not_similar > 0)
    warnings.push_back(std::to_string(not_similar) +
                       " joints have non-uniform or mirrored bind scale: a Skeleton holds no scale, so clips move "
                       "them approximately (the bind pose stays exact)");
  result.model.skeleton = skeleton_from_binds(bones, bind_split, path);

  // --- materials: one per distinct material string (IQM names a texture there), resolved beside the file ---
  Mesh& mesh = result.model.mesh;
  const fs::path folder = utf8_path::from_utf8(path).parent_path();
  std::map<std::string, std::int32_t> material_of;
  struct Part {
    std::string name;
    std::int32_t material;
    std::uint32_t first_vertex, num_vertexes, first_triangle, num_triangles;
  };
  std::vector<Part> parts;
  for (std::uint32_t m = 0; m < h.num_meshes; ++m) {
    const std::uint64_t record = h.ofs_meshes + std::uint64_t{24} * m;
    const std::string element = "meshes[" + std::to_string(m) + "]";
    Part part;
    part.name = text(file.u32(record, element), record, element);
    const std::string material = text(file.u32(record + 4, element), record + 4, element);
    part.first_vertex = file.u32(record + 8, element);
    part.num_vertexes = file.u32(record + 12, element);
    part.first_triangle = file.u32(record + 16, element);
    part.num_triangles = file.u32(record + 20, element);
    if (std::uint64_t{part.first_vertex} + part.num_vertexes > h.num_vertexes)
      file.fail(record + 8, element, "vertices run past the file's " + std::to_string(h.num_vertexes));
    if (std::uint64_t{part.first_triangle} + part.num_triangles > h.num_triangles)
      file.fail(record + 16, element, "triangles run past the file's " + std::to_string(h.num_triangles));
    const auto [found, inserted] = material_of.emplace(material, static_cast<std::int32_t>(mesh.materials.size()));
    if (inserted) {
      Material out;
      out.name = material;
      for (char& c : out.name)
        if (std::isspace(static_cast<unsigned char>(c)) || static_cast<unsigned char>(c) < 0x20) c = '_';
      // Names are unique (an MTL refers to materials by name): an empty name, or one that whitespace replacement
      // made equal to an earlier one, becomes materialN.
      if (out.name.empty() || std::any_of(mesh.materials.begin(), mesh.materials.end(),
                                          [&](const Material& earlier) { return earlier.name == out.name; }))
        out.name = "material" + std::to_string(mesh.materials.size());
      if (!material.empty()) {
        std::string texture = material;
        std::replace(texture.begin(), texture.end(), '\\', '/');
        // Confined to the model's folder like every file a model names (resolve_referenced_file); first, as it
        // refuses a name that is no path (not UTF-8, on Windows).
        const std::string real = resolve_referenced_file(path, texture, element + ".material", options.references);
        fs::path resolved = utf8_path::from_utf8(texture);
        if (resolved.is_relative()) resolved = folder / resolved;
        out.diffuse_map = utf8_path::to_utf8(resolved.lexically_normal());
        std::error_code error;
        if (!fs::is_regular_file(utf8_path::from_utf8(real), error))
          warnings.push_back("material '" + out.name + "': texture '" + out.diffuse_map + "' not found");
      }
      mesh.materials.push_back(std::move(out));
    }
    part.material = found->second;
    parts.push_back(std::move(part));
  }

  // --- vertices: positions in the bind pose (IQM stores them so), influences from the blend arrays ---
  const std::uint16_t joint_bone = static_cast<std::uint16_t>(first);
  std::vector<std::uint32_t> point_of_vertex(h.num_vertexes);
  std::vector<glm::vec3> vertex_normal(h.num_vertexes, glm::vec3(0.0f, 0.0f, 1.0f));
  std::vector<glm::vec2> vertex_uv(arrays[texcoord].present ? h.num_vertexes : 0);
  std::unordered_map<PointKey, std::uint32_t, PointKeyHash> point_of_key;
  std::size_t unweighted = 0;
  const double weight_unit = [&] {
    switch (arrays[blend_weights].format) {
      case is_ubyte: return 255.0;
      case is_ushort: return 65535.0;
      case is_uint: return 4294967295.0;
      case is_byte: return 127.0;
      case is_short: return 32767.0;
      case is_int: return 2147483647.0;
      default: return 1.0;
    }
  }();
  for (std::uint32_t v = 0; v < h.num_vertexes; ++v) {
    glm::vec3 p;
    for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(read(arrays[position], v, static_cast<std::uint32_t>(c)));
    if (!finite(p))
      throw Error::in_file(path, "vertex " + std::to_string(v) + " at byte " + std::to_string(arrays[position].offset),
                           "position is not finite");
    Influences influences;
    if (skinned) {
      std::array<std::pair<double, std::uint32_t>, 4> pairs{};
      double total = 0.0;
      for (std::uint32_t i = 0; i < 4; ++i) {
        const double joint = read(arrays[blend_indexes], v, i);
        const double weight = read(arrays[blend_weights], v, i) / weight_unit;
        const std::uint64_t at = arrays[blend_weights].offset + std::uint64_t{v} * arrays[blend_weights].size;
        if (!std::isfinite(weight) || weight < 0.0)
          file.fail(at, "vertex " + std::to_string(v) + " BLENDWEIGHTS", "weight is negative or not finite");
        if (weight == 0.0) continue;
        if (!(joint >= 0.0) || joint >= h.num_joints || joint != std::floor(joint))
          file.fail(arrays[blend_indexes].offset, "vertex " + std::to_string(v) + " BLENDINDEXES",
                    "joint " + std::to_string(joint) + " of a weighted influence is not one of the " +
                        std::to_string(h.num_joints) + " joints");
        pairs[i] = {weight, static_cast<std::uint32_t>(joint)};
        total += weight;
      }
      // Strongest first (ties by bone id), one entry per joint.
      std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
      });
      int count = 0;
      for (const auto& [weight, joint] : pairs) {
        if (weight <= 0.0) continue;
        const auto bone = static_cast<std::uint16_t>(first + joint);
        bool merged = false;
        for (int k = 0; k < count; ++k)
          if (influences.bones[static_cast<std::size_t>(k)] == bone) {
            influences.weights[static_cast<std::size_t>(k)] += static_cast<float>(weight / total);
            merged = true;
          }
        if (merged) continue;
        influences.bones[static_cast<std::size_t>(count)] = bone;
        influences.weights[static_cast<std::size_t>(count)] = static_cast<float>(weight / total);
        ++count;
      }
      if (count == 0) {
        ++unweighted;
        influences.bones[0] = joint_bone;
        influences.weights[0] = 1.0f;
      }
    } else {
      influences.bones[0] = rigged ? joint_bone : 0;
      influences.weights[0] = 1.0f;
    }
    const auto [found, inserted] =
        point_of_key.emplace(point_key(p, influences), static_cast<std::uint32_t>(mesh.positions.size()));
    if (inserted) {
      mesh.positions.push_back(p);
      result.model.weights.bones.emplace_back(influences.bones[0], influences.bones[1], influences.bones[2],
                                              influences.bones[3]);
      result.model.weights.weights.emplace_back(influences.weights[0], influences.weights[1], influences.weights[2],
                                                influences.weights[3]);
    }
    point_of_vertex[v] = found->second;
    if (arrays[normal].present) {
      glm::vec3 n;
      for (int c = 0; c < 3; ++c) n[c] = static_cast<float>(read(arrays[normal], v, static_cast<std::uint32_t>(c)));
      const float length = glm::length(n);
      if (std::isfinite(length) && length > 0.0f) vertex_normal[v] = n / length;
    }
    if (arrays[texcoord].present) {
      // IQM's texture origin is the top left (the convention of its exporters); libdeform's, like OBJ's, the bottom
      // left.
      const auto u = static_cast<float>(read(arrays[texcoord], v, 0)),
                 t = static_cast<float>(read(arrays[texcoord], v, 1));
      vertex_uv[v] = {std::isfinite(u) ? u : 0.0f, std::isfinite(t) ? 1.0f - t : 0.0f};
    }
  }
  if (unweighted > 0)
    warnings.push_back(std::to_string(unweighted) + " vertices have no bone weight: bound to the first joint");

  if (rigged) {
    // One skin for the listing (ImportedModel::skins): the file's joints, every mesh (IQM skins them all).
    ImportedSkin listed;
    listed.joints = h.num_joints;
    for (const Part& part : parts)
      if (std::find(listed.meshes.begin(), listed.meshes.end(), part.name) == listed.meshes.end())
        listed.meshes.push_back(part.name);
    result.skins.push_back(std::move(listed));
  }

  // --- triangles, per IQM mesh: render vertices are the mesh's vertices, IQM's clockwise front faces turned
  // counter-clockwise ---
  for (const Part& part : parts) {
    Submesh submesh;
    submesh.first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
    submesh.material = part.material;
    submesh.object = part.name;
    submesh.group = part.name;
    const auto first_vertex = static_cast<std::uint32_t>(mesh.vertex_point.size());
    for (std::uint32_t v = part.first_vertex; v < part.first_vertex + part.num_vertexes; ++v) {
      mesh.vertex_point.push_back(point_of_vertex[v]);
      mesh.vertex_normals.push_back(vertex_normal[v]);
      if (!vertex_uv.empty()) mesh.vertex_uvs.push_back(vertex_uv[v]);
    }
    for (std::uint32_t t = part.first_triangle; t < part.first_triangle + part.num_triangles; ++t) {
      const std::uint64_t record = h.ofs_triangles + std::uint64_t{12} * t;
      const std::string element = "triangles[" + std::to_string(t) + "]";
      std::array<std::uint32_t, 3> corner{};
      for (std::uint64_t c = 0; c < 3; ++c) {
        const std::uint32_t vertex = file.u32(record + 4 * c, element);
        if (vertex < part.first_vertex || vertex - part.first_vertex >= part.num_vertexes)
          file.fail(record + 4 * c, element,
                    "vertex " + std::to_string(vertex) + " is outside mesh '" + part.name + "' (vertices " +
                        std::to_string(part.first_vertex) + " to " +
                        std::to_string(std::uint64_t{part.first_vertex} + part.num_vertexes) + ")");
        corner[c] = first_vertex + (vertex - part.first_vertex);
      }
      mesh.triangles.insert(mesh.triangles.end(), {corner[0], corner[2], corner[1]});
    }
    submesh.triangle_count = static_cast<std::uint32_t>(mesh.triangle_count()) - submesh.first_triangle;
    mesh.submeshes.push_back(std::move(submesh));
  }
  if (mesh.triangles.empty()) throw Error::in_file(path, "", "the scene has no triangles");
  mesh.face_sizes.assign(mesh.triangle_count(), 3);
  mesh.face_corners = mesh.triangles;
  if (!rigged) {
    if (h.num_anims > 0) warnings.push_back(std::to_string(h.num_anims) + " animations without joints ignored");
    return result;
  }

  // --- clips: each anim's frames; a pose channel is offset + (masked ? frame value · scale : 0) ---
  if (h.num_anims > 0 && h.num_poses != h.num_joints)
    file.fail(76, hdr,
              std::to_string(h.num_poses) + " poses for " + std::to_string(h.num_joints) +
                  " joints (animations need one pose per joint)");
  struct PoseRecord {
    std::uint32_t mask = 0;
    std::array<float, 10> offset{}, scale{};
  };
  std::vector<PoseRecord> poses(h.num_anims > 0 ? h.num_poses : 0);
  std::uint64_t channels = 0;
  std::size_t pose_parents_differ = 0;
  for (std::uint32_t p = 0; p < poses.size(); ++p) {
    const std::uint64_t record = h.ofs_poses + std::uint64_t{88} * p;
    const std::string element = "poses[" + std::to_string(p) + "]";
    if (file.i32(record, element) != joint_parent[p] && !(file.i32(record, element) < 0 && joint_parent[p] < 0))
      ++pose_parents_differ;
    poses[p].mask = file.u32(record + 4, element) & 0x3ff;
    for (std::uint64_t c = 0; c < 10; ++c) {
      poses[p].offset[c] = file.f32(record + 8 + 4 * c, element);
      poses[p].scale[c] = file.f32(record + 48 + 4 * c, element);
    }
    channels += static_cast<std::uint64_t>(std::popcount(poses[p].mask));
  }
  if (h.num_anims > 0 && channels != h.num_framechannels)
    file.fail(h.ofs_poses, "poses",
              "the channel masks select " + std::to_string(channels) + " channels, the header gives " +
                  std::to_string(h.num_framechannels) + " per frame");
  // Where each joint's channels start within a frame: after the channels of the poses before it.
  std::vector<std::uint64_t> channels_before(poses.size());
  for (std::size_t p = 1; p < poses.size(); ++p)
    channels_before[p] = channels_before[p - 1] + static_cast<std::uint64_t>(std::popcount(poses[p - 1].mask));
  if (pose_parents_differ > 0)
    warnings.push_back(std::to_string(pose_parents_differ) +
                       " poses name another parent than their joint: the joints' hierarchy is used");
  // A bone's translation in skeleton space is its IQM translation times its parent's uniform bind scale (uniform
  // scale commutes with rotation); scale keys are kept relative to the joint's own bind scale.
  auto parent_scale = [&](std::uint32_t j) {
    return joint_parent[j] < 0 ? 1.0f : bind_split[first + static_cast<std::size_t>(joint_parent[j])].scale;
  };
  std::vector<std::string> clip_names;
  for (std::uint32_t a = 0; a < h.num_anims; ++a) {
    const std::uint64_t record = h.ofs_anims + std::uint64_t{20} * a;
    const std::string element = "anims[" + std::to_string(a) + "]";
    Animation clip;
    clip.name = text(file.u32(record, element), record, element);
    const std::uint32_t first_frame = file.u32(record + 4, element), frames = file.u32(record + 8, element);
    double rate = std::bit_cast<float>(file.u32(record + 12, element));
    const std::uint32_t flags = file.u32(record + 16, element);
    if (std::uint64_t{first_frame} + frames > h.num_frames)
      file.fail(record + 4, element, "frames run past the file's " + std::to_string(h.num_frames));
    if (clip.name.empty() || std::find(clip_names.begin(), clip_names.end(), clip.name) != clip_names.end())
      clip.name = "clip" + std::to_string(a);
    clip_names.push_back(clip.name);
    if (!(rate > 0.0) || !std::isfinite(rate)) {
      rate = options.default_ticks_per_second;
      warnings.push_back("clip '" + clip.name + "': no frame rate in the file, " + std::to_string(rate) +
                         " frames per second assumed");
    }
    // Frame f is at f / rate. A clip the file marks as looping wraps from its last frame back to its first over one
    // more frame interval, so the first frame is repeated at the end.
    const bool wraps = (flags & anim_loop) != 0 && frames > 1;
    const std::uint32_t keys = frames + (wraps ? 1 : 0);
    clip.duration = frames == 0 ? 0.0f : static_cast<float>((keys - 1) / rate);
    clip.loop = options.loop_clips;
    std::size_t scaled_bones = 0;
    for (std::uint32_t j = 0; j < h.num_joints; ++j) {
      const PoseRecord& pose = poses[j];
      Channel channel;
      channel.bone = static_cast<std::int32_t>(first + j);
      const bool moves_t = (pose.mask & 0x7) != 0, moves_r = (pose.mask & 0x78) != 0;
      const bool moves_s = (pose.mask & 0x380) != 0;
      const std::uint64_t before = channels_before[j];
      bool scaled = false;
      for (std::uint32_t key = 0; key < std::max<std::uint32_t>(keys, 1); ++key) {
        const std::uint32_t f = frames == 0 ? 0 : first_frame + (key < frames ? key : 0);
        std::array<double, 10> value{};
        std::uint64_t at = h.ofs_frames + (std::uint64_t{f} * h.num_framechannels + before) * 2;
        for (int c = 0; c < 10; ++c) {
          value[static_cast<std::size_t>(c)] = pose.offset[static_cast<std::size_t>(c)];
          if (frames > 0 && (pose.mask >> c) & 1u) {
            value[static_cast<std::size_t>(c)] +=
                static_cast<double>(file.u16(at)) * pose.scale[static_cast<std::size_t>(c)];
            at += 2;
          }
        }
        const float time = static_cast<float>(key / rate);
        if (key == 0 || moves_t) {
          channel.translation.times.push_back(time);
          channel.translation.values.push_back(parent_scale(j) * glm::vec3(glm::dvec3(value[0], value[1], value[2])));
        }
        if (key == 0 || moves_r) {
          glm::dquat q(value[6], value[3], value[4], value[5]);
          const double length = glm::length(q);
          if (!(length > 1e-6) || !std::isfinite(length))
            file.fail(h.ofs_poses + std::uint64_t{88} * j, element + ": joint '" + joint_name[j] + "'",
                      "rotation at frame " + std::to_string(f) + " has length 0");
          channel.rotation.times.push_back(time);
          channel.rotation.values.push_back(glm::quat(q / length));
        }
        const glm::dvec3 s(value[7], value[8], value[9]);
        const glm::dvec3 relative = s / joint_local[j].scale;
        if (key == 0 || moves_s) {
          if (finite(glm::vec3(relative))) {
            channel.scale.times.push_back(time);
            channel.scale.values.push_back(glm::vec3(relative));
          }
        }
        scaled = scaled || glm::length(relative - glm::dvec3(1.0)) > 1e-3;
        if (frames == 0) break;
      }
      if (scaled) ++scaled_bones;
      // Values must be finite for validate(); a frame value times a huge scale can overflow a float.
      for (const glm::vec3& t : channel.translation.values)
        if (!finite(t))
          file.fail(h.ofs_poses + std::uint64_t{88} * j, element + ": joint '" + joint_name[j] + "'",
                    "a translation key is not finite");
      clip.channels.push_back(std::move(channel));
    }
    if (scaled_bones > 0)
      warnings.push_back("clip '" + clip.name + "': " + std::to_string(scaled_bones) +
                         " bones animate scale, which a Pose cannot hold (ignored)");
    clip.require_valid(bones.size(), path);
    result.clips.push_back(std::move(clip));
  }
  return result;
}

}  // namespace deform::import_detail
