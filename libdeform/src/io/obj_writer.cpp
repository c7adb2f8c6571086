// Wavefront OBJ and MTL writers: the input's points and faces in their order, numbers in shortest round-trip form.
#include <charconv>
#include <cmath>
#include <filesystem>
#include <string>
#include <unordered_set>
#include <vector>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
#include "float_text.hpp"
#include "utf8_path.hpp"
namespace deform {
namespace {

void append_number(std::string& out, float value) {
  out.push_back(' ');
  detail::append_shortest(out, value);
}

void append_index(std::string& out, std::uint64_t one_based) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, one_based);
  out.append(buffer, result.ptr);
}

template <int N>
void append_line(std::string& out, const char* keyword, const glm::vec<N, float>& v) {
  out.append(keyword);
  for (int i = 0; i < N; ++i) append_number(out, v[i]);
  out.push_back('\n');
}

void append_statement(std::string& out, std::string_view keyword, std::string_view name) {
  out.append(keyword).push_back(' ');
  out.append(obj_safe_name(name));
  out.push_back('\n');
}

}  // namespace

std::string obj_safe_name(std::string_view name) {
  // The reader takes a name as the rest of its line with blanks trimmed, after cutting at '#' and joining a line whose
  // last non-blank byte is '\\' to the next. So every byte that would end the line or start a comment (control
  // characters, DEL, '#'), every blank at either end (only ' ' is left: the other blanks are control characters) and
  // a final backslash become '_'; the rest, including invalid UTF-8, is kept. A name the reader can read is unchanged.
  std::string safe(name);
  for (char& c : safe) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f || c == '#') c = '_';
  }
  for (std::size_t i = 0; i < safe.size() && safe[i] == ' '; ++i) safe[i] = '_';
  for (std::size_t i = safe.size(); i > 0 && safe[i - 1] == ' '; --i) safe[i - 1] = '_';
  if (!safe.empty() && safe.back() == '\\') safe.back() = '_';
  return safe;
}

std::vector<std::string> obj_material_names(std::span<const Material> materials) {
  // Each name made safe, an empty one "_" (`usemtl` and `newmtl` need a name); a name taken by an earlier material
  // gets "_2", "_3", ... (never a name another material has), so that every `usemtl` finds its own `newmtl`.
  std::vector<std::string> base(materials.size());
  std::unordered_set<std::string> natural;
  for (std::size_t m = 0; m < materials.size(); ++m) {
    base[m] = obj_safe_name(materials[m].name);
    if (base[m].empty()) base[m] = "_";
    natural.insert(base[m]);
  }
  std::unordered_set<std::string> taken;
  std::vector<std::string> names(materials.size());
  for (std::size_t m = 0; m < materials.size(); ++m) {
    std::string name = base[m];
    std::size_t n = 1;
    while (taken.contains(name) || (n > 1 && natural.contains(name))) name = base[m] + "_" + std::to_string(++n);
    taken.insert(name);
    names[m] = std::move(name);
  }
  return names;
}

