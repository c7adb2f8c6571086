// Wavefront OBJ and MTL writers: the input's points and faces in their order, numbers in shortest round-trip form.
#include <charconv>
#include <filesystem>
#include <stdexcept>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
#include "float_text.hpp"
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

}  // namespace

std::string format_obj(const Mesh& mesh, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                       const ObjWriteOptions& options) {
  if (positions.size() != mesh.point_count())
    throw std::invalid_argument("format_obj: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(mesh.point_count()) + " points");
  if (normals.empty()) normals = mesh.vertex_normals;
  const bool write_normals = options.write_normals && mesh.vertex_count() > 0;
  const bool write_uvs = options.write_uvs && !mesh.vertex_uvs.empty();
  if (write_normals && normals.size() != mesh.vertex_count())
    throw std::invalid_argument("format_obj: " + std::to_string(normals.size()) + " normals for " +
                                std::to_string(mesh.vertex_count()) + " render vertices");
  if (write_uvs && mesh.vertex_uvs.size() != mesh.vertex_count())
    throw std::invalid_argument("format_obj: vertex_uvs does not have one entry per render vertex");

  std::string out;
  if (!options.mtllib.empty()) out.append("mtllib ").append(options.mtllib).push_back('\n');
  for (const glm::vec3& p : positions) append_line(out, "v", p);
  if (write_uvs)
    for (const glm::vec2& uv : mesh.vertex_uvs) append_line(out, "vt", uv);
  if (write_normals)
    for (const glm::vec3& n : normals) append_line(out, "vn", n);

  std::size_t corner = 0, triangle = 0, next_submesh = 0;
  const Submesh* current = nullptr;
  for (const std::uint32_t size : mesh.face_sizes) {
    while (next_submesh < mesh.submeshes.size() && mesh.submeshes[next_submesh].first_triangle <= triangle) {
      const Submesh& submesh = mesh.submeshes[next_submesh++];
      if (submesh.triangle_count == 0) continue;
      if (current ? submesh.object != current->object : !submesh.object.empty())
        out.append("o ").append(submesh.object).push_back('\n');
      if (current ? submesh.group != current->group : !submesh.group.empty())
        out.append("g ").append(submesh.group).push_back('\n');
      if (!options.mtllib.empty() && (current ? submesh.material != current->material : submesh.material >= 0)) {
        const bool named = submesh.material >= 0 && std::size_t(submesh.material) < mesh.materials.size();
        out.append("usemtl ").append(named ? mesh.materials[std::size_t(submesh.material)].name : "default");
        out.push_back('\n');
      }
      current = &submesh;
    }
    if (corner + size > mesh.face_corners.size())
      throw std::invalid_argument("format_obj: face_sizes needs more corners than face_corners holds");
    out.push_back('f');
    for (std::uint32_t i = 0; i < size; ++i) {
      const std::uint32_t vertex = mesh.face_corners[corner + i];
      if (vertex >= mesh.vertex_count() || mesh.vertex_point[vertex] >= mesh.point_count())
        throw std::invalid_argument("format_obj: face corner index out of range");
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

std::string material_libraries_for(const Mesh& mesh, const std::string& obj_path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path folder = fs::absolute(fs::path(obj_path), error).lexically_normal().parent_path();
  std::string out;
  for (const std::string& library : mesh.material_libraries) {
    const fs::path absolute = fs::absolute(library, error).lexically_normal();
    fs::path relative = absolute.lexically_relative(folder);
    if (relative.empty()) relative = absolute;  // another root: no relative path exists
    if (!out.empty()) out.push_back(' ');
    out.append(relative.generic_string());
  }
  return out;
}

std::string format_mtl(std::span<const Material> materials) {
  std::string out;
  for (const Material& material : materials) {
    out.append("newmtl ").append(material.name).push_back('\n');
    append_line(out, "Ka", material.ambient);
    append_line(out, "Kd", material.diffuse);
    append_line(out, "Ks", material.specular);
    out.append("d");
    append_number(out, material.opacity);
    out.append("\nNs");
    append_number(out, material.shininess);
    out.append("\nillum ").append(std::to_string(material.illum)).push_back('\n');
    if (!material.diffuse_map.empty()) out.append("map_Kd ").append(material.diffuse_map).push_back('\n');
    out.push_back('\n');
  }
  return out;
}

}  // namespace deform
