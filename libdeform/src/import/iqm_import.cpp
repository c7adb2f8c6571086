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
#include "scene_assembly.hpp"
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

// An IQM mesh: a range of vertices and triangles with its material.
struct Part {
  std::string name;
  std::int32_t material;
  std::uint32_t first_vertex, num_vertexes, first_triangle, num_triangles;
};

// A pose record: the channels a frame holds (mask) and their offsets and scales.
struct PoseRecord {
  std::uint32_t mask = 0;
  std::array<float, 10> offset{}, scale{};
};

std::vector<unsigned char> read_whole(const std::string& path) {
  std::vector<unsigned char> bytes;
  std::ifstream in(utf8_path::from_utf8(path), std::ios::binary);
  if (!in) throw Error::in_file(path, "", "cannot be opened");
  bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error::in_file(path, "", "cannot be read");
  return bytes;
}

// The IQM reader: each step reads one part of the file into the ImportedModel, in the order below (run()).
class IqmImport {
 public:
  IqmImport(const std::string& path, const ImportOptions& options)
      : path_(path), options_(options), file_(path, read_whole(path)) {}
  ImportedModel run();

 private:
  void read_header();
  std::string text(std::uint32_t at, std::uint64_t record, const std::string& element) const {
    return file_.text(h_.ofs_text, h_.num_text, at, record, element);
  }
  double read(VertexArray a, std::uint32_t vertex, std::uint32_t c) const {
    return file_.component(a.offset + (std::uint64_t{vertex} * a.size + c) * format_bytes(a.format), a.format);
  }
  void read_vertex_arrays();
  void read_joints();
  void bind_joints();
  void read_meshes();
  void read_vertices();
  void skin_influences(std::uint32_t v, double weight_unit, std::vector<Influence>& influences);
  void add_triangles();
  void read_poses();
  void read_clip(std::uint32_t a, std::vector<std::string>& clip_names);
  Channel read_channel(std::uint32_t j, std::uint32_t first_frame, std::uint32_t frames, std::uint32_t keys,
                       double rate, const std::string& element, bool& scaled) const;

  const std::string& path_;
  const ImportOptions& options_;
  const Reader file_;
  const std::string hdr_ = "header";
  Header h_{};
  ImportedModel result_;
  std::vector<std::string>& warnings_ = result_.warnings;
  std::array<VertexArray, 6> arrays_{};
  bool skinned_ = false, rigged_ = false;
  std::vector<Trs> joint_local_;
  std::vector<std::int32_t> joint_parent_;
  std::vector<std::string> joint_name_;
  std::uint32_t first_ = 0;  // bone id of joint j is first_ + j (1 when several roots hang under an added `root`)
  std::size_t bone_count_ = 0;
  std::vector<Split> bind_split_;
  std::vector<Part> parts_;
  std::vector<std::uint32_t> point_of_vertex_;
  std::vector<glm::vec3> vertex_normal_;
  std::vector<glm::vec2> vertex_uv_;
  std::vector<PoseRecord> poses_;
  std::vector<std::uint64_t> channels_before_;  // where each joint's channels start within a frame
};

ImportedModel IqmImport::run() {
  read_header();
  result_.model.name = utf8_path::to_utf8(utf8_path::from_utf8(path_).stem());
  result_.up = glm::vec3(0.0f, 0.0f, 1.0f);  // Quake's convention, which IQM files follow: +Z up
  read_vertex_arrays();
  read_joints();
  bind_joints();
  read_meshes();
  read_vertices();
  add_triangles();
  if (!rigged_) {
    if (h_.num_anims > 0) warnings_.push_back(std::to_string(h_.num_anims) + " animations without joints ignored");
    return std::move(result_);
  }
  read_poses();
  std::vector<std::string> clip_names;
  for (std::uint32_t a = 0; a < h_.num_anims; ++a) read_clip(a, clip_names);
  return std::move(result_);
}

