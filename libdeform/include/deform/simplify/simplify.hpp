#pragma once
// A model's mesh simplified for a distant level of detail (docs/skinning.md, "Levels of detail"): fewer triangles and
// points, the same skin. Offline (bind time): allocates, throws deform::Error. Optional layer, built where Debian's
// meshoptimizer is found (libmeshoptimizer-dev).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "deform/offline/topology.hpp"
#include "deform/runtime/model.hpp"
#include "deform/simplify/export.hpp"

namespace deform {

struct SimplifySettings {
  // The share of the triangles to keep, in (0, 1]. A target: the simplifier stops short of it where `max_error` or
  // the mesh's borders and seams forbid more.
  float triangle_ratio = 0.25f;
  // The largest distance a collapse may move the surface, as a fraction of the mesh's largest extent, in [0, 1].
  float max_error = 0.01f;
};

struct SimplifiedModel {
  // The simplified model: its points are a subset of the input's, at the same places, with the same skin weights and
  // morph deltas; its render vertices a subset, with the same normals and UVs; the skeleton unchanged. Triangles stay
  // in their submeshes (materials), each face a triangle.
  Model model;
  std::vector<std::uint32_t> source_point;   // per point of `model`: the input's point it is
  std::vector<std::uint32_t> source_vertex;  // per render vertex of `model`: the input's render vertex it is
  float error = 0.0f;  // the largest surface error the simplifier reports, a fraction of the largest extent
};

// Simplifies `model`'s mesh submesh by submesh (meshoptimizer's edge collapses with quadric errors). UV and normal
// seams stay closed: the render vertices of one point collapse together, along the seam only, so the result keeps
// each corner's own UV. Submesh borders and the mesh's open borders are kept where they are, so that materials and
// holes keep their outlines. Throws deform::Error (kind argument, element "triangle_ratio" or "max_error") for a
// setting out of range, and ("mesh") for a mesh without triangles or whose triangles or points are out of range.
DEFORM_SIMPLIFY_API SimplifiedModel simplify_model(const Model& model, const SimplifySettings& settings = {});

// One level of detail's mesh (simplify_levels): what a Character level deforms (LevelOptions::points) and what the
// renderer draws, both in the numbering of the model it was made from; level 0, the whole mesh, has none.
struct MeshLevel {
  // The level's points, as the model's point ids. Nested: the next (coarser) level's points come first, in the same
  // order, so that after order_points_first(model, levels.front().points) every level's points are a prefix.
  std::vector<std::uint32_t> points;
  // Its triangles as the model's render vertex ids (3 each), grouped by submesh as `submeshes` says (materials kept).
  // Every corner's point is one of `points`.
  std::vector<std::uint32_t> triangles;
  std::vector<Submesh> submeshes;
  // Simplification error, a fraction of the mesh's largest extent: the errors of the simplifications that made this
  // level (each from the level before it) added, a bound on how far its surface lies from the whole mesh's.
  float error = 0.0f;
};
// Meshes for levels 1, 2, ... of a Character: level l keeps levels[l - 1].triangle_ratio of the whole mesh's triangles
// (ratios decreasing: each level is simplify_model of the level before it, so the levels are nested) within its
// max_error. Throws deform::Error as simplify_model does, and (kind argument, element "levels") for no levels or
// ratios that increase. Offline: allocates.
DEFORM_SIMPLIFY_API std::vector<MeshLevel> simplify_levels(const Model& model,
                                                           std::span<const SimplifySettings> levels);
// The levels in a renumbered model's numbering, after `order` = order_points_first(model, levels.front().points)
// (deform/offline/topology.hpp): then level l's points are 0, 1, ..., points.size() - 1 and its triangles name the
// renumbered render vertices.
DEFORM_SIMPLIFY_API void renumber_levels(std::vector<MeshLevel>& levels, const PointOrder& order);

}  // namespace deform
