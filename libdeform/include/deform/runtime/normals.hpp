#pragma once
// Vertex normals of a deformed mesh, per frame: angle-weighted (Thürmer & Wüthrich 1998), accumulated per *point* (so
// seams split by UV or normal become smooth), normalised, copied to the point's render vertices.
//
// Per frame, VertexNormalsJob over a VertexNormalsBinding built once per mesh (bind_vertex_normals); for a one-off,
// compute_vertex_normals straight from a Mesh. Both give each point the sum, over the triangles at it, of its corner
// angle times the triangle's unit normal, then (0, 0, 0) where nothing was added or the contributions cancel
// (|sum| <= 1e-5), else the sum normalised. A triangle adds nothing when its cross product is zero (repeated or
// exactly collinear points) or NaN. The normals are always finite: a point of a triangle with an infinite coordinate
// may get (0, 0, 0). Corner angles come from a polynomial atan2 (src/runtime/simd/mesh_normals_kernel.hpp) within
// 5e-7 rad of the exact angle; a triangle's third corner, π minus the other two, within 1e-6. The two agree to float
// rounding.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

// One-shot vertex normals, one triangle at a time, each scattered into `scratch`. `positions` and `scratch` need
// mesh.point_count() entries, `out_vertex_normals` mesh.vertex_count(). Refuses, leaving the outputs unspecified, on a
// size mismatch ("positions: one per point", "scratch: one per point", "normals: one per render vertex") or a bad
// index ("triangle index count not a multiple of 3", "triangle vertex out of range", "vertex point out of range").
// No allocation; O(triangles + render vertices). For meshes read once (an OBJ without normals); per frame,
// VertexNormalsJob is faster and splits across threads.
DEFORM_RUNTIME_API Status compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions,
                                                 std::span<glm::vec3> scratch,
                                                 std::span<glm::vec3> out_vertex_normals) noexcept;

// A mesh's topology arranged for VertexNormalsJob (bind_vertex_normals). Read-only after binding; share it between
// threads and jobs freely. Triangles with a repeated point are dropped (degenerate in every pose).
struct DEFORM_RUNTIME_API VertexNormalsBinding {
  std::size_t point_count = 0;
  std::size_t vertex_count = 0;    // render vertices
  std::size_t triangle_count = 0;  // kept triangles; 3 corners each

  // The triangles, 3 entries each, ordered by their lowest-numbered point, which comes first in each (the mesh's
  // winding kept): triangle_points[3 t .. 3 t + 2]; triangle_corners, the corner index of each of those points in
  // this triangle. The triangles whose lowest point is p: [triangle_offsets[p], triangle_offsets[p + 1]).
  std::vector<std::uint32_t> triangle_points;
  std::vector<std::uint32_t> triangle_corners;
  std::vector<std::uint32_t> triangle_offsets;
  // The corners at point p: [corner_offsets[p], corner_offsets[p + 1]), in triangle order; corner c is in triangle
  // corner_triangle[c].
  std::vector<std::uint32_t> corner_offsets;
  std::vector<std::uint32_t> corner_triangle;
  // Render vertices of point p: point_vertices[vertex_offsets[p] .. vertex_offsets[p + 1]).
  std::vector<std::uint32_t> vertex_offsets;
  std::vector<std::uint32_t> point_vertices;

  std::size_t corner_count() const noexcept { return corner_triangle.size(); }
  // The size of VertexNormalsJob::scratch for this binding: one entry per point and one per corner.
  std::size_t scratch_size() const noexcept { return point_count + corner_count(); }
};

// Builds the binding of `mesh`'s triangles and vertex_point (its positions are not read). Throws deform::Error
// (Error::invalid_argument, element "mesh") when the triangle index count is not a multiple of 3, a triangle index or
// a vertex_point entry is out of range, or the mesh has 2³² corners, points or render vertices or more. Allocates;
// O(triangles + render vertices).
DEFORM_RUNTIME_API VertexNormalsBinding bind_vertex_normals(const Mesh& mesh);