void IqmImport::read_header() {
  const std::string& hdr = hdr_;
  file_.range(0, 1, header_bytes, hdr);
  if (std::memcmp(file_.data(), "INTERQUAKEMODEL\0", 16) != 0)
    file_.fail(0, hdr, "not an IQM file (no INTERQUAKEMODEL magic)");
  if (const std::uint32_t version = file_.u32(16, hdr); version != 2)
    file_.fail(16, hdr, "IQM version " + std::to_string(version) + " (only version 2 is read)");
  if (const std::uint32_t declared = file_.u32(20, hdr); declared > file_.size())
    file_.fail(20, hdr,
               "truncated: the header gives " + std::to_string(declared) + " bytes, the file has " +
                   std::to_string(file_.size()));
  auto field = [&](int index) { return file_.u32(28 + 4 * static_cast<std::uint64_t>(index), hdr); };
  Header& h = h_;
  h.num_text = field(0), h.ofs_text = field(1), h.num_meshes = field(2), h.ofs_meshes = field(3);
  h.num_vertexarrays = field(4), h.num_vertexes = field(5), h.ofs_vertexarrays = field(6);
  h.num_triangles = field(7), h.ofs_triangles = field(8);
  h.num_joints = field(10), h.ofs_joints = field(11), h.num_poses = field(12), h.ofs_poses = field(13);
  h.num_anims = field(14), h.ofs_anims = field(15), h.num_frames = field(16), h.num_framechannels = field(17);
  h.ofs_frames = field(18);

  file_.range(h.ofs_text, h.num_text, 1, "text");
  file_.range(h.ofs_meshes, h.num_meshes, 24, "meshes");
  file_.range(h.ofs_vertexarrays, h.num_vertexarrays, 20, "vertexarrays");
  file_.range(h.ofs_triangles, h.num_triangles, 12, "triangles");
  file_.range(h.ofs_joints, h.num_joints, 48, "joints");
  file_.range(h.ofs_poses, h.num_poses, 88, "poses");
  file_.range(h.ofs_anims, h.num_anims, 20, "anims");
  file_.range(h.ofs_frames, h.num_frames, std::uint64_t{2} * std::max<std::uint64_t>(h.num_framechannels, 1), "frames");
  if (h.num_meshes == 0 || h.num_triangles == 0 || h.num_vertexes == 0)
    throw Error::in_file(path_, "", "the scene has no triangles");
  if (h.num_joints > 65535) file_.fail(68, hdr, std::to_string(h.num_joints) + " joints (at most 65535)");
}

// --- vertex arrays ---
void IqmImport::read_vertex_arrays() {
  for (std::uint32_t a = 0; a < h_.num_vertexarrays; ++a) {
    const std::uint64_t record = h_.ofs_vertexarrays + std::uint64_t{20} * a;
    const std::string element = "vertexarrays[" + std::to_string(a) + "]";
    const std::uint32_t type = file_.u32(record, element), format = file_.u32(record + 8, element),
                        size = file_.u32(record + 12, element), offset = file_.u32(record + 16, element);
    if (type == 3) continue;  // tangents: a Mesh holds none (normals are kept; tangents follow from them and the UVs)
    if (type >= arrays_.size()) {  // colours and custom arrays: a Mesh has no place for them
      warnings_.push_back(element + (type == 6 ? ": vertex colours" : ": a custom vertex array") +
                          " not read (a Mesh holds positions, normals and UVs)");
      continue;
    }
    const std::uint64_t component = format_bytes(format);
    if (component == 0) file_.fail(record + 8, element, "unknown component format " + std::to_string(format));
    const std::uint32_t needed = type == texcoord ? 2 : type == position || type == normal ? 3 : 4;
    if (size < needed || size > 16)
      file_.fail(record + 12, element,
                 std::to_string(size) + " components per vertex (this array needs " + std::to_string(needed) + ")");
    file_.range(offset, h_.num_vertexes, component * size, element + " data");
    arrays_[type] = {format, size, offset, true};
  }
  if (!arrays_[position].present) throw Error::in_file(path_, "vertexarrays", "no POSITION array");
  skinned_ = h_.num_joints > 0 && arrays_[blend_indexes].present && arrays_[blend_weights].present;
  if (h_.num_joints > 0 && !skinned_)
    warnings_.push_back(std::to_string(h_.num_joints) +
                        " joints but no BLENDINDEXES/BLENDWEIGHTS arrays: every vertex bound to the first joint");
}

