// An ImportedModel as bytes and back (wire.hpp): little-endian as the machine is, one process to another.
#include "wire.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "deform/runtime/error.hpp"

namespace deform::wire {
namespace {

constexpr char magic[8] = {'D', 'F', 'I', 'M', 'P', 'O', 'R', 'T'};
// 2: extra influences, morph targets and channels; 3: skins; 4: embedded images; 5: submesh names beside the mesh
// (ImportedModel::submesh_names), no MTL file list
constexpr std::uint32_t version = 5;

class Writer {
 public:
  template <class T>
  void raw(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void count(std::size_t n) { raw(static_cast<std::uint64_t>(n)); }
  void text(const std::string& s) {
    count(s.size());
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  template <class T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    count(v.size());
    const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }
  template <class T>
  void track(const Track<T>& t) {
    raw(t.interpolation);
    array(t.times);
    array(t.values);
    array(t.in_tangents);
    array(t.out_tangents);
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& bytes, const std::string& source) : bytes_(bytes), source_(source) {}

  template <class T>
  T raw() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  // A count of elements of `size` bytes each, checked against what is left before anything is allocated.
  std::size_t count(std::size_t size) {
    const auto n = raw<std::uint64_t>();
    if (size > 0 && n > (bytes_.size() - at_) / size) fail("a count overruns the data");
    return static_cast<std::size_t>(n);
  }
  std::string text() {
    const std::size_t n = count(1);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), n);
    at_ += n;
    return s;
  }
  template <class T>
  std::vector<T> array() {
    const std::size_t n = count(sizeof(T));
    std::vector<T> v(n);
    if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return v;
  }
  template <class T>
  Track<T> track() {
    Track<T> t;
    const auto interpolation = raw<std::uint8_t>();
    if (interpolation > static_cast<std::uint8_t>(Interpolation::cubic_spline)) fail("unknown interpolation");
    t.interpolation = static_cast<Interpolation>(interpolation);
    t.times = array<float>();
    t.values = array<T>();
    t.in_tangents = array<T>();
    t.out_tangents = array<T>();
    return t;
  }
  bool done() const noexcept { return at_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error::at_byte(source_, static_cast<std::int64_t>(at_), "", "the importer's answer is malformed: " + what);
  }

 private:
  void need(std::size_t n) const {
    if (bytes_.size() - at_ < n) fail("cut short");
  }
  const std::vector<std::uint8_t>& bytes_;
  const std::string& source_;
  std::size_t at_ = 0;
};

}  // namespace

std::vector<std::uint8_t> encode(const ImportedModel& imported) {
  Writer w;
  w.raw(magic);
  w.raw(version);
  const Model& model = imported.model;
  w.text(model.name);
  const Mesh& mesh = model.mesh;
  w.array(mesh.positions);
  w.array(mesh.vertex_point);
  w.array(mesh.vertex_normals);
  w.array(mesh.vertex_uvs);
  w.array(mesh.triangles);
  w.count(mesh.submeshes.size());
  for (const Submesh& s : mesh.submeshes) {
    w.raw(s.first_triangle), w.raw(s.triangle_count), w.raw(s.material);
  }
  w.count(mesh.materials.size());
  for (const Material& m : mesh.materials) {
    w.text(m.name);
    w.raw(m.ambient), w.raw(m.diffuse), w.raw(m.specular), w.raw(m.opacity), w.raw(m.shininess), w.raw(m.illum);
    w.text(m.diffuse_map);
    w.array(m.diffuse_image ? *m.diffuse_image : std::vector<std::uint8_t>{});
  }
  w.array(mesh.face_sizes);
  w.array(mesh.face_corners);
  w.count(model.skeleton.bone_count());
  for (const Bone& b : model.skeleton.bones()) {
    w.text(b.name);
    w.raw(b.parent);
    w.array(b.children);
    w.raw(b.bind_translation), w.raw(b.bind_rotation), w.raw(b.limits.min), w.raw(b.limits.max);
  }
  w.array(model.weights.bones);
  w.array(model.weights.weights);
  w.array(model.weights.extra_points);
  w.array(model.weights.extra_offsets);
  w.array(model.weights.extra_bones);
  w.array(model.weights.extra_weights);
  w.count(model.morph_targets.size());
  for (const MorphTarget& t : model.morph_targets) {
    w.text(t.name), w.text(t.mesh);
    w.raw(t.default_weight);
    w.array(t.points), w.array(t.position_deltas), w.array(t.normal_deltas);
  }
  w.count(imported.clips.size());
  for (const Animation& clip : imported.clips) {
    w.text(clip.name);
    w.raw(clip.duration);
    w.raw(static_cast<std::uint8_t>(clip.loop));
    w.count(clip.channels.size());
    for (const Channel& c : clip.channels) {
      w.raw(c.bone);
      w.track(c.translation);
      w.track(c.rotation);
      w.track(c.scale);
    }
    w.count(clip.morph_channels.size());
    for (const MorphChannel& m : clip.morph_channels) {
      w.raw(m.target);
      w.track(m.weight);
    }
  }
  w.count(imported.warnings.size());
  for (const std::string& warning : imported.warnings) w.text(warning);
  w.raw(static_cast<std::uint8_t>(imported.rigged));
  w.array(imported.file_bind_world);
  w.raw(imported.up);
  w.count(imported.skins.size());
  for (const ImportedSkin& skin : imported.skins) {
    w.text(skin.name);
    w.count(skin.joints);
    w.count(skin.meshes.size());
    for (const std::string& name : skin.meshes) w.text(name);
  }
  w.count(imported.submesh_names.size());
  for (const ObjSubmeshNames& names : imported.submesh_names) w.text(names.object), w.text(names.group);
  return std::move(w.bytes);
}

