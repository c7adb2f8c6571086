// simplify_model (deform/simplify/simplify.hpp): meshoptimizer's simplifier over the render vertices, then the kept
// render vertices and points gathered with their attributes, weights and morph deltas.
#include "deform/simplify/simplify.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "deform/runtime/error.hpp"

namespace deform {
namespace {

constexpr std::uint32_t unused = std::numeric_limits<std::uint32_t>::max();

void check(const Model& model, const SimplifySettings& settings) {
  if (!(settings.triangle_ratio > 0.0f && settings.triangle_ratio <= 1.0f))
    throw Error::invalid_argument("triangle_ratio", "must be within (0, 1]");
  if (!(settings.max_error >= 0.0f && settings.max_error <= 1.0f))
    throw Error::invalid_argument("max_error", "must be within [0, 1]");
  const Mesh& mesh = model.mesh;
  if (mesh.triangles.empty() || mesh.triangles.size() % 3 != 0)
    throw Error::invalid_argument("mesh", "has no triangles, or a partial one");
  for (const std::uint32_t v : mesh.triangles)
    if (v >= mesh.vertex_count())
      throw Error::invalid_argument("mesh", "a triangle names a render vertex out of range");
  for (const std::uint32_t p : mesh.vertex_point)
    if (p >= mesh.point_count()) throw Error::invalid_argument("mesh", "a render vertex names a point out of range");
  if (model.weights.size() != mesh.point_count() && model.weights.size() != 0)
    throw Error::invalid_argument("mesh", "skin weights are not one per point");
  for (const Submesh& s : mesh.submeshes)
    if (std::size_t(s.first_triangle) + s.triangle_count > mesh.triangle_count())
      throw Error::invalid_argument("mesh", "a submesh runs past the triangles");
}

// The skin weights of the kept points, in their new order (sources[i]: the input point of new point i).
SkinWeights kept_weights(const SkinWeights& in, const std::vector<std::uint32_t>& sources) {
  SkinWeights out;
  if (in.size() == 0) return out;
  out.bones.reserve(sources.size());
  out.weights.reserve(sources.size());
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const std::uint32_t p = sources[i];
    out.bones.push_back(in.bones[p]);
    out.weights.push_back(in.weights[p]);
    if (!in.has_extra()) continue;
    const auto it = std::lower_bound(in.extra_points.begin(), in.extra_points.end(), p);
    if (it == in.extra_points.end() || *it != p) continue;
    const auto j = std::size_t(it - in.extra_points.begin());
    if (out.extra_offsets.empty()) out.extra_offsets.push_back(0);
    out.extra_points.push_back(std::uint32_t(i));
    for (std::uint32_t e = in.extra_offsets[j]; e < in.extra_offsets[j + 1]; ++e) {
      out.extra_bones.push_back(in.extra_bones[e]);
      out.extra_weights.push_back(in.extra_weights[e]);
    }
    out.extra_offsets.push_back(std::uint32_t(out.extra_bones.size()));
  }
  return out;
}

// A morph target's entries on kept points, renumbered (new_point: input point -> new point or `unused`).
MorphTarget kept_target(const MorphTarget& in, const std::vector<std::uint32_t>& new_point) {
  MorphTarget out = in;
  out.points.clear(), out.position_deltas.clear(), out.normal_deltas.clear();
  std::vector<std::pair<std::uint32_t, std::size_t>> kept;  // (new point, entry)
  for (std::size_t e = 0; e < in.points.size(); ++e)
    if (const std::uint32_t to = new_point[in.points[e]]; to != unused) kept.emplace_back(to, e);
  std::sort(kept.begin(), kept.end());
  for (const auto& [to, e] : kept) {
    out.points.push_back(to);
    out.position_deltas.push_back(in.position_deltas[e]);
    if (!in.normal_deltas.empty()) out.normal_deltas.push_back(in.normal_deltas[e]);
  }
  return out;
}

}  // namespace