// --- skeleton: the joints, parents before children ---
void IqmImport::read_joints() {
  joint_local_.resize(h_.num_joints);
  joint_parent_.assign(h_.num_joints, -1);
  joint_name_.resize(h_.num_joints);
  for (std::uint32_t j = 0; j < h_.num_joints; ++j) {
    const std::uint64_t record = h_.ofs_joints + std::uint64_t{48} * j;
    const std::string element = "joints[" + std::to_string(j) + "]";
    joint_name_[j] = text(file_.u32(record, element), record, element);
    joint_parent_[j] = file_.i32(record + 4, element);
    if (joint_parent_[j] >= static_cast<std::int32_t>(j))
      file_.fail(record + 4, element, "parent " + std::to_string(joint_parent_[j]) + " does not precede the joint");
    if (joint_parent_[j] < 0) joint_parent_[j] = -1;
    Trs& t = joint_local_[j];
    for (int c = 0; c < 3; ++c) t.translation[c] = file_.f32(record + 8 + 4 * static_cast<std::uint64_t>(c), element);
    t.rotation = glm::dquat(file_.f32(record + 32, element), file_.f32(record + 20, element),
                            file_.f32(record + 24, element), file_.f32(record + 28, element));
    for (int c = 0; c < 3; ++c) t.scale[c] = file_.f32(record + 36 + 4 * static_cast<std::uint64_t>(c), element);
    const double length = glm::length(t.rotation);
    if (!(length > 1e-6)) file_.fail(record + 20, element, "rotation quaternion has length 0");
    t.rotation /= length;
  }
  rigged_ = h_.num_joints > 0;
  result_.rigged = rigged_;
}

// The bones (several roots are held by an added bone `root`: bones_of_forest), their bind world transforms and the
// skeleton of their rigid parts.
void IqmImport::bind_joints() {
  std::size_t shortened = 0;
  ForestBones forest = bones_of_forest(joint_name_, joint_parent_, shortened);
  first_ = static_cast<std::uint32_t>(forest.first);
  std::vector<Bone> bones = std::move(forest.bones);
  std::vector<glm::dmat4> bind_world;
  if (!rigged_ || first_ == 1) bind_world.emplace_back(1.0);
  for (std::uint32_t j = 0; j < h_.num_joints; ++j) {
    const glm::dmat4 parent =
        joint_parent_[j] < 0 ? glm::dmat4(1.0) : bind_world[static_cast<std::size_t>(first_) + joint_parent_[j]];
    bind_world.push_back(parent * joint_local_[j].matrix());
  }
  warn_shortened_names(shortened, warnings_);
  bind_split_.resize(bones.size());
  std::size_t not_similar = 0;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const glm::mat4 world(bind_world[b]);
    if (!finite(world))
      throw Error::in_file(path_, "joints", "bind transform of joint '" + bones[b].name + "' overflows");
    bind_split_[b] = split(world);
    if (!bind_split_[b].similarity) ++not_similar;
    result_.file_bind_world.push_back(world);
  }
  if (not_similar > 0)
    warnings_.push_back(std::to_string(not_similar) +
                        " joints have non-uniform or mirrored bind scale: a Skeleton holds no scale, so clips move "
                        "them approximately (the bind pose stays exact)");
  bone_count_ = bones.size();
  result_.model.skeleton = skeleton_from_binds(bones, bind_split_, path_);
}

