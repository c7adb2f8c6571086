// Wavefront OBJ reader: one pass over the text, std::from_chars and read_decimal for numbers, every index checked
// where it is read.
// Memory grows only with what the file holds (nothing is reserved from counts the file claims).
#include <algorithm>
#include <filesystem>
#include <unordered_map>
#include <unordered_set>

#include "deform/io/atomic_file.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
#include "obj_text.hpp"
#include "utf8_path.hpp"

namespace deform {
namespace {

using obj_text::Place;
using obj_text::Tokens;

constexpr std::uint32_t none = ~0u;

// How the corners of a face are written; every corner of one face uses the same form.
enum class CornerForm { position, position_uv, position_normal, position_uv_normal };

const char* form_text(CornerForm form) {
  switch (form) {
    case CornerForm::position: return "v";
    case CornerForm::position_uv: return "v/vt";
    case CornerForm::position_normal: return "v//vn";
    case CornerForm::position_uv_normal: return "v/vt/vn";
  }
  return "";
}

// The (o, g, usemtl) state a submesh is drawn with; material names are resolved once all MTL files are read.
struct SubmeshState {
  std::string object;
  std::string group;
  std::string material;
  std::int64_t material_line = 0;
};

class ObjParser {
 public:
  ObjParser(const std::string& name, const std::string& base_folder, Warnings* warnings, const ReferencePolicy& policy,
            ObjNames* names)
      : name_(name), base_folder_(base_folder), warnings_(warnings), policy_(policy), names_(names) {}

  Mesh parse(std::string_view text) {
    max_name_bytes_ = (std::size_t{64} << 20) + 4 * text.size();
    obj_text::LineReader lines(text);
    std::string_view statement;
    while (lines.next(statement)) {
      Tokens tokens(statement);
      std::string_view keyword;
      if (!tokens.next(keyword)) continue;
      const Place place{name_, lines.line()};
      if (keyword == "v") {
        read_position(tokens, place);
      } else if (keyword == "vt") {
        float uvw[3] = {};
        obj_text::parse_floats(tokens, uvw, 1, 3, place, "vt");
        uvs_.emplace_back(uvw[0], uvw[1]);
      } else if (keyword == "vn") {
        float xyz[3] = {};
        obj_text::parse_floats(tokens, xyz, 3, 3, place, "vn");
        normals_.emplace_back(xyz[0], xyz[1], xyz[2]);
      } else if (keyword == "f") {
        read_face(tokens, place);
      } else if (keyword == "o") {
        set_state(state_.object, tokens.rest());
      } else if (keyword == "g") {
        set_state(state_.group, tokens.rest());
      } else if (keyword == "usemtl") {
        if (tokens.rest().empty()) place.fail("usemtl", "missing material name");
        set_state(state_.material, tokens.rest());
        state_.material_line = place.line;
      } else if (keyword == "mtllib") {
        read_material_libraries(tokens, place);
      } else if (keyword != "s") {
        skipped_.add(keyword, place.line);
      }
    }
    skipped_.report(warnings_, name_);
    return finish();
  }

 private:
  void read_position(Tokens& tokens, const Place& place) {
    float xyzw_rgb[7] = {};  // x y z, then w and/or r g b (unused)
    obj_text::parse_floats(tokens, xyzw_rgb, 3, 7, place, "v");
    if (mesh_.positions.size() == none) place.fail("v", "too many vertices");
    mesh_.positions.emplace_back(xyzw_rgb[0], xyzw_rgb[1], xyzw_rgb[2]);
    first_vertex_of_point_.push_back(none);
    chain_length_.push_back(0);
  }

  // A 1-based or negative (relative) OBJ index into `count` elements, as a 0-based index.
  static std::uint32_t resolve_index(std::string_view token, std::size_t count, const char* kind, const Place& place,
                                     std::size_t corner) {
    const auto element = [corner] { return "f corner " + std::to_string(corner); };
    std::int64_t index = 0;
    const auto [stop, error] = std::from_chars(token.data(), token.data() + token.size(), index);
    if (error != std::errc() || stop != token.data() + token.size())
      index = obj_text::parse_integer(token, place, element());  // a leading '+', or the error
    const auto available = static_cast<std::int64_t>(count);
    if (index == 0) place.fail(element(), std::string(kind) + " index 0 (OBJ indices start at 1, or -1 for the last)");
    if (index > available || index < -available)
      place.fail(element(), std::string(kind) + " index " + std::to_string(index) +
                                " is out of range: " + std::to_string(count) + " `" + kind + "` above this line");
    return static_cast<std::uint32_t>(index > 0 ? index - 1 : available + index);
  }

