#pragma once
// Vertex normals of a deformed mesh, per frame.
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

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
DEFORM_RUNTIME_API bool compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions,
                                       std::span<glm::vec3> scratch, std::span<glm::vec3> out_vertex_normals);

// compute_vertex_normals for one mesh topology, recomputed every frame: the triangles' points are looked up once at
// bind time and packed 16 triangles per block, so compute() is flat loops over 16 triangles at once (the
// widest copy the CPU runs, isa.hpp). Same weighting, degenerate rule, finiteness
// and error bound as compute_vertex_normals, with which it agrees to float rounding. Per frame on the built-in
// character (5,056 triangles): 32 µs with AVX-512, 68 µs without, 103 µs with compute_vertex_normals (AMD EPYC).
class DEFORM_RUNTIME_API VertexNormals {
 public:
  VertexNormals() = default;
  // Binds to `mesh`'s triangles and vertex_point (positions are not kept). Triangles with a repeated point are dropped
  // here (they are degenerate in every pose). Throws std::invalid_argument when a triangle or vertex_point index is
  // out of range or the triangle indices are not a multiple of 3. Allocates; O(triangles + render vertices).
  explicit VertexNormals(const Mesh& mesh);

  // Per frame: `positions` has point_count() entries (deformed points), `out_vertex_normals` vertex_count(); `isa`
  // picks the kernel copy (isa.hpp). Returns false, writing nothing, on a size mismatch or an unavailable `isa`. No allocation, no locks; O(triangles + render vertices). Uses the
  // object's own scratch, so one object serves one thread at a time.
  bool compute(std::span<const glm::vec3> positions, std::span<glm::vec3> out_vertex_normals,
               Isa isa = Isa::automatic);

  std::size_t point_count() const noexcept { return point_sums_.size(); }
  std::size_t vertex_count() const noexcept { return vertex_point_.size(); }
  // Triangles kept at bind time (those without a repeated point).
  std::size_t triangle_count() const noexcept { return triangle_count_; }

 private:
  std::size_t triangle_count_ = 0;
  std::vector<std::uint32_t> block_points_;  // 48 per block of 16 triangles: corner k of lane j at [16 k + j]
  std::vector<std::uint32_t> vertex_point_;  // render vertex -> point (a copy of Mesh::vertex_point)
  std::vector<glm::vec4> point_sums_;        // scratch, per point: weighted normal sum, then the unit normal (w = 0)
};

}  // namespace deform