// --- meshes, and materials: one per distinct material string (IQM names a texture there), resolved beside the file
void IqmImport::read_meshes() {
  Mesh& mesh = result_.model.mesh;
  std::map<std::string, std::int32_t> material_of;
  std::vector<std::string> used;
  for (std::uint32_t m = 0; m < h_.num_meshes; ++m) {
    const std::uint64_t record = h_.ofs_meshes + std::uint64_t{24} * m;
    const std::string element = "meshes[" + std::to_string(m) + "]";
    Part part;
    part.name = text(file_.u32(record, element), record, element);
    const std::string material = text(file_.u32(record + 4, element), record + 4, element);
    part.first_vertex = file_.u32(record + 8, element);
    part.num_vertexes = file_.u32(record + 12, element);
    part.first_triangle = file_.u32(record + 16, element);
    part.num_triangles = file_.u32(record + 20, element);
    if (std::uint64_t{part.first_vertex} + part.num_vertexes > h_.num_vertexes)
      file_.fail(record + 8, element, "vertices run past the file's " + std::to_string(h_.num_vertexes));
    if (std::uint64_t{part.first_triangle} + part.num_triangles > h_.num_triangles)
      file_.fail(record + 16, element, "triangles run past the file's " + std::to_string(h_.num_triangles));
    const auto [found, inserted] = material_of.emplace(material, static_cast<std::int32_t>(mesh.materials.size()));
    if (inserted) {
      Material out;
      out.name = unique_material_name(material, mesh.materials.size(), used);
      if (!material.empty())
        out.diffuse_map =
            referenced_texture(path_, material, element + ".material", options_.references, out.name, warnings_);
      mesh.materials.push_back(std::move(out));
    }
    part.material = found->second;
    parts_.push_back(std::move(part));
  }
}

// --- vertices: positions in the bind pose (IQM stores them so), influences from the blend arrays ---
void IqmImport::read_vertices() {
  Mesh& mesh = result_.model.mesh;
  const std::uint16_t joint_bone = static_cast<std::uint16_t>(first_);
  point_of_vertex_.resize(h_.num_vertexes);
  vertex_normal_.assign(h_.num_vertexes, glm::vec3(0.0f, 0.0f, 1.0f));
  vertex_uv_.resize(arrays_[texcoord].present ? h_.num_vertexes : 0);
  PointMerger points(mesh.positions, result_.model.weights);
  std::size_t unweighted = 0;
  const double weight_unit = [&] {
    switch (arrays_[blend_weights].format) {
      case is_ubyte: return 255.0;
      case is_ushort: return 65535.0;
      case is_uint: return 4294967295.0;
      case is_byte: return 127.0;
      case is_short: return 32767.0;
      case is_int: return 2147483647.0;
      default: return 1.0;
    }
  }();
  std::vector<Influence> influences;
  for (std::uint32_t v = 0; v < h_.num_vertexes; ++v) {
    glm::vec3 p;
    for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(read(arrays_[position], v, static_cast<std::uint32_t>(c)));
    if (!finite(p))
      throw Error::in_file(path_,
                           "vertex " + std::to_string(v) + " at byte " + std::to_string(arrays_[position].offset),
                           "position is not finite");
    influences.clear();
    if (skinned_) skin_influences(v, weight_unit, influences);
    if (influences.empty()) {
      if (skinned_) ++unweighted;
      influences.push_back({skinned_ || rigged_ ? joint_bone : std::uint16_t{0}, 1.0f});
    }
    point_of_vertex_[v] = points.add(p, influences).first;
    if (arrays_[normal].present) {
      glm::vec3 n;
      for (int c = 0; c < 3; ++c) n[c] = static_cast<float>(read(arrays_[normal], v, static_cast<std::uint32_t>(c)));
      const float length = glm::length(n);
      if (std::isfinite(length) && length > 0.0f) vertex_normal_[v] = n / length;
    }
    if (arrays_[texcoord].present) {
      // IQM's texture origin is the top left (the convention of its exporters); libdeform's, like OBJ's, the bottom
      // left.
      const auto u = static_cast<float>(read(arrays_[texcoord], v, 0)),
                 t = static_cast<float>(read(arrays_[texcoord], v, 1));
      vertex_uv_[v] = {std::isfinite(u) ? u : 0.0f, std::isfinite(t) ? 1.0f - t : 0.0f};
    }
  }
  if (unweighted > 0)
    warnings_.push_back(std::to_string(unweighted) + " vertices have no bone weight: bound to the first joint");
}

