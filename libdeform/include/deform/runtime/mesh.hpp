#pragma once
// Mesh: flat arrays of points, render vertices and triangles, with materials: geometry only, what a frame needs.
// io/obj.hpp reads and writes them as Wavefront OBJ/MTL (a file's `o`/`g` names and MTL files are its ObjNames,
// kept beside the Mesh); runtime/normals.hpp recomputes their normals per frame.
//
// Two levels of vertex, because OBJ has two:
//  - a *point* is one `v` line of the OBJ, in file order. Skin weights (.skw), lattice bindings and the CLI's output
//    are per point, and every deformer in libdeform deforms `positions` (one per point).
//  - a *render vertex* is a point split where its UV or normal differ between faces (what a GPU draws).
//    `vertex_point[r]` maps render vertex r back to its point, so per-point results reach the GPU by a gather and
//    every deformation can be reported per original vertex.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/export.hpp"

namespace deform {

// One MTL `newmtl`. Colours are linear RGB as written in the file; defaults are MTL's own.
struct Material {
  std::string name;
  glm::vec3 ambient{0.2f};   // Ka
  glm::vec3 diffuse{0.8f};   // Kd
  glm::vec3 specular{0.0f};  // Ks
  float opacity = 1.0f;      // d (or 1 - Tr)
  float shininess = 0.0f;    // Ns
  int illum = 2;             // illum
  std::string diffuse_map;   // map_Kd, resolved relative to the MTL file's folder; empty if none
  // An embedded texture's encoded image (PNG or JPEG bytes, as a glTF/GLB file holds it), when the texture lives
  // inside the model file rather than beside it; diffuse_map is then empty. Shared, so that copies of a Model (one
  // per Character instance) do not copy the image. Null if none.
  std::shared_ptr<const std::vector<std::uint8_t>> diffuse_image;
};

// A run of triangles drawn with one material.
struct Submesh {
  std::uint32_t first_triangle = 0;
  std::uint32_t triangle_count = 0;
  std::int32_t material = -1;  // index into Mesh::materials, -1 = default material
};

struct Mesh {
  // --- points: one per OBJ `v`, in file order ---
  std::vector<glm::vec3> positions;

  // --- render vertices ---
  std::vector<std::uint32_t> vertex_point;  // render vertex -> point index (size = render vertex count)
  std::vector<glm::vec3>
      vertex_normals;                 // per render vertex; from `vn` as written, or computed where a corner has none
  std::vector<glm::vec2> vertex_uvs;  // per render vertex ((0, 0) where a corner has no `vt`); empty when no
                                      // face corner uses a `vt`

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
// Axis-aligned bounds of a set of points; min = max = (0, 0, 0) for no points.
struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};
DEFORM_RUNTIME_API Bounds compute_bounds(std::span<const glm::vec3> points);

}  // namespace deform
