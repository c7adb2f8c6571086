#pragma once
// Mesh topology built once at bind time: point adjacency and boundary edges; the render vertices' order.
#include <cstdint>
#include <span>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"

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

// What order_points_first did: the new index of each previous point and of each previous render vertex.
struct PointOrder {
  std::vector<std::uint32_t> point;
  std::vector<std::uint32_t> vertex;
};
// Renumbers a model's points so that `first` (previous point ids, each once, in any order) become points 0, 1, ... in
// that order and the others follow in their previous order; positions, skin weights (one per point, or none), morph
// targets (their points renumbered, kept ascending with their deltas) and vertex_point follow, and the render vertices
// are then ordered by order_vertices_by_point. The model draws and skins the same. Why: a Character level of detail
// that deforms a simplified mesh's points (Character::LevelOptions::points, from simplify_model's source_point) reads
// and writes a few scattered points of every cache line when they are spread over the mesh, and whole lines when they
// come first: list the coarsest level's points, then the next's (nested levels: simplify the simplified model
// further), and each level is a prefix (docs/skinning.md, "Levels of detail"). Per-point data made before (a rig's
// corrective shapes, simplified models' source_point) is renumbered through `point` by the caller. Throws
// deform::Error (kind argument, element "first") for an id out of range or listed twice, or what
// order_vertices_by_point throws; the model is unchanged then. Allocates; O(points + render vertices + corners + morph
// entries).
DEFORM_OFFLINE_API PointOrder order_points_first(Model& model, std::span<const std::uint32_t> first);

}  // namespace deform