std::string format_obj(const Mesh& mesh, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                       const ObjWriteOptions& options) {
  if (positions.size() != mesh.point_count())
    throw Error::invalid_argument("positions", std::to_string(positions.size()) + " positions for " +
                                                   std::to_string(mesh.point_count()) + " points");
  // Nothing non-finite is ever written: a NaN in an output file is a silent corruption downstream.
  for (std::size_t p = 0; p < positions.size(); ++p)
    if (!std::isfinite(positions[p].x) || !std::isfinite(positions[p].y) || !std::isfinite(positions[p].z))
      throw Error::invalid_argument("vertex " + std::to_string(p), "position is not finite (not written)");
  if (normals.empty()) normals = mesh.vertex_normals;
  const bool write_normals = options.write_normals && mesh.vertex_count() > 0;
  const bool write_uvs = options.write_uvs && !mesh.vertex_uvs.empty();
  if (write_normals && normals.size() != mesh.vertex_count())
    throw Error::invalid_argument("normals", std::to_string(normals.size()) + " normals for " +
                                                 std::to_string(mesh.vertex_count()) + " render vertices");
  if (write_normals)
    for (std::size_t r = 0; r < normals.size(); ++r)
      if (!std::isfinite(normals[r].x) || !std::isfinite(normals[r].y) || !std::isfinite(normals[r].z))
        throw Error::invalid_argument("render vertex " + std::to_string(r), "normal is not finite (not written)");
  if (write_uvs && mesh.vertex_uvs.size() != mesh.vertex_count())
    throw Error::invalid_argument("mesh", "vertex_uvs does not have one entry per render vertex");
  if (!options.submesh_names.empty() && options.submesh_names.size() != mesh.submeshes.size())
    throw Error::invalid_argument("submesh_names", std::to_string(options.submesh_names.size()) + " names for " +
                                                       std::to_string(mesh.submeshes.size()) + " submeshes");

  std::string out;
  if (!options.mtllib.empty()) append_statement(out, "mtllib", options.mtllib);
  const std::vector<std::string> material_names = obj_material_names(mesh.materials);
  for (const glm::vec3& p : positions) append_line(out, "v", p);
  if (write_uvs)
    for (const glm::vec2& uv : mesh.vertex_uvs) append_line(out, "vt", uv);
  if (write_normals)
    for (const glm::vec3& n : normals) append_line(out, "vn", n);

  std::size_t corner = 0, triangle = 0, next_submesh = 0;
  const Submesh* current = nullptr;
  const ObjSubmeshNames no_names;  // where options.submesh_names is empty: no `o` or `g` is written
  const ObjSubmeshNames* current_names = nullptr;
  for (const std::uint32_t size : mesh.face_sizes) {
    while (next_submesh < mesh.submeshes.size() && mesh.submeshes[next_submesh].first_triangle <= triangle) {
      const std::size_t s = next_submesh++;
      const Submesh& submesh = mesh.submeshes[s];
      if (submesh.triangle_count == 0) continue;
      const ObjSubmeshNames& names = options.submesh_names.empty() ? no_names : options.submesh_names[s];
      if (current ? names.object != current_names->object : !names.object.empty())
        append_statement(out, "o", names.object);
      if (current ? names.group != current_names->group : !names.group.empty()) append_statement(out, "g", names.group);
      if (!options.mtllib.empty() && (current ? submesh.material != current->material : submesh.material >= 0)) {
        const bool named = submesh.material >= 0 && std::size_t(submesh.material) < mesh.materials.size();
        append_statement(out, "usemtl",
                         named ? std::string_view(material_names[std::size_t(submesh.material)]) : "default");
      }
      current = &submesh;
      current_names = &names;
    }
    if (corner + size > mesh.face_corners.size())
      throw Error::invalid_argument("mesh", "face_sizes needs more corners than face_corners holds");
    out.push_back('f');
    for (std::uint32_t i = 0; i < size; ++i) {
      const std::uint32_t vertex = mesh.face_corners[corner + i];
      if (vertex >= mesh.vertex_count() || mesh.vertex_point[vertex] >= mesh.point_count())
        throw Error::invalid_argument("mesh", "face corner index out of range");
      out.push_back(' ');
      append_index(out, std::uint64_t(mesh.vertex_point[vertex]) + 1);
      if (write_uvs || write_normals) out.push_back('/');
      if (write_uvs) append_index(out, std::uint64_t(vertex) + 1);
      if (write_normals) {
        out.push_back('/');
        append_index(out, std::uint64_t(vertex) + 1);
      }
    }
    out.push_back('\n');
    corner += size;
    triangle += size >= 2 ? size - 2 : 0;
  }
  return out;
}

void write_obj(const std::string& path, const Mesh& mesh, std::span<const glm::vec3> positions,
               std::span<const glm::vec3> normals, const ObjWriteOptions& options) {
  write_file_atomic(path, format_obj(mesh, positions, normals, options));
}

std::string material_libraries_for(const ObjNames& names, const std::string& obj_path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path folder = fs::absolute(utf8_path::from_utf8(obj_path), error).lexically_normal().parent_path();
  std::string out;
  for (const std::string& library : names.material_libraries) {
    const fs::path absolute = fs::absolute(utf8_path::from_utf8(library), error).lexically_normal();
    fs::path relative = absolute.lexically_relative(folder);
    if (relative.empty()) relative = absolute;  // another root: no relative path exists
    if (!out.empty()) out.push_back(' ');
    out.append(utf8_path::generic_utf8(relative));
  }
  return out;
}

std::string format_mtl(std::span<const Material> materials) {
  std::string out;
  const std::vector<std::string> names = obj_material_names(materials);
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const Material& material = materials[m];
    append_statement(out, "newmtl", names[m]);
    append_line(out, "Ka", material.ambient);
    append_line(out, "Kd", material.diffuse);
    append_line(out, "Ks", material.specular);
    out.append("d");
    append_number(out, material.opacity);
    out.append("\nNs");
    append_number(out, material.shininess);
    out.append("\nillum ").append(std::to_string(material.illum)).push_back('\n');
    if (!material.diffuse_map.empty()) append_statement(out, "map_Kd", material.diffuse_map);
    out.push_back('\n');
  }
  return out;
}

}  // namespace deform