  void read_face(Tokens& tokens, const Place& place) {
    face_.clear();
    CornerForm face_form = CornerForm::position;
    std::string_view corner;
    while (tokens.next(corner)) {
      const std::size_t number = face_.size() + 1;
      const auto fail = [&](std::string message) { place.fail("f corner " + std::to_string(number), message); };
      constexpr auto npos = std::string_view::npos;
      const std::size_t slash1 = corner.find('/');
      const std::size_t slash2 = slash1 == npos ? npos : corner.find('/', slash1 + 1);
      if (slash2 != npos && corner.find('/', slash2 + 1) != npos) fail("malformed corner " + obj_text::quoted(corner));
      const std::string_view v = corner.substr(0, slash1);
      std::string_view vt, vn;
      if (slash1 != npos) vt = corner.substr(slash1 + 1, slash2 == npos ? npos : slash2 - slash1 - 1);
      if (slash2 != npos) vn = corner.substr(slash2 + 1);
      CornerForm form = CornerForm::position;
      if (slash2 != npos) form = vt.empty() ? CornerForm::position_normal : CornerForm::position_uv_normal;
      else if (slash1 != npos) form = CornerForm::position_uv;
      if (v.empty() || (slash1 != npos && slash2 == npos && vt.empty()) || (slash2 != npos && vn.empty()))
        fail("malformed corner " + obj_text::quoted(corner));
      if (face_.empty()) face_form = form;
      else if (form != face_form)
        fail(std::string("corner form ") + form_text(form) + " mixed with " + form_text(face_form) + " in one face");

      const std::uint32_t point = resolve_index(v, mesh_.positions.size(), "v", place, number);
      const std::uint32_t uv = vt.empty() ? none : resolve_index(vt, uvs_.size(), "vt", place, number);
      const std::uint32_t normal = vn.empty() ? none : resolve_index(vn, normals_.size(), "vn", place, number);
      face_.push_back(render_vertex(point, uv, normal));
    }
    if (face_.size() < 3) place.fail("f", "a face needs at least 3 corners, found " + std::to_string(face_.size()));
    if (face_.size() > none / 3 || mesh_.face_corners.size() > none - face_.size())
      place.fail("f", "too many face corners");

    if (state_changed_ || mesh_.submeshes.empty()) start_submesh(place);
    mesh_.face_sizes.push_back(static_cast<std::uint32_t>(face_.size()));
    mesh_.face_corners.insert(mesh_.face_corners.end(), face_.begin(), face_.end());
    for (std::size_t i = 1; i + 1 < face_.size(); ++i)
      mesh_.triangles.insert(mesh_.triangles.end(), {face_[0], face_[i], face_[i + 1]});
    mesh_.submeshes.back().triangle_count += static_cast<std::uint32_t>(face_.size() - 2);
  }

  // The render vertex of a (v, vt, vn) triple, created at first use. The vertices of one point are chained, and a
  // point rarely has more than a few, so the search is short; a point with more than `long_chain` (a hostile file:
  // one point used with 200,000 different `vt`) is looked up in a hash map instead, so reading stays linear.
  std::uint32_t render_vertex(std::uint32_t point, std::uint32_t uv, std::uint32_t normal) {
    constexpr std::uint8_t long_chain = 16;
    const Triple key{point, uv, normal};
    if (chain_length_[point] < long_chain) {
      for (std::uint32_t r = first_vertex_of_point_[point]; r != none; r = next_vertex_of_point_[r])
        if (vertex_uv_[r] == uv && vertex_normal_[r] == normal) return r;
    } else if (const auto found = long_chains_.find(key); found != long_chains_.end()) {
      return found->second;
    }
    const auto r = static_cast<std::uint32_t>(mesh_.vertex_point.size());
    mesh_.vertex_point.push_back(point);
    vertex_uv_.push_back(uv);
    vertex_normal_.push_back(normal);
    next_vertex_of_point_.push_back(first_vertex_of_point_[point]);
    first_vertex_of_point_[point] = r;
    if (chain_length_[point] < long_chain && ++chain_length_[point] == long_chain) {
      for (std::uint32_t v = r; v != none; v = next_vertex_of_point_[v])
        long_chains_.emplace(Triple{point, vertex_uv_[v], vertex_normal_[v]}, v);
    } else if (chain_length_[point] == long_chain) {
      long_chains_.emplace(key, r);
    }
    return r;
  }

