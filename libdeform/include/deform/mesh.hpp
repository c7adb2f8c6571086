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
#include <string_view>
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
  std::vector<glm::vec3> vertex_normals;    // per render vertex; from `vn` as written, or computed where a corner has none
  std::vector<glm::vec2> vertex_uvs;        // per render vertex ((0, 0) where a corner has no `vt`); empty when no
                                            // face corner uses a `vt`

  // --- triangles (3 render-vertex indices each), grouped by submesh ---
  std::vector<std::uint32_t> triangles;
  std::vector<Submesh> submeshes;
  std::vector<Material> materials;
  // The MTL files the OBJ's `mtllib` lines named and read_obj read, as it opened them (resolved against the OBJ's
  // folder), in file order. write_obj does not use them by itself: see material_libraries_for.
  std::vector<std::string> material_libraries;

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
// `s` (ignored), `mtllib`, `usemtl`, `\` line continuation; MTL `newmtl`, `Ka`, `Kd`, `Ks`, `d`, `Tr`, `Ns`, `illum`,
// `map_Kd`. Render vertices are the distinct (v, vt, vn) triples, numbered in order of first use.
// A malformed line or an out-of-range index throws deform::Error with the file and line; a missing MTL, an unknown
// material, a missing texture or an unsupported statement (`l`, `p`, curves...) is a warning. Normals missing from
// the file are computed as compute_vertex_normals does. Linear time and memory in the file size.
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
// the faces as the file had them, with `o`/`g`/`usemtl` where the submesh changes. Vertex i in means vertex i out;
// numbers are written in the shortest form that reads back to the same float. Throws std::invalid_argument when a
// span has the wrong size.
DEFORM_API std::string format_obj(const Mesh& mesh, std::span<const glm::vec3> positions,
                                  std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// Writes format_obj() to `path` atomically. Throws deform::Error on failure.
DEFORM_API void write_obj(const std::string& path, const Mesh& mesh, std::span<const glm::vec3> positions,
                          std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// The ObjWriteOptions::mtllib value with which an OBJ written to `obj_path` uses the MTL files `mesh` was read with:
// each of mesh.material_libraries relative to obj_path's folder (absolute when no relative path exists), joined by
// spaces. Empty when the mesh has none (a mesh built in code, or an OBJ without `mtllib`).
DEFORM_API std::string material_libraries_for(const Mesh& mesh, const std::string& obj_path);
// Formats the mesh's materials as MTL text (map_Kd written as given).
DEFORM_API std::string format_mtl(std::span<const Material> materials);

// Recomputes per-render-vertex normals for deformed point positions: each triangle's unit normal weighted by its
// corner angle (Thürmer & Wüthrich 1998), accumulated per *point* (so seams split by UV or normal become smooth),
// normalised, gathered to render vertices; (0, 0, 0) for a point no non-degenerate triangle touches or whose
// contributions cancel (|sum| <= 1e-5). A triangle is degenerate, and adds nothing, when its cross product is zero
// (repeated or exactly collinear points) or NaN. The normals are always finite: a point of a triangle with an
// infinite coordinate may get (0, 0, 0). Corner angles come from a polynomial atan2 (src/mesh_normals_kernel.hpp)
// within 5e-7 rad of the exact angle; the third corner of a triangle, π minus the other two, within 1e-6.
// `positions` and `scratch` need point_count() entries, `out_vertex_normals` vertex_count(). Returns false (and
// leaves the outputs unspecified) on a size mismatch or an index out of range. No allocation; O(triangles), one
// triangle at a time: per frame, VertexNormals gives the same normals faster.
DEFORM_API bool compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions,
                                       std::span<glm::vec3> scratch, std::span<glm::vec3> out_vertex_normals);

// compute_vertex_normals for one mesh topology, recomputed every frame: the triangles' points are looked up once at
// bind time and packed 16 triangles per block, so compute() is flat loops over 16 triangles at once (AVX-512 where
// the CPU has it, chosen at run time, else the same code 4 lanes wide). Same weighting, degenerate rule, finiteness
// and error bound as compute_vertex_normals, with which it agrees to float rounding. Per frame on the built-in
// character (5,056 triangles): 32 µs with AVX-512, 68 µs without, 103 µs with compute_vertex_normals (AMD EPYC).
class DEFORM_API VertexNormals {
 public:
  // Which code compute() runs: `automatic` is AVX-512 where the CPU has it, `portable` the baseline copy everywhere
  // (tests compare the two; the benchmark measures both).
  enum class Kernel : std::uint8_t { automatic, portable };

  VertexNormals() = default;
  // Binds to `mesh`'s triangles and vertex_point (positions are not kept). Triangles with a repeated point are dropped
  // here (they are degenerate in every pose). Throws std::invalid_argument when a triangle or vertex_point index is
  // out of range or the triangle indices are not a multiple of 3. Allocates; O(triangles + render vertices).
  explicit VertexNormals(const Mesh& mesh);

  // Per frame: `positions` has point_count() entries (deformed points), `out_vertex_normals` vertex_count(). Returns
  // false, writing nothing, on a size mismatch. No allocation, no locks; O(triangles + render vertices). Uses the
  // object's own scratch, so one object serves one thread at a time.
  bool compute(std::span<const glm::vec3> positions, std::span<glm::vec3> out_vertex_normals,
               Kernel kernel = Kernel::automatic);

  std::size_t point_count() const noexcept { return point_sums_.size(); }
  std::size_t vertex_count() const noexcept { return vertex_point_.size(); }
  // Triangles kept at bind time (those without a repeated point).
  std::size_t triangle_count() const noexcept { return triangle_count_; }
  // True when Kernel::automatic runs the AVX-512 code on this CPU.
  static bool has_avx512() noexcept;

 private:
  std::size_t triangle_count_ = 0;
  std::vector<std::uint32_t> block_points_;  // 48 per block of 16 triangles: corner k of lane j at [16 k + j]
  std::vector<std::uint32_t> vertex_point_;  // render vertex -> point (a copy of Mesh::vertex_point)
  std::vector<glm::vec4> point_sums_;        // scratch, per point: weighted normal sum, then the unit normal (w = 0)
};

// Axis-aligned bounds of a set of points; min = max = (0, 0, 0) for no points.
struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};
DEFORM_API Bounds compute_bounds(std::span<const glm::vec3> points);

// Point adjacency (edges taken in point space, so UV/normal seams are not boundaries): each point's one-ring and the
// mesh's boundary edges. Built once at bind time for smoothing and seam checks; O(T log T) for T triangles.
struct PointTopology {
  std::vector<std::uint32_t> neighbour_offsets;  // point_count() + 1 entries; neighbours of p: [offsets[p], offsets[p+1])
  std::vector<std::uint32_t> neighbours;         // each point's one-ring, ascending, no duplicates, never p itself
  std::vector<std::uint32_t> boundary_edges;     // pairs (a, b), a < b, of edges used by exactly one triangle, sorted

  // The points sharing a triangle edge with `point` (empty for an isolated point).
  std::span<const std::uint32_t> point_neighbours(std::uint32_t point) const noexcept {
    return {neighbours.data() + neighbour_offsets[point], neighbours.data() + neighbour_offsets[point + 1]};
  }
  std::size_t boundary_edge_count() const noexcept { return boundary_edges.size() / 2; }
};

// Builds the point topology of a mesh's triangles. Triangles with a repeated point contribute only their real edges.
// Throws std::invalid_argument when a triangle or vertex_point index is out of range.
DEFORM_API PointTopology build_point_topology(const Mesh& mesh);

}  // namespace deform