SimplifiedModel simplify_model(const Model& model, const SimplifySettings& settings) {
  check(model, settings);
  const Mesh& in = model.mesh;
  // Each render vertex at its point: vertices of one point are one position, which is how meshoptimizer finds seams.
  std::vector<glm::vec3> at(in.vertex_count());
  for (std::size_t r = 0; r < at.size(); ++r) at[r] = in.positions[in.vertex_point[r]];
  std::vector<Submesh> submeshes = in.submeshes;
  if (submeshes.empty()) submeshes.push_back({0, std::uint32_t(in.triangle_count()), -1});

  SimplifiedModel result;
  std::vector<std::uint32_t> triangles;  // the input's render vertices, submesh after submesh
  std::vector<Submesh> out_submeshes;
  std::vector<std::uint32_t> scratch;
  for (const Submesh& s : submeshes) {
    const std::size_t count = std::size_t(s.triangle_count) * 3;
    const std::uint32_t* indices = in.triangles.data() + std::size_t(s.first_triangle) * 3;
    const auto target = std::size_t(std::max(1.0, std::round(double(s.triangle_count) * settings.triangle_ratio))) * 3;
    scratch.resize(count);
    float error = 0.0f;
    // Borders locked: a submesh's outline is its material's edge (or a hole), which the neighbours share.
    const std::size_t kept = meshopt_simplify(scratch.data(), indices, count, &at[0].x, at.size(), sizeof(glm::vec3),
                                              target, settings.max_error, meshopt_SimplifyLockBorder, &error);
    result.error = std::max(result.error, error);
    out_submeshes.push_back({std::uint32_t(triangles.size() / 3), std::uint32_t(kept / 3), s.material});
    triangles.insert(triangles.end(), scratch.begin(), scratch.begin() + std::ptrdiff_t(kept));
  }

  // The kept render vertices and points, in the order the triangles first use them.
  std::vector<std::uint32_t> new_vertex(in.vertex_count(), unused), new_point(in.point_count(), unused);
  Mesh& out = result.model.mesh;
  for (std::uint32_t& v : triangles) {
    if (new_vertex[v] == unused) {
      const std::uint32_t p = in.vertex_point[v];
      if (new_point[p] == unused) {
        new_point[p] = std::uint32_t(result.source_point.size());
        result.source_point.push_back(p);
        out.positions.push_back(in.positions[p]);
      }
      new_vertex[v] = std::uint32_t(result.source_vertex.size());
      result.source_vertex.push_back(v);
      out.vertex_point.push_back(new_point[p]);
      if (!in.vertex_normals.empty()) out.vertex_normals.push_back(in.vertex_normals[v]);
      if (!in.vertex_uvs.empty()) out.vertex_uvs.push_back(in.vertex_uvs[v]);
    }
    v = new_vertex[v];
  }
  out.triangles = std::move(triangles);
  out.submeshes = std::move(out_submeshes);
  out.materials = in.materials;
  out.face_sizes.assign(out.triangles.size() / 3, 3);
  out.face_corners = out.triangles;

  result.model.name = model.name;
  result.model.skeleton = model.skeleton;
  result.model.weights = kept_weights(model.weights, result.source_point);
  for (const MorphTarget& target : model.morph_targets)
    result.model.morph_targets.push_back(kept_target(target, new_point));
  return result;
}

std::vector<MeshLevel> simplify_levels(const Model& model, std::span<const SimplifySettings> levels) {
  if (levels.empty()) throw Error::invalid_argument("levels", "no level to make");
  for (std::size_t l = 1; l < levels.size(); ++l)
    if (levels[l].triangle_ratio > levels[l - 1].triangle_ratio)
      throw Error::invalid_argument(
          "levels", "level " + std::to_string(l + 1) + " keeps more triangles than level " + std::to_string(l));
  // Each level from the one before: `chain` maps the current model's points and render vertices to the input's.
  std::vector<SimplifiedModel> made;
  made.reserve(levels.size());
  std::vector<MeshLevel> out(levels.size());
  float ratio = 1.0f, error = 0.0f;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    SimplifySettings step = levels[l];
    if (l > 0) step.triangle_ratio = std::min(1.0f, levels[l].triangle_ratio / ratio);  // of the level before
    made.push_back(simplify_model(l == 0 ? model : made.back().model, step));
    if (l > 0) {  // back to the input's numbering
      const SimplifiedModel& before = made[made.size() - 2];
      for (std::uint32_t& p : made.back().source_point) p = before.source_point[p];
      for (std::uint32_t& v : made.back().source_vertex) v = before.source_vertex[v];
    }
    ratio = levels[l].triangle_ratio;
    error += made.back().error;
    MeshLevel& level = out[l];
    level.error = error;
    level.submeshes = made.back().model.mesh.submeshes;
    level.triangles = made.back().model.mesh.triangles;
    for (std::uint32_t& v : level.triangles) v = made.back().source_vertex[v];
  }
  // Points: the coarsest level's, then each finer level's others (nested: a level's points are all its finer
  // neighbour's), so that every level's list is a prefix of the finer ones'.
  std::vector<char> listed(model.mesh.point_count(), 0);
  std::vector<std::uint32_t> order;
  for (std::size_t l = levels.size(); l-- > 0;) {
    for (const std::uint32_t p : made[l].source_point)
      if (!listed[p]) listed[p] = 1, order.push_back(p);
    out[l].points.assign(order.begin(), order.begin() + std::ptrdiff_t(made[l].source_point.size()));
  }
  return out;
}

void renumber_levels(std::vector<MeshLevel>& levels, const PointOrder& order) {
  for (MeshLevel& level : levels) {
    for (std::uint32_t& p : level.points) p = order.point[p];
    for (std::uint32_t& v : level.triangles) v = order.vertex[v];
  }
}

}  // namespace deform