  void set_state(std::string& field, std::string_view value) {
    if (field == value) return;
    field.assign(value);
    state_changed_ = true;
  }

  void start_submesh(const Place& place) {
    state_changed_ = false;
    if (!mesh_.submeshes.empty()) {
      const SubmeshState& last = submesh_states_.back();
      if (last.object == state_.object && last.group == state_.group && last.material == state_.material) return;
    }
    // Each submesh copies the names in effect: a long name kept while the material alternates would copy it for every
    // face (a 4 MB file asking for gigabytes). The copies are bounded by a multiple of the file's size.
    name_bytes_ += 2 * (state_.object.size() + state_.group.size()) + state_.material.size();
    if (name_bytes_ > max_name_bytes_)
      place.fail("f", "the names in effect are copied into more submeshes than the file's size allows (" +
                          std::to_string(max_name_bytes_) + " bytes of names)");
    Submesh& submesh = mesh_.submeshes.emplace_back();
    submesh.first_triangle = static_cast<std::uint32_t>(mesh_.triangle_count());
    submesh_states_.push_back(state_);
    if (names_) names_->submeshes.push_back({state_.object, state_.group});
  }

  // `mtllib a.mtl b.mtl`; a single name with blanks is taken whole when such a file exists inside the model's folder
  // (or an allowed one): whether a file outside exists changes nothing.
  void read_material_libraries(Tokens& tokens, const Place& place) {
    const std::string_view whole = tokens.rest();
    if (whole.empty()) place.fail("mtllib", "missing file name");
    std::string whole_path;
    try {
      whole_path =
          resolve_referenced_file_in(base_folder_, name_, whole, "mtllib", policy_, ReferenceSyntax::path, place.line);
    } catch (const Error&) {
      whole_path.clear();  // refused as a whole: each name is resolved (and refused) on its own below
    }
    std::error_code error;
    if (!whole_path.empty() && std::filesystem::is_regular_file(utf8_path::from_utf8(whole_path), error)) {
      read_material_library(whole, place);
      return;
    }
    std::string_view file;
    while (tokens.next(file)) read_material_library(file, place);
  }

  // One MTL file, confined to the model's folder (resolve_referenced_file): a file outside is refused before it is
  // opened, so nothing of it (not a line, not its size) reaches a message.
  void read_material_library(std::string_view file, const Place& place) {
    const std::string real =
        resolve_referenced_file_in(base_folder_, name_, file, "mtllib", policy_, ReferenceSyntax::path, place.line);
    const std::string path = obj_text::resolve_path(base_folder_, file);
    std::error_code error;
    if (!std::filesystem::is_regular_file(utf8_path::from_utf8(real), error)) {
      obj_text::warn(warnings_, name_, place.line,
                     "MTL file " + obj_text::quoted(file) + " not found (looked for '" + path + "')");
      return;
    }
    // Each MTL file is read once, however often the OBJ names it (a hostile file names one 20,000 times).
    if (std::find(read_libraries_.begin(), read_libraries_.end(), real) != read_libraries_.end()) return;
    read_libraries_.push_back(real);
    if (names_) names_->material_libraries.push_back(path);
    const std::string folder = utf8_path::generic_utf8(utf8_path::from_utf8(path).parent_path());
    for (Material& material : obj_text::parse_mtl_confined(read_file_text(real), path, folder.empty() ? "." : folder,
                                                           base_folder_, warnings_, policy_)) {
      if (material_index_.contains(material.name)) {
        obj_text::warn(warnings_, name_, place.line,
                       "material " + obj_text::quoted(material.name) + " defined again in '" + path +
                           "': the first definition is used");
        continue;
      }
      material_index_.emplace(material.name, static_cast<std::int32_t>(mesh_.materials.size()));
      mesh_.materials.push_back(std::move(material));
    }
  }

