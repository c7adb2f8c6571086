#pragma once
// Mesh topology built once at bind time: point adjacency and boundary edges.
#include <cstdint>
#include <span>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

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
// Throws deform::Error (kind argument) when a triangle or vertex_point index is out of range.
DEFORM_OFFLINE_API PointTopology build_point_topology(const Mesh& mesh);

}  // namespace deform