// Vertex `v`'s weighted influences, strongest first (ties by bone id), one entry per joint; none when every weight
// is 0.
void IqmImport::skin_influences(std::uint32_t v, double weight_unit, std::vector<Influence>& influences) {
  std::array<std::pair<double, std::uint32_t>, 4> pairs{};
  double total = 0.0;
  for (std::uint32_t i = 0; i < 4; ++i) {
    const double joint = read(arrays_[blend_indexes], v, i);
    const double weight = read(arrays_[blend_weights], v, i) / weight_unit;
    const std::uint64_t at = arrays_[blend_weights].offset + std::uint64_t{v} * arrays_[blend_weights].size;
    if (!std::isfinite(weight) || weight < 0.0)
      file_.fail(at, "vertex " + std::to_string(v) + " BLENDWEIGHTS", "weight is negative or not finite");
    if (weight == 0.0) continue;
    if (!(joint >= 0.0) || joint >= h_.num_joints || joint != std::floor(joint))
      file_.fail(arrays_[blend_indexes].offset, "vertex " + std::to_string(v) + " BLENDINDEXES",
                 "joint " + std::to_string(joint) + " of a weighted influence is not one of the " +
                     std::to_string(h_.num_joints) + " joints");
    pairs[i] = {weight, static_cast<std::uint32_t>(joint)};
    total += weight;
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  for (const auto& [weight, joint] : pairs) {
    if (weight <= 0.0) continue;
    const auto bone = static_cast<std::uint16_t>(first_ + joint);
    bool merged = false;
    for (Influence& earlier : influences)
      if (earlier.bone == bone) {
        earlier.weight += static_cast<float>(weight / total);
        merged = true;
      }
    if (!merged) influences.push_back({bone, static_cast<float>(weight / total)});
  }
}

// --- the skin listing, and triangles per IQM mesh: render vertices are the mesh's vertices, IQM's clockwise front
// faces turned counter-clockwise ---
void IqmImport::add_triangles() {
  Mesh& mesh = result_.model.mesh;
  if (rigged_) {
    // One skin for the listing (ImportedModel::skins): the file's joints, every mesh (IQM skins them all).
    ImportedSkin listed;
    listed.joints = h_.num_joints;
    for (const Part& part : parts_)
      if (std::find(listed.meshes.begin(), listed.meshes.end(), part.name) == listed.meshes.end())
        listed.meshes.push_back(part.name);
    result_.skins.push_back(std::move(listed));
  }
  for (const Part& part : parts_) {
    Submesh submesh;
    submesh.first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
    submesh.material = part.material;
    const auto first_vertex = static_cast<std::uint32_t>(mesh.vertex_point.size());
    for (std::uint32_t v = part.first_vertex; v < part.first_vertex + part.num_vertexes; ++v) {
      mesh.vertex_point.push_back(point_of_vertex_[v]);
      mesh.vertex_normals.push_back(vertex_normal_[v]);
      if (!vertex_uv_.empty()) mesh.vertex_uvs.push_back(vertex_uv_[v]);
    }
    for (std::uint32_t t = part.first_triangle; t < part.first_triangle + part.num_triangles; ++t) {
      const std::uint64_t record = h_.ofs_triangles + std::uint64_t{12} * t;
      const std::string element = "triangles[" + std::to_string(t) + "]";
      std::array<std::uint32_t, 3> corner{};
      for (std::uint64_t c = 0; c < 3; ++c) {
        const std::uint32_t vertex = file_.u32(record + 4 * c, element);
        if (vertex < part.first_vertex || vertex - part.first_vertex >= part.num_vertexes)
          file_.fail(record + 4 * c, element,
                     "vertex " + std::to_string(vertex) + " is outside mesh '" + part.name + "' (vertices " +
                         std::to_string(part.first_vertex) + " to " +
                         std::to_string(std::uint64_t{part.first_vertex} + part.num_vertexes) + ")");
        corner[c] = first_vertex + (vertex - part.first_vertex);
      }
      mesh.triangles.insert(mesh.triangles.end(), {corner[0], corner[2], corner[1]});
    }
    submesh.triangle_count = static_cast<std::uint32_t>(mesh.triangle_count()) - submesh.first_triangle;
    mesh.submeshes.push_back(std::move(submesh));
    result_.submesh_names.push_back({part.name, part.name});
  }
  close_triangle_faces(mesh, path_);
}

// --- the poses clips read: a pose channel is offset + (masked ? frame value · scale : 0) ---
void IqmImport::read_poses() {
  if (h_.num_anims > 0 && h_.num_poses != h_.num_joints)
    file_.fail(76, hdr_,
               std::to_string(h_.num_poses) + " poses for " + std::to_string(h_.num_joints) +
                   " joints (animations need one pose per joint)");
  poses_.resize(h_.num_anims > 0 ? h_.num_poses : 0);
  std::uint64_t channels = 0;
  std::size_t pose_parents_differ = 0;
  for (std::uint32_t p = 0; p < poses_.size(); ++p) {
    const std::uint64_t record = h_.ofs_poses + std::uint64_t{88} * p;
    const std::string element = "poses[" + std::to_string(p) + "]";
    if (file_.i32(record, element) != joint_parent_[p] && !(file_.i32(record, element) < 0 && joint_parent_[p] < 0))
      ++pose_parents_differ;
    poses_[p].mask = file_.u32(record + 4, element) & 0x3ff;
    for (std::uint64_t c = 0; c < 10; ++c) {
      poses_[p].offset[c] = file_.f32(record + 8 + 4 * c, element);
      poses_[p].scale[c] = file_.f32(record + 48 + 4 * c, element);
    }
    channels += static_cast<std::uint64_t>(std::popcount(poses_[p].mask));
  }
  if (h_.num_anims > 0 && channels != h_.num_framechannels)
    file_.fail(h_.ofs_poses, "poses",
               "the channel masks select " + std::to_string(channels) + " channels, the header gives " +
                   std::to_string(h_.num_framechannels) + " per frame");
  channels_before_.assign(poses_.size(), 0);
  for (std::size_t p = 1; p < poses_.size(); ++p)
    channels_before_[p] = channels_before_[p - 1] + static_cast<std::uint64_t>(std::popcount(poses_[p - 1].mask));
  if (pose_parents_differ > 0)
    warnings_.push_back(std::to_string(pose_parents_differ) +
                        " poses name another parent than their joint: the joints' hierarchy is used");
}

// --- clips: each anim's frames, one channel per joint ---
void IqmImport::read_clip(std::uint32_t a, std::vector<std::string>& clip_names) {
  const std::uint64_t record = h_.ofs_anims + std::uint64_t{20} * a;
  const std::string element = "anims[" + std::to_string(a) + "]";
  Animation clip;
  const std::string name = text(file_.u32(record, element), record, element);
  const std::uint32_t first_frame = file_.u32(record + 4, element), frames = file_.u32(record + 8, element);
  double rate = std::bit_cast<float>(file_.u32(record + 12, element));
  const std::uint32_t flags = file_.u32(record + 16, element);
  if (std::uint64_t{first_frame} + frames > h_.num_frames)
    file_.fail(record + 4, element, "frames run past the file's " + std::to_string(h_.num_frames));
  clip.name = unique_clip_name(name, a, clip_names);
  if (!(rate > 0.0) || !std::isfinite(rate)) {
    rate = options_.default_ticks_per_second;
    warnings_.push_back("clip '" + clip.name + "': no frame rate in the file, " + std::to_string(rate) +
                        " frames per second assumed");
  }
  // Frame f is at f / rate. A clip the file marks as looping wraps from its last frame back to its first over one
  // more frame interval, so the first frame is repeated at the end.
  const bool wraps = (flags & anim_loop) != 0 && frames > 1;
  const std::uint32_t keys = frames + (wraps ? 1 : 0);
  clip.duration = frames == 0 ? 0.0f : static_cast<float>((keys - 1) / rate);
  clip.loop = options_.loop_clips;
  std::size_t scaled_bones = 0;
  for (std::uint32_t j = 0; j < h_.num_joints; ++j) {
    bool scaled = false;
    clip.channels.push_back(read_channel(j, first_frame, frames, keys, rate, element, scaled));
    if (scaled) ++scaled_bones;
  }
  add_clip(std::move(clip), 0, scaled_bones, bone_count_, path_, result_.clips, warnings_);
}

// Joint `j`'s channel over the keys of a clip. A bone's translation in skeleton space is its IQM translation times
// its parent's uniform bind scale (uniform scale commutes with rotation); scale keys are kept relative to the
// joint's own bind scale. `scaled`: whether the joint animates scale.
Channel IqmImport::read_channel(std::uint32_t j, std::uint32_t first_frame, std::uint32_t frames, std::uint32_t keys,
                                double rate, const std::string& element, bool& scaled) const {
  const float parent_scale =
      joint_parent_[j] < 0 ? 1.0f : bind_split_[first_ + static_cast<std::size_t>(joint_parent_[j])].scale;
  const PoseRecord& pose = poses_[j];
  Channel channel;
  channel.bone = static_cast<std::int32_t>(first_ + j);
  const bool moves_t = (pose.mask & 0x7) != 0, moves_r = (pose.mask & 0x78) != 0;
  const bool moves_s = (pose.mask & 0x380) != 0;
  const std::uint64_t before = channels_before_[j];
  for (std::uint32_t key = 0; key < std::max<std::uint32_t>(keys, 1); ++key) {
    const std::uint32_t f = frames == 0 ? 0 : first_frame + (key < frames ? key : 0);
    std::array<double, 10> value{};
    std::uint64_t at = h_.ofs_frames + (std::uint64_t{f} * h_.num_framechannels + before) * 2;
    for (int c = 0; c < 10; ++c) {
      value[static_cast<std::size_t>(c)] = pose.offset[static_cast<std::size_t>(c)];
      if (frames > 0 && (pose.mask >> c) & 1u) {
        value[static_cast<std::size_t>(c)] +=
            static_cast<double>(file_.u16(at)) * pose.scale[static_cast<std::size_t>(c)];
        at += 2;
      }
    }
    const float time = static_cast<float>(key / rate);
    if (key == 0 || moves_t) {
      channel.translation.times.push_back(time);
      channel.translation.values.push_back(parent_scale * glm::vec3(glm::dvec3(value[0], value[1], value[2])));
    }
    if (key == 0 || moves_r) {
      glm::dquat q(value[6], value[3], value[4], value[5]);
      const double length = glm::length(q);
      if (!(length > 1e-6) || !std::isfinite(length))
        file_.fail(h_.ofs_poses + std::uint64_t{88} * j, element + ": joint '" + joint_name_[j] + "'",
                   "rotation at frame " + std::to_string(f) + " has length 0");
      channel.rotation.times.push_back(time);
      channel.rotation.values.push_back(glm::quat(q / length));
    }
    const glm::dvec3 s(value[7], value[8], value[9]);
    const glm::dvec3 relative = s / joint_local_[j].scale;
    if ((key == 0 || moves_s) && finite(glm::vec3(relative))) {
      channel.scale.times.push_back(time);
      channel.scale.values.push_back(glm::vec3(relative));
    }
    scaled = scaled || glm::length(relative - glm::dvec3(1.0)) > 1e-3;
    if (frames == 0) break;
  }
  // Values must be finite for validate(); a frame value times a huge scale can overflow a float.
  for (const glm::vec3& t : channel.translation.values)
    if (!finite(t))
      file_.fail(h_.ofs_poses + std::uint64_t{88} * j, element + ": joint '" + joint_name_[j] + "'",
                 "a translation key is not finite");
  return channel;
}

}  // namespace

bool is_iqm_path(const std::string& path) {
  std::string extension = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".iqm";
}

ImportedModel import_iqm(const std::string& path, const ImportOptions& options) {
  return IqmImport(path, options).run();
}

}  // namespace deform::import_detail