ImportedModel decode(const std::vector<std::uint8_t>& bytes, const std::string& source) {
  Reader r(bytes, source);
  const auto head = r.raw<std::array<char, 8>>();
  if (std::memcmp(head.data(), magic, sizeof magic) != 0) r.fail("no magic");
  if (r.raw<std::uint32_t>() != version) r.fail("the importer process is another version of libdeform");
  ImportedModel imported;
  Model& model = imported.model;
  model.name = r.text();
  Mesh& mesh = model.mesh;
  mesh.positions = r.array<glm::vec3>();
  mesh.vertex_point = r.array<std::uint32_t>();
  mesh.vertex_normals = r.array<glm::vec3>();
  mesh.vertex_uvs = r.array<glm::vec2>();
  mesh.triangles = r.array<std::uint32_t>();
  mesh.submeshes.resize(r.count(3 * sizeof(std::uint32_t)));
  for (Submesh& s : mesh.submeshes) {
    s.first_triangle = r.raw<std::uint32_t>(), s.triangle_count = r.raw<std::uint32_t>();
    s.material = r.raw<std::int32_t>();
  }
  mesh.materials.resize(r.count(8 + 3 * sizeof(glm::vec3)));
  for (Material& m : mesh.materials) {
    m.name = r.text();
    m.ambient = r.raw<glm::vec3>(), m.diffuse = r.raw<glm::vec3>(), m.specular = r.raw<glm::vec3>();
    m.opacity = r.raw<float>(), m.shininess = r.raw<float>(), m.illum = r.raw<int>();
    m.diffuse_map = r.text();
    std::vector<std::uint8_t> image = r.array<std::uint8_t>();
    if (!image.empty()) m.diffuse_image = std::make_shared<const std::vector<std::uint8_t>>(std::move(image));
  }
  mesh.face_sizes = r.array<std::uint32_t>();
  mesh.face_corners = r.array<std::uint32_t>();
  std::vector<Bone> bones(r.count(8 + sizeof(std::int32_t) + 8));
  for (Bone& b : bones) {
    b.name = r.text();
    b.parent = r.raw<std::int32_t>();
    b.children = r.array<std::int32_t>();
    b.bind_translation = r.raw<glm::vec3>(), b.bind_rotation = r.raw<glm::vec3>();
    b.limits.min = r.raw<glm::vec3>(), b.limits.max = r.raw<glm::vec3>();
  }
  model.skeleton = Skeleton(std::move(bones), source);  // validates the hierarchy
  model.weights.bones = r.array<glm::u16vec4>();
  model.weights.weights = r.array<glm::vec4>();
  model.weights.extra_points = r.array<std::uint32_t>();
  model.weights.extra_offsets = r.array<std::uint32_t>();
  model.weights.extra_bones = r.array<std::uint16_t>();
  model.weights.extra_weights = r.array<float>();
  model.morph_targets.resize(r.count(8 + 8 + sizeof(float) + 3 * 8));
  for (MorphTarget& t : model.morph_targets) {
    t.name = r.text(), t.mesh = r.text();
    t.default_weight = r.raw<float>();
    t.points = r.array<std::uint32_t>();
    t.position_deltas = r.array<glm::vec3>();
    t.normal_deltas = r.array<glm::vec3>();
  }
  imported.clips.resize(r.count(8 + sizeof(float) + 1 + 8));
  for (Animation& clip : imported.clips) {
    clip.name = r.text();
    clip.duration = r.raw<float>();
    clip.loop = r.raw<std::uint8_t>() != 0;
    clip.channels.resize(r.count(sizeof(std::int32_t) + 3 * (1 + 4 * 8)));
    for (Channel& c : clip.channels) {
      c.bone = r.raw<std::int32_t>();
      c.translation = r.track<glm::vec3>();
      c.rotation = r.track<glm::quat>();
      c.scale = r.track<glm::vec3>();
    }
    clip.morph_channels.resize(r.count(sizeof(std::int32_t) + 1 + 4 * 8));
    for (MorphChannel& m : clip.morph_channels) {
      m.target = r.raw<std::int32_t>();
      m.weight = r.track<float>();
      if (m.target < 0 || static_cast<std::size_t>(m.target) >= model.morph_targets.size())
        r.fail("a morph channel names a target out of range");
    }
    clip.require_valid(model.skeleton.bone_count(), source);
  }
  imported.warnings.resize(r.count(8));
  for (std::string& warning : imported.warnings) warning = r.text();
  imported.rigged = r.raw<std::uint8_t>() != 0;
  imported.file_bind_world = r.array<glm::mat4>();
  imported.up = r.raw<glm::vec3>();
  imported.skins.resize(r.count(3 * 8));
  for (ImportedSkin& skin : imported.skins) {
    skin.name = r.text();
    skin.joints = r.count(0);
    skin.meshes.resize(r.count(8));
    for (std::string& name : skin.meshes) name = r.text();
  }
  imported.submesh_names.resize(r.count(16));
  for (ObjSubmeshNames& names : imported.submesh_names) names.object = r.text(), names.group = r.text();
  if (!r.done()) r.fail("trailing bytes");

  // What the rest of libdeform relies on: indices in range, one weight entry per point, finite numbers.
  const std::size_t points = mesh.positions.size(), vertices = mesh.vertex_point.size();
  for (std::uint32_t p : mesh.vertex_point)
    if (p >= points) r.fail("a render vertex names a point out of range");
  for (std::uint32_t v : mesh.triangles)
    if (v >= vertices) r.fail("a triangle names a render vertex out of range");
  if (mesh.triangles.size() % 3 != 0) r.fail("triangle indices are not a multiple of 3");
  if (mesh.vertex_normals.size() != vertices || (!mesh.vertex_uvs.empty() && mesh.vertex_uvs.size() != vertices))
    r.fail("per-vertex attributes do not match the render vertices");
  for (const Submesh& s : mesh.submeshes)
    if (std::uint64_t(s.first_triangle) + s.triangle_count > mesh.triangle_count() || s.material < -1 ||
        s.material >= static_cast<std::int64_t>(mesh.materials.size()))
      r.fail("a submesh is out of range");
  if (!imported.submesh_names.empty() && imported.submesh_names.size() != mesh.submeshes.size())
    r.fail("the submesh names do not match the submeshes");
  if (model.weights.bones.size() != points || model.weights.weights.size() != points)
    r.fail("skin weights do not match the points");
  for (const glm::u16vec4& ids : model.weights.bones)
    for (int k = 0; k < 4; ++k)
      if (ids[k] >= model.skeleton.bone_count()) r.fail("a skin weight names a bone out of range");
  for (const glm::vec3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) r.fail("a position is not finite");
  // The extra influences as SkinningJob::validate wants them (sizes, order, bones); morph targets as MorphJob does.
  const SkinWeights& sw = model.weights;
  if (sw.extra_points.empty()
          ? !(sw.extra_offsets.empty() && sw.extra_bones.empty() && sw.extra_weights.empty())
          : sw.extra_offsets.size() != sw.extra_points.size() + 1 || sw.extra_offsets.front() != 0 ||
                sw.extra_offsets.back() != sw.extra_bones.size() || sw.extra_bones.size() != sw.extra_weights.size())
    r.fail("extra influences are inconsistent");
  for (std::size_t j = 0; j < sw.extra_points.size(); ++j)
    if (sw.extra_points[j] >= points || (j > 0 && sw.extra_points[j] <= sw.extra_points[j - 1]) ||
        sw.extra_offsets[j + 1] < sw.extra_offsets[j])
      r.fail("extra influences are inconsistent");
  for (std::size_t e = 0; e < sw.extra_bones.size(); ++e)
    if (sw.extra_bones[e] >= model.skeleton.bone_count() || !(sw.extra_weights[e] >= 0.0f) ||
        !std::isfinite(sw.extra_weights[e]))
      r.fail("an extra influence is out of range");
  require_valid_morph_targets(model.morph_targets, points, source);
  return imported;
}

}  // namespace deform::wire
