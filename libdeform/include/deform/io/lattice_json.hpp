#pragma once
// Lattice files of the CLI: the lattice JSON and vertex lists (docs/formats.md).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "deform/io/export.hpp"
#include "deform/runtime/lattice.hpp"

namespace deform {

// Vertex list file (docs/formats.md): 0-based point indices (the OBJ's `v` lines in order, as in .skw) separated by
// white space, `#` comments to the end of the line. Each index must be < point_count and appear once. Throws
// deform::Error with file, line and element.
DEFORM_IO_API std::vector<std::uint32_t> parse_vertex_list(std::string_view text, std::size_t point_count,
                                                           const std::string& name = "<memory>");
DEFORM_IO_API std::vector<std::uint32_t> read_vertex_list(const std::string& path, std::size_t point_count);

// --- the CLI's lattice JSON (docs/cli.md, docs/formats.md) ---

// {"origin": [x,y,z], "size": [sx,sy,sz], "degree": [l,m,n], "displacements": [{"index": [i,j,k], "offset":
// [dx,dy,dz]}, ...], "vertices": [...]}: an axis-aligned Bézier lattice with the displacements applied.
struct LatticeDocument {
  BezierLattice lattice{LatticeFrame{}};
  std::size_t displacement_count = 0;
  bool has_vertices = false;            // "vertices" was given
  std::vector<std::uint32_t> vertices;  // its point indices (0-based), each < point_count, no repeats
};
// Throws deform::Error naming `name` and the key (e.g. "key 'displacements[2].index'") for malformed JSON, a missing
// or unknown key, a wrong-length array, a non-finite number, a size ≤ 0, a degree outside [1, max_bezier_degree], an
// index out of range or repeated, or a vertex index ≥ point_count or repeated.
DEFORM_IO_API LatticeDocument parse_lattice_json(std::string_view json, std::size_t point_count,
                                                 const std::string& name = "<memory>");
DEFORM_IO_API LatticeDocument read_lattice_json(const std::string& path, std::size_t point_count);

}  // namespace deform
