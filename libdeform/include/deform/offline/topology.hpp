#pragma once
// Mesh topology built once at bind time: point adjacency and boundary edges; the render vertices' order.
#include <cstdint>
#include <span>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

// Point adjacency (edges taken in point space, so UV/normal seams are not boundaries): each point's one-ring and the
// mesh's boundary edges. Built once at bind time for smoothing and seam checks; O(T log T) for T triangles.
struct PointTopology {
  std::vector<std::uint32_t>
      neighbour_offsets;                      // point_count() + 1 entries; neighbours of p: [offsets[p], offsets[p+1])
  std::vector<std::uint32_t> neighbours;      // each point's one-ring, ascending, no duplicates, never p itself
  std::vector<std::uint32_t> boundary_edges;  // pairs (a, b), a < b, of edges used by exactly one triangle, sorted

  // The points sharing a triangle edge with `point` (empty for an isolated point).
  std::span<const std::uint32_t> point_neighbours(std::uint32_t point) const noexcept {
    return {neighbours.data() + neighbour_offsets[point], neighbours.data() + neighbour_offsets[point + 1]};
  }
  std::size_t boundary_edge_count() const noexcept { return boundary_edges.size() / 2; }
};

// Builds the point topology of a mesh's triangles. Triangles with a repeated point contribute only their real edges.
// Throws deform::Error (kind argument) when a triangle or vertex_point index is out of range.
DEFORM_OFFLINE_API PointTopology build_point_topology(const Mesh& mesh);

// Renumbers the render vertices so that render vertex p belongs to point p — the first of point p's render vertices
// in the previous order — for every point some render vertex uses; the further render vertices (a point's copies
// along UV or normal seams, in their previous order) fill the slots of unused points, then follow. triangles,
// face_corners, vertex_point, vertex_normals and vertex_uvs follow the renumbering, so the mesh draws the same;
// points and everything indexed by point (weights, morph targets, .skw files) are untouched. Returns the new index of
// each previous render vertex. Why: a per-point array gathered into render vertices in place (InPlaceGatherJob, as
// Character's transported normals are) then costs one move per seam copy instead of about one per render vertex —
// on the built-in character, whose order this is, 218 moves instead of 3,068. Throws deform::Error (kind argument,
// element "mesh") when a vertex_point entry, triangle or face corner is out of range, or an optional per-vertex
// array is neither empty nor one per render vertex; the mesh is unchanged then. O(render vertices + corners).
DEFORM_OFFLINE_API std::vector<std::uint32_t> order_vertices_by_point(Mesh& mesh);

}  // namespace deform