// Per-frame vertex normals of a bound mesh (ozz-style job). The job's elements are the mesh's points; run(begin, end)
// computes the normals of points [begin, end) and writes each to the point's render vertices.
//
// The shape, chosen for speed, no races and the same bits however the points are split: a range computes each
// triangle with a corner in it once (its binding puts every triangle's lowest point first and orders the triangles by
// it, so those whose lowest point is in the range are a contiguous run; the few reaching in from below are found
// through the corners), always from the triangle's lowest point, so that a triangle's contributions (corner angle
// times unit normal) have the same bits in whichever range computes them; and each point adds its triangles'
// contributions in triangle order, those reaching in from below first (parked in their corners' slots of `scratch`
// until then), so that its sum has the same bits as in one run over all points. A range writes only its own points'
// and corners' slots of `scratch` and its own points' render vertices: disjoint ranges run on different threads with
// one shared scratch, no locks, no atomics (run_parallel in parallel.hpp). Work: on one thread, each triangle once (as
// a scatter over triangles would; a gather per point would compute each three times); split, the triangles spanning
// two ranges twice. Per frame on the built-in character (5,696 triangles) and a 200,000-triangle torus: normals/* in
// bench/normals_bench.cpp.
struct DEFORM_RUNTIME_API VertexNormalsJob {
  const VertexNormalsBinding* binding = nullptr;
  std::span<const glm::vec3> positions;  // deformed points: binding->point_count
  std::span<glm::vec3> normals;          // out: unit normals, binding->vertex_count render vertices
  std::span<glm::vec4> scratch;          // scratch_size() entries, overwritten
  Isa isa = Isa::automatic;              // the kernel copy: isa.hpp

  // run_parallel cuts ranges at multiples of 16 points, in chunks of at least 4096 points by default: below that a
  // thread wake-up costs more than it saves.
  static constexpr std::size_t split_multiple = 16;
  static constexpr std::size_t min_parallel_chunk = 4096;

  // The scratch the job needs: binding->scratch_size() (0 without a binding).
  std::size_t scratch_size() const noexcept { return binding ? binding->scratch_size() : 0; }

  // Ok when the job can run, else why not: a binding ("no binding") whose arrays have the sizes its counts say
  // ("binding arrays differ in size"), whose offsets never decrease and end at the array sizes ("binding offsets
  // invalid"), whose triangles are sorted by their lowest point and name points and corners consistently ("binding
  // triangle invalid"), whose render vertices exist ("binding vertex out of range"); `positions` one per point
  // ("positions: one per point"), `normals` one per render vertex ("normals: one per render vertex"), `scratch`
  // scratch_size() entries ("scratch: one per point and corner"), the ISA available ("instruction set not
  // available"). Cost: O(corners + render vertices); the binding is read-only, so once per binding and job layout.
  Status validate() const noexcept;

  // The number of points (0 without a binding).
  std::size_t count() const noexcept { return binding ? binding->point_count : 0; }

  // Computes the normals of every point — or of points [begin, end) — on this thread. Checks only what is O(1) (the
  // sizes above, the ISA, the range: "range outside the job") and refuses, writing nothing, when that fails; the
  // binding's contents are validate()'s to check. A point's normal does not depend on the range it is run in. No
  // allocation, no locks. O(corners + render vertices) of the range.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
};

// A gather done in place: after it, values[v] = (values before)[map[v]] for every v < map.size(), where every map
// entry is < sources <= map.size() — one array holding first one value per source (e.g. per point) and then, once
// gathered, one per destination (e.g. per render vertex), plus one entry of scratch at its end. What it saves over a
// gather into a second array is that array: for a crowd of characters, each one's per-point normals (Character,
// transported normals) need no memory of their own. plan_in_place_gather orders the moves once (a source is read by
// all its destinations before its own slot is overwritten, the lowest ready destination first; each cycle of the
// map goes through the scratch entry), InPlaceGatherJob replays them.
struct DEFORM_RUNTIME_API InPlaceGather {
  std::size_t sources = 0;
  std::size_t destinations = 0;  // map.size(); the array has one entry more, the scratch, at index destinations
  // Move k copies slot moves[2k + 1] into slot moves[2k], in order; entries with map[v] == v make no move.
  std::vector<std::uint32_t> moves;
};

// The plan for `map` over `sources` values. Throws deform::Error (Error::invalid_argument, element "map") when
// sources > map.size(), an entry is >= sources, or map.size() >= 2³² - 1. Allocates; O(map.size() · log + sources).
DEFORM_RUNTIME_API InPlaceGather plan_in_place_gather(std::span<const std::uint32_t> map, std::size_t sources);

// Per frame: replays a plan on `values` (plan->destinations + 1 entries: the first plan->sources hold the sources,
// the last is scratch, left unspecified).
struct DEFORM_RUNTIME_API InPlaceGatherJob {
  const InPlaceGather* plan = nullptr;
  std::span<glm::vec3> values;

  // Ok when the job can run, else why not: a plan ("no plan"), `values` one per destination and the scratch entry
  // ("values: one per destination and one more"). The plan's moves are plan_in_place_gather's to be right. O(1).
  Status validate() const noexcept;
  // Gathers; refuses, writing nothing, what validate() refuses. No allocation, no locks; O(destinations).
  Status run() const noexcept;
};

}  // namespace deform