  Mesh finish() {
    std::unordered_set<std::string> unknown;
    for (std::size_t s = 0; s < mesh_.submeshes.size(); ++s) {
      const SubmeshState& state = submesh_states_[s];
      if (state.material.empty()) continue;
      if (const auto found = material_index_.find(state.material); found != material_index_.end())
        mesh_.submeshes[s].material = found->second;
      else if (unknown.insert(state.material).second)
        obj_text::warn(warnings_, name_, state.material_line,
                       "material " + obj_text::quoted(state.material) + " is not defined: default material used");
    }

    const std::size_t vertex_count = mesh_.vertex_count();
    bool any_uv = false, all_normals = true;
    for (std::size_t r = 0; r < vertex_count; ++r) {
      any_uv = any_uv || vertex_uv_[r] != none;
      all_normals = all_normals && vertex_normal_[r] != none;
    }
    if (any_uv) {
      mesh_.vertex_uvs.resize(vertex_count, glm::vec2(0.0f));
      for (std::size_t r = 0; r < vertex_count; ++r)
        if (vertex_uv_[r] != none) mesh_.vertex_uvs[r] = uvs_[vertex_uv_[r]];
    }
    mesh_.vertex_normals.resize(vertex_count);
    if (!all_normals) {
      std::vector<glm::vec3> scratch(mesh_.point_count());
      compute_vertex_normals(mesh_, mesh_.positions, scratch, mesh_.vertex_normals);
    }
    for (std::size_t r = 0; r < vertex_count; ++r)
      if (vertex_normal_[r] != none) mesh_.vertex_normals[r] = normals_[vertex_normal_[r]];
    return std::move(mesh_);
  }

  const std::string& name_;
  const std::string& base_folder_;
  Warnings* warnings_;
  const ReferencePolicy& policy_;
  ObjNames* names_;                          // null: the caller keeps no names
  std::vector<std::string> read_libraries_;  // canonical paths of the MTL files read
  Mesh mesh_;

  std::vector<glm::vec2> uvs_;      // the file's `vt`
  std::vector<glm::vec3> normals_;  // the file's `vn`
  // Per render vertex: its vt and vn (`none` if the corner had none) and the next render vertex of the same point.
  std::vector<std::uint32_t> vertex_uv_, vertex_normal_, next_vertex_of_point_;
  std::vector<std::uint32_t> first_vertex_of_point_;  // per point, `none` until a face uses it
  std::vector<std::uint8_t> chain_length_;            // per point, its render vertex count up to `long_chain`
  struct Triple {
    std::uint32_t point, uv, normal;
    bool operator==(const Triple&) const = default;
  };
  struct TripleHash {
    std::size_t operator()(const Triple& t) const noexcept {
      return std::hash<std::uint64_t>()((std::uint64_t(t.point) << 32 | t.uv) ^
                                        (std::uint64_t(t.normal) * 0x9e3779b97f4a7c15ull));
    }
  };
  std::unordered_map<Triple, std::uint32_t, TripleHash> long_chains_;  // render vertices of points with long chains
  std::vector<std::uint32_t> face_;                                    // render vertices of the face being read

  SubmeshState state_;
  bool state_changed_ = false;
  std::size_t name_bytes_ = 0;                // bytes of names copied into submeshes so far
  std::size_t max_name_bytes_ = 0;            // 64 MiB + 4 × the file's size
  std::vector<SubmeshState> submesh_states_;  // one per submesh
  std::unordered_map<std::string, std::int32_t> material_index_;
  obj_text::SkippedStatements skipped_;
};

}  // namespace

Mesh parse_obj(std::string_view text, const std::string& name, const std::string& base_folder, Warnings* warnings,
               const ReferencePolicy& policy, ObjNames* names) {
  if (names) *names = {};
  return ObjParser(name, base_folder, warnings, policy, names).parse(text);
}

Mesh read_obj(const std::string& path, Warnings* warnings, const ReferencePolicy& policy, ObjNames* names) {
  const std::string text = read_file_text(path);
  const std::string folder = utf8_path::generic_utf8(utf8_path::from_utf8(path).parent_path());
  return parse_obj(text, path, folder.empty() ? "." : folder, warnings, policy, names);
}

}  // namespace deform
