#pragma once
// Mesh: flat arrays of points, render vertices and triangles, with materials; Wavefront OBJ/MTL read and write.
//
// Two levels of vertex, because OBJ has two:
//  - a *point* is one `v` line of the OBJ, in file order. Skin weights (.skw), lattice bindings and the CLI's output
//    are per point, and every deformer in libdeform deforms `positions` (one per point).
//  - a *render vertex* is a point split where its UV or normal differ between faces (what a GPU draws).
//    `vertex_point[r]` maps render vertex r back to its point, so per-point results reach the GPU by a gather and
//    every deformation can be reported per original vertex.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/export.hpp"

namespace deform {

// One MTL `newmtl`. Colours are linear RGB as written in the file; defaults are MTL's own.
struct Material {
  std::string name;
  glm::vec3 ambient{0.2f};    // Ka
  glm::vec3 diffuse{0.8f};    // Kd
  glm::vec3 specular{0.0f};   // Ks
  float opacity = 1.0f;       // d (or 1 - Tr)
  float shininess = 0.0f;     // Ns
  int illum = 2;              // illum
  std::string diffuse_map;    // map_Kd, resolved relative to the MTL file's folder; empty if none
};

// A run of triangles drawn with one material.
struct Submesh {
  std::uint32_t first_triangle = 0;
  std::uint32_t triangle_count = 0;
  std::int32_t material = -1;  // index into Mesh::materials, -1 = default material
  std::string object;          // last `o` name in effect ("" if none)
  std::string group;           // last `g` name in effect ("" if none)
};

struct Mesh {
  // --- points: one per OBJ `v`, in file order ---
  std::vector<glm::vec3> positions;

  // --- render vertices ---
  std::vector<std::uint32_t> vertex_point;  // render vertex -> point index (size = render vertex count)
  std::vector<glm::vec3> vertex_normals;    // per render vertex; from `vn`, or computed when the file has none
  std::vector<glm::vec2> vertex_uvs;        // per render vertex; empty when the file has no `vt` at all

  // --- triangles (3 render-vertex indices each), grouped by submesh ---
  std::vector<std::uint32_t> triangles;
  std::vector<Submesh> submeshes;
  std::vector<Material> materials;

  // --- the file's polygons, kept so that write_obj reproduces faces as they were (quads stay quads) ---
  std::vector<std::uint32_t> face_sizes;    // corners per face, in file order
  std::vector<std::uint32_t> face_corners;  // render vertex per corner, concatenated

  std::size_t point_count() const noexcept { return positions.size(); }
  std::size_t vertex_count() const noexcept { return vertex_point.size(); }
  std::size_t triangle_count() const noexcept { return triangles.size() / 3; }
};

// Non-fatal findings of a reader (a missing MTL or texture), one line each, with file and line.
struct Warnings {
  std::vector<std::string> messages;
};

// Reads an OBJ file and the MTL files it names. Supports `v` (extra w / colour components ignored), `vn`, `vt`,
// `f` in the forms v, v/vt, v//vn, v/vt/vn with negative (relative) indices, polygons (fan-triangulated), `o`, `g`,
// `s` (ignored), `mtllib`, `usemtl`; MTL `newmtl`, `Ka`, `Kd`, `Ks`, `d`, `Tr`, `Ns`, `illum`, `map_Kd`.
// A malformed line or an out-of-range index throws deform::Error with the file and line; a missing MTL, an unknown
// material or a missing texture is a warning. Normals missing from the file are computed (area-weighted).
DEFORM_API Mesh read_obj(const std::string& path, Warnings* warnings = nullptr);

// Parses OBJ text held in memory; `name` is used in messages, MTL files are resolved relative to `base_folder`.
DEFORM_API Mesh parse_obj(std::string_view text, const std::string& name = "<memory>",
                          const std::string& base_folder = ".", Warnings* warnings = nullptr);

// Parses MTL text; `name` for messages, texture paths resolved relative to `base_folder`.
DEFORM_API std::vector<Material> parse_mtl(std::string_view text, const std::string& name,
                                           const std::string& base_folder, Warnings* warnings = nullptr);

// Options for write_obj.
struct ObjWriteOptions {
  std::string mtllib;         // written as `mtllib` when non-empty (materials are then named by `usemtl`)
  bool write_normals = true;  // `vn` lines (one per render vertex) and v//vn face indices
  bool write_uvs = true;      // `vt` lines when the mesh has UVs
};

// Formats the mesh as OBJ text: one `v` per point (in order, from `positions`, which must have point_count()
// entries), then `vt`/`vn` per render vertex (normals from `normals` if not empty, else mesh.vertex_normals), then
// the faces as the file had them. Vertex i in means vertex i out.
DEFORM_API std::string format_obj(const Mesh& mesh, std::span<const glm::vec3> positions,
                                  std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// Writes format_obj() to `path` atomically. Throws deform::Error on failure.
DEFORM_API void write_obj(const std::string& path, const Mesh& mesh, std::span<const glm::vec3> positions,
                          std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// Formats the mesh's materials as MTL text (map_Kd written as given).
DEFORM_API std::string format_mtl(std::span<const Material> materials);

// Recomputes per-render-vertex normals for deformed point positions: each triangle's normal weighted by its corner
// angle, accumulated per *point* (so seams split only by UV stay smooth), normalised, gathered to render vertices.
// `scratch` must have point_count() entries. No allocation; safe to call every frame.
DEFORM_API void compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions,
                                       std::span<glm::vec3> scratch, std::span<glm::vec3> out_vertex_normals);

// Axis-aligned bounds of a set of points.
struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};
DEFORM_API Bounds compute_bounds(std::span<const glm::vec3> points);

}  // namespace deform
